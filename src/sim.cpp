// The compiled copy of the definitions in s2kf/sim/ (core/compilation_mode.hpp).
#include <s2kf/sim/recording.hxx>
#include <s2kf/sim/subject.hxx>
