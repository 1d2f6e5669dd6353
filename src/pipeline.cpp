// The compiled copy of the definitions in s2kf/pipeline/ (core/compilation_mode.hpp).
#include <s2kf/pipeline/session.hxx>
