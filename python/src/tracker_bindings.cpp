/// @file
/// s2kf.Tracker: the whole-body tracker fed one frame at a time from Python (live systems), and
/// s2kf.FrameEstimate, what it reports per frame. The per-frame path copies the frame into buffers
/// the tracker reuses and runs the filter without the GIL, so it costs what C++ costs plus the
/// conversion of one (P, 3) array and the estimate's few small arrays (measured in docs/python.md).
#include "bindings.hpp"
#include "numpy_bridge.hpp"
#include "streaming_tracker.hpp"

#include <s2kf/app/marker_set_json.hpp>
#include <s2kf/app/sample_sets.hpp>
#include <s2kf/app/track_request.hpp>

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/body/marker_set_mapping.hpp>
#include <s2kf/io/sample_cache.hpp>
#include <s2kf/pipeline/session.hpp>
#include <s2kf/track/tracker.hpp>
#include <s2kf/track/tracker_options.hpp>

#include <pybind11/stl.h>

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

namespace s2kf::python {
namespace {

/// A tracker whose model carries a marker set (bundled name or file), as the pipeline builds it
/// (pipeline::prepare_session): the set applied to the model at its reference height, scaled to the
/// subject, labels mapped by the set's labels and aliases, the set's per-marker noise.
std::unique_ptr<StreamingTracker> streaming_tracker_for_marker_set(const std::vector<std::string>& labels,
                                                                   double rate, const std::string& markerset,
                                                                   double height_mm,
                                                                   track::TrackerOptions options) {
  if (!pipeline::plausible_height_mm(height_mm))
    throw py::value_error("height_mm must lie between 300 and 3000, got " + number_text(height_mm));
  body::MarkerSet set;
  try {
    set = app::resolve_marker_set(markerset);
  } catch (const app::UserError& e) {
    throw py::value_error(e.what());
  }
  const body::BodyModel model = body::apply_marker_set(body::mmm_body_model(set.reference_height_mm), set);
  const body::MarkerMapping mapping = body::map_marker_set(labels, set);
  if (mapping.markers_used() == 0)
    throw py::value_error("none of the " + std::to_string(labels.size()) +
                          " labels is a marker of the marker set " + set.name);
  if (!(rate > 0) || !std::isfinite(rate))
    throw py::value_error("the frame rate must be a positive number of Hz, got " + number_text(rate));
  options.marker_noise_mm_per_marker = pipeline::marker_noise_of(set);
  py::gil_scoped_release unlocked;
  const SampleSet samples = app::cached_sample_set(model.joint_count() + 6, options.samples);
  return std::make_unique<StreamingTracker>(model.scaled(height_mm), mapping, std::move(options), rate,
                                            samples, static_cast<Eigen::Index>(labels.size()));
}

track::TrackerOptions tracker_options(const std::string& preset, const std::string& gain, double rate,
                                      int samples, double marker_noise_mm, double gate_probability) {
  // The preset, samples and gain as s2kf.track and `s2kf track` take them (app::TrackRequest).
  app::TrackRequest request;
  request.names = app::OptionNames::python;
  request.preset = preset;
  request.gain = gain;
  if (samples > 0) request.samples = samples;
  app::check_request(request);
  track::TrackerOptions options = app::tracker_options(request, rate);
  if (marker_noise_mm > 0) options.marker_noise_mm = marker_noise_mm;
  options.gate_probability = gate_probability;
  options.validate();
  return options;
}

}  // namespace

void bind_tracker(py::module_& module) {
  using track::FrameEstimate;
  py::class_<FrameEstimate>(module, "FrameEstimate",
                            "What the tracker knows after one frame (arrays are copies).")
      .def_readonly("tracked", &FrameEstimate::tracked, "False before the first frame with enough markers")
      .def_property_readonly("status",
                             [](const FrameEstimate& e) { return std::string(to_string(e.status)); })
      .def_property_readonly(
          "root_position", [](const FrameEstimate& e) { return vector_copy(e.pose.root_position); },
          "(3,) mm")
      .def_property_readonly(
          "root_rpy", [](const FrameEstimate& e) { return vector_copy(e.pose.root_rpy); },
          "(3,) roll, pitch, yaw, rad")
      .def_property_readonly(
          "joints", [](const FrameEstimate& e) { return vector_copy(e.pose.joints); }, "(40,) rad")
      .def_property_readonly(
          "pose", [](const FrameEstimate& e) { return vector_copy(body::pose_row(e.pose)); },
          "(46,) root x, y, z, roll, pitch, yaw, joints: a row of the motion table")
      .def_property_readonly(
          "root_rotation", [](const FrameEstimate& e) { return matrix_copy(e.root_rotation); }, "(3, 3)")
      .def_property_readonly(
          "covariance", [](const FrameEstimate& e) { return matrix_copy(e.covariance); },
          "(46, 46): root position (mm), orientation error (rad), joint parameters Theta")
      .def_property_readonly(
          "predicted_markers", [](const FrameEstimate& e) { return points_copy(e.predicted_markers); },
          "(M, 3) every model marker at the estimate, mm")
      .def_property_readonly(
          "marker_distance", [](const FrameEstimate& e) { return vector_copy(e.marker_distance); },
          "(M,) mm per model marker, NaN where not observed")
      .def_readonly("mean_marker_distance", &FrameEstimate::mean_marker_distance, "mm")
      .def_readonly("visible_markers", &FrameEstimate::visible_markers)
      .def_readonly("nis", &FrameEstimate::nis)
      .def_readonly("seconds", &FrameEstimate::seconds, "time spent in the C++ tracker");

  py::class_<StreamingTracker>(
      module, "Tracker",
      "The whole-body S2KF tracker, one frame at a time. `labels` name the points of "
      "each frame, matched to the model's markers by name (KIT names).")
      .def(
          py::init([](const std::vector<std::string>& labels, double rate, const body::BodyModel* model,
                      const py::object& markerset, double height_mm, int samples, const std::string& preset,
                      const std::string& gain, double marker_noise_mm, double gate_probability) {
            track::TrackerOptions options =
                tracker_options(preset, gain, rate, samples, marker_noise_mm, gate_probability);
            if (markerset.is_none())
              return streaming_tracker_for_labels(labels, rate,
                                                  model ? *model : body::mmm_body_model(height_mm), options);
            if (model) throw py::value_error("give a model or a marker set, not both");
            return streaming_tracker_for_marker_set(labels, rate, py::str(markerset), height_mm, options);
          }),
          py::arg("labels"), py::arg("rate"), py::arg("model") = nullptr, py::arg("markerset") = py::none(),
          py::arg("height_mm") = 1750.0, py::arg("samples") = 301, py::arg("preset") = "default",
          py::arg("gain") = "information-form", py::arg("marker_noise_mm") = 0.0,
          py::arg("gate_probability") = 0.0,
          "labels: one per point; rate: Hz; model: a BodyModel whose marker names the labels are (default: "
          "the KIT model at height_mm); markerset: 'kit', 'cmu', 'plugin_gait' or a .json file instead, on a "
          "subject of height_mm; samples: S2KF sample count; preset: 'default' or 'paper'; gain: "
          "'information-form' or 'square-root' (the exact update); marker_noise_mm: "
          "0 keeps the preset's")
      .def("process", &StreamingTracker::process, py::arg("frame"), py::arg("visible") = py::none(),
           "One frame: (P, 3) mm in label order (NaN: hidden), optional (P,) visibility. Returns a "
           "FrameEstimate. Runs without the GIL.")
      .def_property_readonly("model", [](const StreamingTracker& t) { return t.tracker().model(); })
      .def_property_readonly("joint_names",
                             [](const StreamingTracker& t) { return t.tracker().model().joint_names(); })
      .def_property_readonly("markers_used",
                             [](const StreamingTracker& t) {
                               // In the model's order (the tracker stacks them by body part).
                               std::vector<int> used = t.tracker().used_markers();
                               std::sort(used.begin(), used.end());
                               std::vector<std::string> names;
                               for (int m : used) names.push_back(t.tracker().model().markers[m].name);
                               return names;
                             })
      .def_property_readonly("ignored_labels",
                             [](const StreamingTracker& t) { return t.tracker().mapping().ignored_labels; })
      .def_property_readonly("samples",
                             [](const StreamingTracker& t) { return t.tracker().options().samples; })
      .def_property_readonly("initialised",
                             [](const StreamingTracker& t) { return t.tracker().initialised(); })
      .def_property_readonly("frames_processed",
                             [](const StreamingTracker& t) { return t.tracker().frames_processed(); });
}

}  // namespace s2kf::python
