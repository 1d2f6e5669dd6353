/// @file
/// s2kf.track: a whole recording through the library's pipeline (pipeline/session.hpp: marker-set
/// choice, height, subject calibration, tracker, optional smoothing) exactly as `s2kf track` runs it,
/// with the same summary; and s2kf.TrackResult, the motion as numpy views with the program's
/// writers (.csv, .mot, .bvh, .json, _markers.csv).
#include "bindings.hpp"
#include "numpy_bridge.hpp"
#include "streaming_tracker.hpp"

#include <s2kf/app/calibrated_subject.hpp>
#include <s2kf/app/sample_sets.hpp>
#include <s2kf/app/track_request.hpp>
#include <s2kf/app/user_error.hpp>

#include <s2kf/io/atomic_file.hpp>
#include <s2kf/io/bvh.hpp>
#include <s2kf/io/c3d_frame_source.hpp>
#include <s2kf/io/frame_source.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/pipeline/session.hpp>
#include <s2kf/track/tracking_metrics.hpp>

#include <pybind11/stl.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace s2kf::python {
namespace {

namespace fs = std::filesystem;

/// A tracked recording: the request's preparation (marker set, session, samples), the run, and the
/// summary `s2kf track` writes.
struct TrackResult {
  std::string name;  // the .mot file's first line: the recording's file stem
  app::PreparedTrack prepared;
  track::TrackingRun run;
  nlohmann::json summary;
  Eigen::Index point_count = 0;
};

/// The request through the application layer, as `s2kf track` runs it (without its files).
std::unique_ptr<TrackResult> track_request(FrameSource& source, const app::RecordingDescription& recording,
                                           const std::string& name, const app::TrackRequest& request) {
  auto result = std::make_unique<TrackResult>();
  result->name = name;
  result->point_count = static_cast<Eigen::Index>(source.labels().size());
  result->prepared = app::prepare_track(source, recording, request);
  result->run = app::run_track(result->prepared, source, request);
  result->summary = app::summarize_track(result->prepared, result->run, request);
  return result;
}

/// Frames read in place from a C-ordered (F, P, 3) float64 array: no copy of the recording. A
/// point is visible where its coordinates are finite.
class ArrayFrameSource : public FrameSource {
 public:
  ArrayFrameSource(const double* data, std::int64_t frames, std::vector<std::string> labels, double rate)
      : data_(data), frames_(frames), labels_(std::move(labels)), rate_(rate) {}
  const std::vector<std::string>& labels() const override { return labels_; }
  double rate_hz() const override { return rate_; }
  std::int64_t frame_count() const override { return frames_; }
  bool read(std::int64_t index, MarkerFrame& frame) override {
    if (index < 0 || index >= frames_) return false;
    const auto points = static_cast<Eigen::Index>(labels_.size());
    frame.index = index;
    frame.positions = Eigen::Map<const Eigen::Matrix3Xd>(data_ + index * 3 * points, 3, points);
    frame.visible.resize(points);
    for (Eigen::Index p = 0; p < points; ++p) {
      frame.visible(p) = frame.positions.col(p).allFinite();
      if (!frame.visible(p)) frame.positions.col(p).setConstant(std::numeric_limits<double>::quiet_NaN());
    }
    return true;
  }

