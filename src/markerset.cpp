// The compiled copy of the definitions in s2kf/markerset/ (core/compilation_mode.hpp).
#include <s2kf/markerset/marker_set_completion.hxx>
#include <s2kf/markerset/marker_set_inference.hxx>
#include <s2kf/markerset/rigid_clusters.hxx>
#include <s2kf/markerset/segment_rigidity.hxx>
