/// @file
/// The streaming tracker behind s2kf.Tracker: a track::Tracker and the frame buffers it is fed
/// from, sized once, so a frame from Python costs one small copy and no allocation on the way in.
/// Shared by s2kf.Tracker (tracker_bindings.cpp) and TrackResult.tracker() (track_bindings.cpp).
#pragma once

#include "numpy_bridge.hpp"

#include <s2kf/body/body_model.hpp>
#include <s2kf/body/marker_mapping.hpp>
#include <s2kf/io/sample_cache.hpp>
#include <s2kf/track/tracker.hpp>
#include <s2kf/track/tracker_options.hpp>

#include <algorithm>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace s2kf::python {

class StreamingTracker {
 public:
  StreamingTracker(body::BodyModel model, body::MarkerMapping mapping, track::TrackerOptions options,
                   double rate, const SampleSet& samples, Eigen::Index point_count) {
    tracker_ = std::make_unique<track::Tracker>(std::move(model), std::move(mapping), std::move(options),
                                                rate, samples);
    points_.resize(3, point_count);
    visible_.resize(point_count);
  }

  /// One frame: (P, 3) mm in label order (NaN: hidden) and an optional (P,) visibility.
  track::FrameEstimate process(const py::handle& frame_value, const py::handle& visible_value) {
    const Eigen::Index count = points_.cols();
    const DoubleArray frame = as_double_array(frame_value, "frame");
    require_shape(frame, {count, 3}, "frame", "(P, 3) with P = " + std::to_string(count) + " labels");
    // C-ordered (P, 3) is the tracker's column-major 3 x P.
    std::copy(frame.data(), frame.data() + 3 * count, points_.data());
    if (visible_value.is_none()) {
      visible_.setConstant(true);  // the tracker treats NaN coordinates as hidden
    } else {
      const auto mask = py::array_t<bool, py::array::c_style | py::array::forcecast>::ensure(visible_value);
      if (!mask || mask.ndim() != 1 || mask.shape(0) != count)
        throw py::value_error("visible must be one bool per point (" + std::to_string(count) + ")");
      std::copy(mask.data(), mask.data() + count, visible_.data());
    }
    py::gil_scoped_release unlocked;
    return tracker_->process(points_, visible_);
  }

  const track::Tracker& tracker() const { return *tracker_; }

 private:
  std::unique_ptr<track::Tracker> tracker_;
  Eigen::Matrix3Xd points_;
  Eigen::Array<bool, Eigen::Dynamic, 1> visible_;
};

/// A tracker for points named `labels`, matched to the model's marker names (KIT names).
inline std::unique_ptr<StreamingTracker> streaming_tracker_for_labels(const std::vector<std::string>& labels,
                                                                      double rate,
                                                                      const body::BodyModel& model,
                                                                      const track::TrackerOptions& options) {
  if (!(rate > 0) || !std::isfinite(rate))
    throw py::value_error("the frame rate must be a positive number of Hz, got " + std::to_string(rate));
  model.validate();
  body::MarkerMapping mapping = body::map_markers(labels, model.marker_names());
  if (mapping.markers_used() == 0)
    throw py::value_error("none of the " + std::to_string(labels.size()) +
                          " labels is a marker of the body model (expected names such as LASI, RKNE, C7)");
  py::gil_scoped_release unlocked;  // the sample set may be computed (a fraction of a second) on first use
  const SampleSet samples = lcd_sample_set(model.joint_count() + 6, options.samples).set;
  return std::make_unique<StreamingTracker>(model, std::move(mapping), options, rate, samples,
                                            static_cast<Eigen::Index>(labels.size()));
}

}  // namespace s2kf::python