 private:
  const double* data_;
  std::int64_t frames_;
  std::vector<std::string> labels_;
  double rate_;
};

/// The program's error sentences as Python exceptions: a missing file is FileNotFoundError.
[[noreturn]] void raise_user_error(const std::string& message) {
  const bool missing =
      message.find("does not exist") != std::string::npos || message.find("cannot open") != std::string::npos;
  PyErr_SetString(missing ? PyExc_FileNotFoundError : PyExc_ValueError, message.c_str());
  throw py::error_already_set();
}

std::unique_ptr<TrackResult> track(const py::object& recording, const py::object& labels_value,
                                   const py::object& rate_value, const app::TrackRequest& request,
                                   const py::object& model_output_value, const py::object& name_value) {
  try {
    app::check_request(request);
    // A C3D file: read as the program reads it, frame by frame.
    if (py::isinstance<py::str>(recording) || py::hasattr(recording, "__fspath__")) {
      if (!labels_value.is_none() || !rate_value.is_none())
        throw py::value_error(
            "labels and rate come from the C3D file; give them only with an array of points");
      const std::string path = py::str(py::module_::import("os").attr("fspath")(recording));
      if (!fs::exists(path)) raise_user_error(path + ": no such file (it does not exist)");
      py::gil_scoped_release unlocked;
      c3d::C3dFrameSource source(path);
      app::RecordingDescription description;
      description.input = path;
      description.readable_file =
          true;  // labels the set does not name placed by their motion, as the program
      for (const c3d::PointLabel& label : source.info().labels) description.raw_labels.push_back(label.raw);
      description.file_warnings = source.info().warnings;
      return track_request(source, description, fs::path(path).stem().string(), request);
    }
    // Points with labels and a rate, given or taken from a read_c3d / simulate result.
    py::object points_value = recording, model_output = model_output_value;
    py::object labels_object = labels_value, rate_object = rate_value;
    std::vector<std::string> file_warnings;
    if (py::hasattr(recording, "points") && py::hasattr(recording, "labels") &&
        py::hasattr(recording, "rate")) {
      points_value = recording.attr("points");
      if (labels_object.is_none()) labels_object = recording.attr("labels");
      if (rate_object.is_none()) rate_object = recording.attr("rate");
      if (model_output.is_none() && py::hasattr(recording, "model_output"))
        model_output = recording.attr("model_output");
      if (py::hasattr(recording, "warnings"))
        file_warnings = recording.attr("warnings").cast<std::vector<std::string>>();
    }
    if (labels_object.is_none() || rate_object.is_none())
      throw py::value_error(
          "track(points, labels, rate): labels and rate are needed with an array of points");
    const auto labels = labels_object.cast<std::vector<std::string>>();
    const double rate = rate_object.cast<double>();
    if (!(rate > 0) || !std::isfinite(rate))
      throw py::value_error("the frame rate must be a positive number of Hz, got " + number_text(rate));
    const DoubleArray points = as_double_array(points_value, "points");
    const auto point_count = static_cast<py::ssize_t>(labels.size());
    require_shape(points, {-1, point_count, 3}, "points",
                  "(F, P, 3) with P = " + std::to_string(point_count) + " labels");
    // Model outputs (angles, forces stored as points) match nothing: an empty label, as the program.
    std::vector<std::string> matched = labels;
    if (!model_output.is_none()) {
      const auto mask = py::array_t<bool, py::array::c_style | py::array::forcecast>::ensure(model_output);
      if (!mask || mask.ndim() != 1 || mask.shape(0) != point_count)
        throw py::value_error("model_output must be one bool per point (" + std::to_string(point_count) +
                              ")");
      for (py::ssize_t p = 0; p < point_count; ++p)
        if (mask.at(p)) matched[static_cast<std::size_t>(p)].clear();
    }
    const std::string name = name_value.is_none() ? std::string("recording") : name_value.cast<std::string>();
    py::gil_scoped_release unlocked;
    ArrayFrameSource source(points.data(), points.shape(0), matched, rate);
    app::RecordingDescription description;
    description.input = name;
    description.raw_labels = labels;
    description.file_warnings = file_warnings;
    return track_request(source, description, name, request);
  } catch (const app::UserError& e) {
    raise_user_error(e.what());
  }
}

/// s2kf.calibrate: `s2kf calibrate` without its report and .osim file: the calibrated subject as
/// the document a subject file holds (a dict), also written to `out` when given.
py::object calibrate(const py::object& recording, const py::object& out,
                     const app::SubjectSettings& settings) {
  const py::object fspath = py::module_::import("os").attr("fspath");
  const std::string path = py::str(fspath(recording));
  const std::string out_path = out.is_none() ? std::string() : std::string(py::str(fspath(out)));
  const std::string name =
      out_path.empty() ? fs::path(path).stem().string() + "_subject" : fs::path(out_path).stem().string();
  nlohmann::json document;
  try {
    if (!fs::exists(path)) raise_user_error(path + ": no such file (it does not exist)");
    py::gil_scoped_release unlocked;
    const app::CalibratedSubject calibrated = app::calibrate_subject_file(
        path, "", settings, app::cached_sample_set(6 + body::kJointCount, app::TrackRequest{}.samples), name);
    document = app::subject_document(calibrated, path);
    if (!out_path.empty()) app::write_subject_file(out_path, document);
  } catch (const app::UserError& e) {
    raise_user_error(e.what());
  }
  return py::module_::import("json").attr("loads")(document.dump());
}

/// A view of column `first`..`first + count` of the run's motion table (frames x columns,
/// column-major), as a (F, count) array, or (F,) for one column; no copy.
py::array motion_columns_view(py::object self, Eigen::Index first, Eigen::Index count, bool flatten) {
  const Eigen::MatrixXd& values = self.cast<const TrackResult&>().run.motion.values;
  const auto step = static_cast<py::ssize_t>(sizeof(double));
  const double* data = values.data() + first * values.rows();
  if (flatten) return py::array_t<double>({values.rows()}, {step}, data, self);
  return py::array_t<double>({values.rows(), count}, {step, step * values.rows()}, data, self);
}

void write_marker_report(const TrackResult& r, const std::string& path) {
  // PREFIX_markers.csv of `s2kf track`, line for line.
  io::write_file_atomically(path, [&](std::ostream& out) {
    out << "frame,time,mean_marker_distance_mm,visible_markers\n";
    for (std::size_t f = 0; f < r.run.motion.frame.size(); ++f) {
      out << std::setprecision(9) << r.run.motion.frame[f] << "," << r.run.motion.time[f] << ",";
      if (std::isfinite(r.run.mean_marker_distance[f]))
        out << r.run.mean_marker_distance[f];
      else
        out << "nan";
      out << "," << r.run.visible_markers[f] << "\n";
    }
  });
}

void write_summary(const TrackResult& r, const std::string& path) {
  io::write_file_atomically(path, [&](std::ostream& out) { out << r.summary.dump(2) << "\n"; });
}

}  // namespace

