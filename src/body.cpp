// The compiled copy of the definitions in s2kf/body/ (core/compilation_mode.hpp).
#include <s2kf/body/body_model.hxx>
#include <s2kf/body/bounded_joints.hxx>
#include <s2kf/body/forward_kinematics.hxx>
#include <s2kf/body/marker_measurement_model.hxx>
#include <s2kf/body/marker_set.hxx>
#include <s2kf/body/marker_set_labels.hxx>
#include <s2kf/body/marker_set_mapping.hxx>
#include <s2kf/body/pose.hxx>
