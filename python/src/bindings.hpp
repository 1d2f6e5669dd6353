/// @file
/// The parts of the s2kf Python module, one per translation unit (compiled in parallel), each
/// adding its functions and classes to the module object.
#pragma once

#include <pybind11/pybind11.h>

namespace s2kf::python {

void bind_c3d(pybind11::module_& module);       // read_c3d, write_c3d
void bind_body(pybind11::module_& module);      // BodyModel, forward kinematics
void bind_filter(pybind11::module_& module);    // sample_set, Gaussian, SmartSamplingKalmanFilter
void bind_tracker(pybind11::module_& module);   // Tracker (streaming), FrameEstimate
void bind_track(pybind11::module_& module);     // track(), TrackResult
void bind_simulate(pybind11::module_& module);  // simulate(), Simulation

}  // namespace s2kf::python