void bind_track(py::module_& module) {
  py::class_<TrackResult>(
      module, "TrackResult",
      "A tracked recording: the motion (arrays are views, one row per frame), the model it "
      "was tracked with, the program's summary, and writers for its output files.")
      .def_property_readonly(
          "frame",
          [](const TrackResult& r) {
            py::array_t<long> out(static_cast<py::ssize_t>(r.run.motion.frame.size()));
            std::copy(r.run.motion.frame.begin(), r.run.motion.frame.end(), out.mutable_data());
            return out;
          },
          "(F,) frame numbers")
      .def_property_readonly(
          "time",
          [](const TrackResult& r) {
            return vector_copy(Eigen::Map<const Eigen::VectorXd>(
                r.run.motion.time.data(), static_cast<Eigen::Index>(r.run.motion.time.size())));
          },
          "(F,) s")
      .def_property_readonly(
          "poses", [](py::object self) { return motion_columns_view(self, 0, 6 + body::kJointCount, false); },
          "(F, 46) root x, y, z (mm), roll, pitch, yaw (rad), joints (rad); NaN rows before tracking starts")
      .def_property_readonly(
          "root_position", [](py::object self) { return motion_columns_view(self, 0, 3, false); },
          "(F, 3) mm")
      .def_property_readonly(
          "root_rpy", [](py::object self) { return motion_columns_view(self, 3, 3, false); }, "(F, 3) rad")
      .def_property_readonly(
          "joints", [](py::object self) { return motion_columns_view(self, 6, body::kJointCount, false); },
          "(F, 40) rad, in joint_names order")
      .def_property_readonly("joint_names", [](const TrackResult& r) { return r.run.motion.joint_names; })
      .def_property_readonly(
          "marker_distance",
          [](const TrackResult& r) {
            return vector_copy(Eigen::Map<const Eigen::VectorXd>(
                r.run.mean_marker_distance.data(),
                static_cast<Eigen::Index>(r.run.mean_marker_distance.size())));
          },
          "(F,) mean distance (mm) between the observed markers and the model's, NaN where none")
      .def_property_readonly(
          "visible_markers",
          [](const TrackResult& r) {
            py::array_t<int> out(static_cast<py::ssize_t>(r.run.visible_markers.size()));
            std::copy(r.run.visible_markers.begin(), r.run.visible_markers.end(), out.mutable_data());
            return out;
          },
          "(F,) mapped markers observed per frame")
      .def_property_readonly(
          "seconds",
          [](const TrackResult& r) {
            return vector_copy(Eigen::Map<const Eigen::VectorXd>(
                r.run.seconds.data(), static_cast<Eigen::Index>(r.run.seconds.size())));
          },
          "(F,) time the tracker spent per frame")
      .def_property_readonly(
          "summary",
          [](const TrackResult& r) { return py::module_::import("json").attr("loads")(r.summary.dump()); },
          "the dict `s2kf track` writes as PREFIX.json")
      .def_property_readonly(
          "messages", [](const TrackResult& r) { return r.prepared.messages; },
          "what the program prints about the marker set")
      .def_property_readonly(
          "model", [](const TrackResult& r) { return r.prepared.session.model; },
          "the body model tracked with: the marker set applied, scaled, calibrated")
      .def_property_readonly("height_mm", [](const TrackResult& r) { return r.prepared.session.height_mm; })
      .def(
          "to_csv",
          [](const TrackResult& r, const std::string& path) { io::save_motion_csv(path, r.run.motion); },
          py::arg("path"), "frame,time,root_x,...,RAy (mm, rad), as `s2kf track` writes PREFIX.csv")
      .def(
          "to_mot",
          [](const TrackResult& r, const std::string& path) {
            io::save_opensim_mot(path, r.run.motion, r.name);
          },
          py::arg("path"), "OpenSim motion file (degrees, metres)")
      .def(
          "to_bvh",
          [](const TrackResult& r, const std::string& path) {
            io::save_bvh(path, r.prepared.session.model, r.run.motion, r.prepared.session.rate_hz);
          },
          py::arg("path"), "BVH for Blender")
      .def("to_json", &write_summary, py::arg("path"), "the summary as `s2kf track` writes PREFIX.json")
      .def("to_marker_report", &write_marker_report, py::arg("path"),
           "frame,time,mean_marker_distance_mm,visible_markers (PREFIX_markers.csv)")
      .def(
          "write",
          [](const TrackResult& r, const std::string& prefix) {
            io::save_motion_csv(prefix + ".csv", r.run.motion);
            io::save_opensim_mot(prefix + ".mot", r.run.motion, r.name);
            io::save_bvh(prefix + ".bvh", r.prepared.session.model, r.run.motion, r.prepared.session.rate_hz);
            write_summary(r, prefix + ".json");
            write_marker_report(r, prefix + "_markers.csv");
          },
          py::arg("prefix"), "PREFIX.csv, .mot, .bvh, .json and _markers.csv, as `s2kf track --out PREFIX`")
      .def(
          "tracker",
          [](const TrackResult& r) {
            return std::make_unique<StreamingTracker>(r.prepared.session.model, r.prepared.session.mapping,
                                                      r.prepared.session.tracker, r.prepared.session.rate_hz,
                                                      r.prepared.samples, r.point_count);
          },
          "a fresh streaming Tracker with this result's model, marker mapping and options: feeding it the "
          "recording's frames reproduces the (unsmoothed) motion")
      .def("__repr__", [](const TrackResult& r) {
        return "<s2kf.TrackResult " + r.name + ": " + std::to_string(r.run.frames_tracked) + " of " +
               std::to_string(r.run.frames) + " frames tracked>";
      });

  // The keywords are `s2kf track`'s options (dashes as underscores) with the same defaults, from
  // one app::TrackRequest; python/tests/test_parity.py checks them against `s2kf track --help`.
  const app::TrackRequest defaults;
  module.def(
      "track",
      [](const py::object& recording, const py::object& labels, const py::object& rate,
         const py::object& markerset, const py::object& subject, const py::object& static_trial,
         double static_sd, const py::object& static_pose, const std::string& static_posture,
         bool static_alone, const py::object& static_refine, bool static_stretch, bool calibrate,
         std::int64_t calibration_frames, int calibration_samples, double calibration_shrink,
         bool uniform_noise, bool smooth, int samples, double height, const py::object& height_mm,
         const std::string& preset, const std::string& motion_model, const std::string& gain,
         const std::string& method, const py::object& truth, bool force, const py::object& model_output,
         const py::object& name) {
        const auto text = [](const py::object& value) {
          return value.is_none() ? std::string() : py::str(value).cast<std::string>();
        };
        app::TrackRequest request;
        request.names = app::OptionNames::python;
        request.markerset = text(markerset);
        request.subject = text(subject);
        request.static_trial = text(static_trial);
        request.static_sd_deg = static_sd;
        request.static_pose = text(static_pose);
        request.static_posture = static_posture;
        request.static_alone = static_alone;
        request.static_refine = !static_refine.is_none() && static_refine.cast<bool>();
        if (const std::string deprecated = app::deprecation_warning(request); !deprecated.empty())
          if (PyErr_WarnEx(PyExc_DeprecationWarning, deprecated.c_str(), 1) != 0)
            throw py::error_already_set();
        request.static_stretch = static_stretch;
        request.calibrate = calibrate;
        request.calibration_frames = static_cast<long>(calibration_frames);
        request.calibration_samples = calibration_samples;
        request.calibration_shrink = calibration_shrink;
        request.uniform_noise = uniform_noise;
        request.smooth = smooth;
        request.samples = samples;
        request.height_mm =
            height_mm.is_none() ? height : height_mm.cast<double>();  // height_mm: the old name
        request.preset = preset;
        request.motion_model = motion_model;
        request.gain = gain;
        request.method = method;
        request.truth = text(truth);
        request.force = force;
        return track(recording, labels, rate, request, model_output, name);
      },
      py::arg("recording"), py::arg("labels") = py::none(), py::arg("rate") = py::none(), py::kw_only(),
      py::arg("markerset") = py::none(), py::arg("subject") = py::none(), py::arg("static") = py::none(),
      py::arg("static_sd") = defaults.static_sd_deg, py::arg("static_pose") = py::none(),
      py::arg("static_posture") = defaults.static_posture, py::arg("static_alone") = defaults.static_alone,
      py::arg("static_refine") = py::none(), py::arg("static_stretch") = defaults.static_stretch,
      py::arg("calibrate") = defaults.calibrate, py::arg("calibration_frames") = defaults.calibration_frames,
      py::arg("calibration_samples") = defaults.calibration_samples,
      py::arg("calibration_shrink") = defaults.calibration_shrink,
      py::arg("uniform_noise") = defaults.uniform_noise, py::arg("smooth") = defaults.smooth,
      py::arg("samples") = defaults.samples, py::arg("height") = defaults.height_mm,
      py::arg("height_mm") = py::none(), py::arg("preset") = defaults.preset,
      py::arg("motion_model") = defaults.motion_model, py::arg("gain") = defaults.gain,
      py::arg("method") = defaults.method, py::arg("truth") = py::none(), py::arg("force") = defaults.force,
      py::arg("model_output") = py::none(), py::arg("name") = py::none(),
      "Tracks a whole recording as `s2kf track` does, with its options as keywords (dashes as "
      "underscores, the same defaults): track('walk.c3d'), track(s2kf.read_c3d(...)), or track(points, "
      "labels, rate) with points (F, P, 3) in mm, NaN where hidden. markerset: 'kit', 'cmu', "
      "'plugin_gait' or a .json file (default: the best match); subject: a calibrated subject file; "
      "static: a C3D static trial, on which the subject is calibrated together with the recording "
      "(static_alone=True: on the static trial alone, then the recording tracked with it; static_pose: "
      "the pose held, "
      "'zero', 't-pose', 'a-pose' or a pose CSV, default: the nearest one; static_sd: each joint's SD "
      "from it, degrees; static_posture: 'near', the posture held estimated near the pose, 'exact', or "
      "'auto' (exact, the pelvis "
      "upright, where a segment carries only markers placed by their motion, else near); "
      "static_refine: deprecated, what static does now); static_stretch: without "
      "static, a stretch of the recording where the subject stands still in a reference pose is its "
      "static trial; calibrate: fit the subject's "
      "offsets and bone lengths on calibration_frames frames spread over the recording (calibration_samples: "
      "the samples of its tracking pass, 0: samples); calibration_shrink: C, a weakly seen offset direction "
      "keeps mu / (mu + C) of the data's step; uniform_noise: every marker the same noise (else each its "
      "calibration residual's); smooth: RTS smoothing; height: mm, 0 estimates it (height_mm: the same, "
      "its former name); motion_model: 'random-walk' or 'constant-velocity'; gain: 'information-form' or "
      "'square-root' (the exact update); truth: a ground-truth motion CSV, whose accuracy goes into the "
      "summary; force: track a C3D file even when the set inferred from its motion does not look like a "
      "whole body; "
      "model_output: (P,) bool, points that are not markers. Runs without the GIL. Returns a "
      "TrackResult.");

  module.def(
      "calibrate",
      [](const py::object& recording, const py::object& out, bool static_trial, double static_sd,
         const py::object& static_pose, const std::string& static_posture, const py::object& markerset,
         double height_mm, std::int64_t frames, bool uniform_noise) {
        app::SubjectSettings settings;
        settings.markerset = markerset.is_none() ? std::string() : py::str(markerset).cast<std::string>();
        if (height_mm != 0 && !(height_mm >= 300 && height_mm <= 3000))
          throw py::value_error("height_mm must lie between 300 and 3000 (or be 0: estimated), got " +
                                number_text(height_mm));
        if (frames < 10) throw py::value_error("frames must be at least 10");
        if (!(static_sd >= 0.1 && static_sd <= 90.0))
          throw py::value_error("static_sd must lie between 0.1 and 90 degrees");
        settings.height_mm = height_mm;
        settings.frames = static_cast<long>(frames);
        settings.noise_from_calibration = !uniform_noise;
        if (static_posture != "near" && static_posture != "exact")
          throw py::value_error("static_posture must be 'near' or 'exact', not '" + static_posture + "'");
        settings.static_pose = static_trial;
        settings.static_sd_deg = static_sd;
        settings.static_pose_name =
            static_pose.is_none() ? std::string() : py::str(static_pose).cast<std::string>();
        settings.static_pose_option = "static_pose";
        settings.static_posture = static_posture;
        settings.threads = every_core();
        return calibrate(recording, out, settings);
      },
      py::arg("recording"), py::kw_only(), py::arg("out") = py::none(), py::arg("static") = false,
      py::arg("static_sd") = 3.0, py::arg("static_pose") = py::none(), py::arg("static_posture") = "near",
      py::arg("markerset") = py::none(), py::arg("height_mm") = 0.0, py::arg("frames") = 1200,
      py::arg("uniform_noise") = false,
      "Estimates a subject's marker offsets and bone lengths from a C3D recording as `s2kf calibrate` does "
      "and returns the subject file's document (a dict); out: also write it there (for track(subject=...) "
      "or `s2kf track --subject`). static: the recording is a static trial (static_pose, static_sd, "
      "static_posture: as in track); markerset: as in track; frames: frames used at "
      "most; uniform_noise: write no per-marker noise. Runs without the GIL.");
}

}  // namespace s2kf::python
