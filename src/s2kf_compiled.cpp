// The one compiled copy of s2kf's heavy functions (the library s2kf_compiled, the CMake target
// s2kf::compiled). Code that links it is compiled with S2KF_COMPILED and sees only their
// declarations; here every definition is emitted once (include/s2kf/core/compilation_mode.hpp).
#define S2KF_BUILDING_COMPILED
#include <s2kf/s2kf.hpp>
