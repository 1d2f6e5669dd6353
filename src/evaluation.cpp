// The compiled copy of the definitions in s2kf/evaluation/ (core/compilation_mode.hpp).
#include <s2kf/evaluation/evaluation.hxx>
#include <s2kf/evaluation/hidden_time_error.hxx>
#include <s2kf/evaluation/identifiable_subject_reference.hxx>
#include <s2kf/evaluation/true_subject_reference.hxx>
#include <s2kf/evaluation/truth_metrics.hxx>
