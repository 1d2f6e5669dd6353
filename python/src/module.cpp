/// @file
/// The s2kf Python module: numpy in and out, the GIL released while C++ runs, and C++ errors as
/// Python exceptions with the library's own one-sentence messages.
#include "bindings.hpp"
#include "data_directory.hpp"

#include <s2kf/app/user_error.hpp>
#include <s2kf/core/error.hpp>
#include <s2kf/io/c3d_error.hpp>

#include <pybind11/pybind11.h>

#include <exception>

namespace py = pybind11;

PYBIND11_MODULE(s2kf, module) {
  module.doc() =
      "Smart Sampling Kalman Filter whole-body motion tracking from optical motion capture "
      "(C3D in, root pose and 40 joint angles per frame out). See docs/python.md.";
  module.attr("__version__") = S2KF_VERSION;
  s2kf::python::use_installed_data();

  // pybind11 already maps std::invalid_argument (DimensionError included) to ValueError and
  // std::runtime_error to RuntimeError. A C3D file that cannot be opened or read is an OSError, as
  // Python's own file functions report it (read_c3d raises FileNotFoundError for a missing path).
  py::register_exception_translator([](std::exception_ptr error) {
    try {
      if (error) std::rethrow_exception(error);
    } catch (const s2kf::c3d::C3dError& e) {
      PyErr_SetString(PyExc_OSError, e.what());
    } catch (const s2kf::app::UserError& e) {  // what the user asked for: a bad value
      PyErr_SetString(PyExc_ValueError, e.what());
    }
  });

  s2kf::python::bind_c3d(module);
  s2kf::python::bind_body(module);
  s2kf::python::bind_filter(module);
  s2kf::python::bind_tracker(module);
  s2kf::python::bind_track(module);
  s2kf::python::bind_simulate(module);
}
