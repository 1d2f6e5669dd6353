/// @file
/// s2kf.read_c3d and s2kf.write_c3d: C3D files to and from (F, P, 3) float arrays in mm with NaN for
/// missing points. The reader's 3P x F column-major matrix is exactly a C-ordered (F, P, 3) array,
/// so points reach numpy without a copy, and written arrays are read in place frame by frame.
#include "bindings.hpp"
#include "numpy_bridge.hpp"

#include <s2kf/io/c3d_reader.hpp>
#include <s2kf/io/c3d_writer.hpp>

#include <pybind11/stl.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace s2kf::python {
namespace {

/// What read_c3d returns: the whole recording plus the reader's findings. Unpacks as
/// `labels, rate, points = s2kf.read_c3d(path)`.
struct C3dData {
  c3d::Recording recording;

  /// Point names as the tracker matches them; a computed output (POINT:ANGLES, ...) keeps its
  /// label as stored, and is flagged in model_output so tracking ignores it.
  std::vector<std::string> labels() const {
    std::vector<std::string> names;
    for (const c3d::PointLabel& label : recording.info.labels)
      names.push_back(label.model_output ? label.raw : label.name);
    return names;
  }
};

void raise_file_not_found(const std::string& path) {
  // The reader's own sentence, as a FileNotFoundError (an OSError) like open() raises.
  const std::string message =
      std::filesystem::path(path).filename().string() + ": cannot open the file for reading: no such file";
  PyErr_SetString(PyExc_FileNotFoundError, message.c_str());
  throw py::error_already_set();
}

C3dData read_c3d_file(const std::string& path) {
  if (!std::filesystem::exists(path)) raise_file_not_found(path);
  C3dData data;
  py::gil_scoped_release unlocked;
  data.recording = c3d::read_c3d(path);
  return data;
}

void write_c3d_file(const std::string& path, const std::vector<std::string>& labels, double rate,
                    const py::handle& points_value, const std::vector<std::string>& descriptions) {
  const DoubleArray points = as_double_array(points_value, "points");
  const auto point_count = static_cast<py::ssize_t>(labels.size());
  require_shape(points, {-1, point_count, 3}, "points",
                "(F, P, 3) with P = " + std::to_string(point_count) + " labels");
  if (!(rate > 0) || !std::isfinite(rate))
    throw py::value_error("the frame rate must be a positive number of Hz, got " + std::to_string(rate));
  if (!descriptions.empty() && descriptions.size() != labels.size())
    throw py::value_error(std::to_string(descriptions.size()) + " descriptions for " +
                          std::to_string(labels.size()) + " labels");
  const py::ssize_t frames = points.shape(0);
  const double* data = points.data();
  py::gil_scoped_release unlocked;
  c3d::C3dStreamWriter writer(path, labels, rate, descriptions);
  // Missing where a coordinate is not finite (the writer's rule): frames go straight from numpy.
  for (py::ssize_t f = 0; f < frames; ++f)
    writer.append(Eigen::Map<const Eigen::Matrix3Xd>(data + f * 3 * point_count, 3, point_count));
  writer.finish();
}

}  // namespace

void bind_c3d(py::module_& module) {
  py::class_<C3dData>(module, "C3dData",
                      "A C3D recording: labels, rate (Hz) and points (F, P, 3) in mm, NaN where missing. "
                      "Unpacks as `labels, rate, points = s2kf.read_c3d(path)`.")
      .def_property_readonly("labels", &C3dData::labels, "point labels (subject prefix removed)")
      .def_property_readonly(
          "rate", [](const C3dData& d) { return d.recording.info.rate; }, "frames per second")
      .def_property_readonly(
          "points",
          [](py::object self) {
            const c3d::Recording& r = self.cast<const C3dData&>().recording;
            // No copy: the array views the recording and keeps this object alive.
            return py::array_t<double>({r.frame_count(), r.point_count(), Eigen::Index{3}},
                                       r.positions.data(), self);
          },
          "(F, P, 3) float64, mm, NaN where a point is missing (a view, no copy)")
      .def_property_readonly(
          "visible",
          [](py::object self) {
            const c3d::Recording& r = self.cast<const C3dData&>().recording;
            // P x F column-major bool = C-ordered (F, P).
            return py::array_t<bool>({r.frame_count(), r.point_count()}, r.visible.data(), self);
          },
          "(F, P) bool, False where a point is missing")
      .def_property_readonly(
          "model_output",
          [](const C3dData& d) {
            py::array_t<bool> out(static_cast<py::ssize_t>(d.recording.info.labels.size()));
            for (std::size_t p = 0; p < d.recording.info.labels.size(); ++p)
              out.mutable_at(static_cast<py::ssize_t>(p)) = d.recording.info.labels[p].model_output;
            return out;
          },
          "(P,) bool: computed outputs (angles, forces, ...) that are not markers")
      .def_property_readonly(
          "raw_labels",
          [](const C3dData& d) {
            std::vector<std::string> raw;
            for (const c3d::PointLabel& label : d.recording.info.labels) raw.push_back(label.raw);
            return raw;
          },
          "labels as stored in the file")
      .def_property_readonly("descriptions", [](const C3dData& d) { return d.recording.info.descriptions; })
      .def_property_readonly(
          "warnings", [](const C3dData& d) { return d.recording.info.warnings; },
          "what the reader had to work around")
      .def_property_readonly(
          "units", [](const C3dData& d) { return d.recording.info.units; }, "POINT:UNITS as stored")
      .def_property_readonly(
          "to_mm", [](const C3dData& d) { return d.recording.info.to_mm; },
          "the factor that turned the stored coordinates into mm")
      .def_property_readonly("first_frame", [](const C3dData& d) { return d.recording.info.first_frame; })
      .def("__iter__",
           [](py::object self) {
             const C3dData& d = self.cast<const C3dData&>();
             return py::iter(py::make_tuple(d.labels(), d.recording.info.rate, self.attr("points")));
           })
      .def("__repr__", [](const C3dData& d) {
        return "<s2kf.C3dData: " + std::to_string(d.recording.frame_count()) + " frames, " +
               std::to_string(d.recording.point_count()) + " points at " +
               c3d::detail::format_number(d.recording.info.rate) + " Hz>";
      });

  module.def("read_c3d", &read_c3d_file, py::arg("path"),
             "Reads a whole C3D file. Returns a C3dData that unpacks as (labels, rate, points), points "
             "(F, P, 3) in mm with NaN for missing. Raises FileNotFoundError for a missing file and "
             "OSError for one that is not a readable C3D file.");
  module.def("write_c3d", &write_c3d_file, py::arg("path"), py::arg("labels"), py::arg("rate"),
             py::arg("points"), py::arg("descriptions") = std::vector<std::string>{},
             "Writes (F, P, 3) points in mm (NaN: missing) with one label per point as a C3D file "
             "(Intel, float). The file appears only when complete.");
}

}  // namespace s2kf::python
