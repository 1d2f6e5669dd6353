/// @file
/// s2kf.track: the whole pipeline on a recording (next commit).
#include "bindings.hpp"
namespace s2kf::python {
void bind_track(pybind11::module_&) {}
}  // namespace s2kf::python
