/// @file
/// s2kf.simulate: a synthetic recording with ground truth, made exactly as `s2kf simulate` makes it
/// (the same motion files, subject, noise and occlusion draws for the same seed), as numpy arrays.
#include "bindings.hpp"
#include "numpy_bridge.hpp"

#include <s2kf/app/bundled_motions.hpp>
#include <s2kf/app/motion_json.hpp>

#include <s2kf/body/body_model.hpp>
#include <s2kf/sim/recording.hpp>
#include <s2kf/sim/subject.hpp>

#include <pybind11/stl.h>

#include <algorithm>
#include <filesystem>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

namespace s2kf::python {
namespace {

namespace fs = std::filesystem;

/// A simulation's arrays in the module's layout: points and clean (F, M, 3), visible (F, M),
/// truth (F, 46) rows of the motion table.
struct Simulation {
  sim::Recording recording;  // the measured markers (MarkerSequence: 3M x F, NaN where hidden)
  std::vector<std::string> joint_names;
  Eigen::MatrixXd clean;  // 3M x F
  Eigen::MatrixXd truth;  // 46 x F
};

std::vector<std::string> bundled_motions() { return app::motion_names(); }

/// A bundled motion's name or the path of a motion .json file (the program's rule and messages).
fs::path resolve_motion(const std::string& motion) {
  try {
    return app::resolve_motion(motion);
  } catch (const app::UserError& e) {
    throw py::value_error(e.what());
  }
}

void require_range(double value, double low, double high, const std::string& what) {
  if (!(value >= low && value <= high))
    throw py::value_error(what + " must lie between " + number_text(low) + " and " + number_text(high) +
                          ", got " + number_text(value));
}

Simulation simulate(const std::string& motion_name, std::uint64_t seed, double height_mm, long frames,
                    double rate, std::optional<std::pair<double, double>> occlusion, double noise_mm,
                    double placement_mm, double soft_tissue_mm, double segment_scale_sd,
                    const std::vector<std::pair<double, double>>& blackouts,
                    const std::vector<std::tuple<std::string, double, double>>& dropouts) {
  // The CLI's ranges, so both accept the same settings.
  require_range(height_mm, 500, 2500, "height_mm");
  if (!(rate > 0 && rate <= 10000)) throw py::value_error("rate must lie in (0, 10000] Hz");
  if (frames < 0) throw py::value_error("frames must not be negative");
  require_range(noise_mm, 0, 1000, "noise_mm");
  require_range(placement_mm, 0, 1000, "placement_mm");
  require_range(soft_tissue_mm, 0, 1000, "soft_tissue_mm");
  require_range(segment_scale_sd, 0, 0.2, "segment_scale_sd");
  sim::RecordingOptions options;
  options.frame_rate = rate;
  options.frames = frames;
  if (occlusion) options.occlusion = {occlusion->first, occlusion->second};
  for (const auto& [start, duration] : blackouts) options.blackouts.push_back({start, duration});
  for (const auto& [segment, start, duration] : dropouts)
    options.segment_dropouts.push_back({segment, start, duration});
  sim::SubjectOptions subject_options;
  subject_options.height_mm = height_mm;
  subject_options.noise_sd_mm = noise_mm;
  subject_options.placement_sd_mm = placement_mm;
  subject_options.soft_tissue_mm = soft_tissue_mm;
  subject_options.segment_scale_sd = segment_scale_sd;
  const fs::path motion_file = resolve_motion(motion_name);

  py::gil_scoped_release unlocked;
  const sim::Subject subject = sim::make_subject(body::mmm_body_model(height_mm), subject_options, seed);
  const app::JointTable joints{subject.joint_names, subject.lower, subject.upper};
  // Same order of calls as `s2kf simulate`: motion, dropout check, recording.
  sim::Recording recording;
  try {
    const sim::KeyframeMotion motion = app::load_motion_file(motion_file, joints, seed);
    for (const sim::SegmentDropout& dropout : options.segment_dropouts)
      sim::markers_of_segment(subject, dropout.segment);
    recording = sim::simulate_recording(motion, subject, options, seed);
  } catch (const std::out_of_range& e) {
    throw std::invalid_argument(e.what());  // an unknown segment: a bad value, not an index
  }

  Simulation out;
  out.joint_names = subject.joint_names;
  const Eigen::Index count = recording.frames(), markers = recording.markers();
  const Eigen::Index columns = 6 + static_cast<Eigen::Index>(subject.joint_names.size());
  out.clean.resize(3 * markers, count);
  out.truth.resize(columns, count);
  for (Eigen::Index k = 0; k < count; ++k) {
    const auto f = static_cast<std::size_t>(k);
    out.clean.col(k) = Eigen::Map<const Eigen::VectorXd>(recording.clean[f].data(), 3 * markers);
    out.truth.col(k) = body::pose_row(recording.truth[f]);
  }
  out.recording = std::move(recording);
  // The per-frame copies are in `clean` and `truth` now; keep only the marker data.
  out.recording.clean.clear();
  out.recording.truth.clear();
  return out;
}

/// A view (F, rows / 3, 3) or (F, rows) of a column-major rows x F matrix owned by `self`.
py::array_t<double> frames_view(py::object self, const Eigen::MatrixXd& matrix, bool points) {
  if (points)
    return py::array_t<double>({matrix.cols(), matrix.rows() / 3, Eigen::Index{3}}, matrix.data(), self);
  return py::array_t<double>({matrix.cols(), matrix.rows()}, matrix.data(), self);
}

}  // namespace

void bind_simulate(py::module_& module) {
  py::class_<Simulation>(
      module, "Simulation",
      "A synthetic recording with its truth. Unpacks as (labels, rate, points) like read_c3d.")
      .def_property_readonly("motion_name", [](const Simulation& s) { return s.recording.motion_name; })
      .def_property_readonly("rate", [](const Simulation& s) { return s.recording.rate_hz; })
      .def_property_readonly(
          "labels", [](const Simulation& s) { return s.recording.labels; }, "the model's 50 marker names")
      .def_readonly("joint_names", &Simulation::joint_names)
      .def_property_readonly("hidden_fraction",
                             [](const Simulation& s) { return s.recording.hidden_fraction(); })
      .def_property_readonly(
          "points",
          [](py::object self) {
            return frames_view(self, self.cast<const Simulation&>().recording.positions, true);
          },
          "(F, M, 3) measured markers in mm, NaN where hidden")
      .def_property_readonly(
          "clean",
          [](py::object self) { return frames_view(self, self.cast<const Simulation&>().clean, true); },
          "(F, M, 3) markers with placement and soft tissue, before noise and occlusion")
      .def_property_readonly(
          "truth",
          [](py::object self) { return frames_view(self, self.cast<const Simulation&>().truth, false); },
          "(F, 46) the true pose per frame: root x, y, z (mm), roll, pitch, yaw, joints (rad)")
      .def_property_readonly(
          "visible",
          [](py::object self) {
            const auto& v = self.cast<const Simulation&>().recording.visible;
            return py::array_t<bool>({v.cols(), v.rows()}, v.data(), self);
          },
          "(F, M) bool")
      .def("__iter__", [](py::object self) {
        const Simulation& s = self.cast<const Simulation&>();
        return py::iter(py::make_tuple(s.recording.labels, s.recording.rate_hz, self.attr("points")));
      });

  module.def("simulate", &simulate, py::arg("motion"), py::arg("seed") = 1,
             py::arg("height_mm") = sim::SubjectOptions{}.height_mm, py::arg("frames") = 0,
             py::arg("rate") = 100.0, py::arg("occlusion") = py::none(),
             py::arg("noise_mm") = sim::SubjectOptions{}.noise_sd_mm,
             py::arg("placement_mm") = sim::SubjectOptions{}.placement_sd_mm,
             py::arg("soft_tissue_mm") = sim::SubjectOptions{}.soft_tissue_mm,
             py::arg("segment_scale_sd") = sim::SubjectOptions{}.segment_scale_sd,
             py::arg("blackouts") = std::vector<std::pair<double, double>>{},
             py::arg("dropouts") = std::vector<std::tuple<std::string, double, double>>{},
             "Simulates a bundled motion (see motions()) or a motion .json file on a random subject, as "
             "`s2kf simulate` does: the same seed gives the same recording. occlusion=(p, lambda) hides "
             "markers at random; blackouts [(start_s, duration_s)] hide all; dropouts [(segment, start_s, "
             "duration_s)] one segment's. frames=0: the motion's length.");
  module.def("motions", &bundled_motions, "names of the bundled motions");
}

}  // namespace s2kf::python
