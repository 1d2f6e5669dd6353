// The compiled copy of the definitions in s2kf/geometry/ (core/compilation_mode.hpp).
#include <s2kf/geometry/rigid_fit.hxx>
