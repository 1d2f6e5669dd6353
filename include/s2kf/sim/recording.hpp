/// @file
/// A synthetic recording: a motion played on a subject, seen by a noisy camera system that loses
/// markers, with the true pose of every frame kept beside the measurements.
#pragma once

#include <s2kf/body/pose.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/io/marker_sequence.hpp>
#include <s2kf/io/motion_files.hpp>
#include <s2kf/sim/keyframe_motion.hpp>
#include <s2kf/sim/occlusion.hpp>
#include <s2kf/sim/random.hpp>
#include <s2kf/sim/subject.hpp>

#include <Eigen/Core>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace s2kf::sim {

struct RecordingOptions {
  double frame_rate = 100.0;  ///< Hz
  /// Number of frames; 0 = the motion's length: floor((t_last - t_first) * rate) + 1, so keyframes
  /// from 0 to 6.74 s give the paper's 675 frames at 100 Hz. Frames past the last keyframe hold it.
  Eigen::Index frames = 0;
  RandomOcclusion occlusion;                     ///< off by default (probability 0)
  std::vector<SegmentDropout> segment_dropouts;  ///< planned losses of one segment's markers
  std::vector<Blackout> blackouts;               ///< planned losses of every marker
};

/// What a simulation produces: the measured markers (clean + sensor noise, NaN where hidden; labels
/// are the subject's marker names) with what a real recording never has, the truth. Frame k is at
/// time k / rate_hz (0-based, like the tracker's CSV).
struct Recording : MarkerSequence {
  std::string motion_name;
  std::vector<body::Pose> truth;        ///< the subject's true pose per frame (mm, rad)
  std::vector<Eigen::Matrix3Xd> clean;  ///< markers with placement and soft tissue, before noise (mm)

  Eigen::Index frames() const { return frame_count(); }
  Eigen::Index markers() const { return point_count(); }
  double hidden_fraction() const { return visible.size() ? 1.0 - visible.cast<double>().mean() : 0.0; }
};

/// The true poses of a recording as a motion table (one row per frame, the rows `s2kf track`
/// writes), for comparing an estimate with compare_with_truth or writing FILE_truth.csv.
io::MotionTable truth_motion(const Recording& recording, const std::vector<std::string>& joint_names);

/// Stream numbers of the independent random generators (see derive_seed).
enum class RandomStream : std::uint64_t { noise = 2, occlusion = 3 };  // the subject: SubjectStream

/// The pose of a subject of `height_mm` for a motion sample (root translation scaled from the
/// reference height).
inline body::Pose pose_from_sample(const MotionSample& sample, double height_mm) {
  return body::Pose{sample.root_position * (height_mm / kReferenceHeightMm), sample.root_rpy, sample.joints};
}

/// Plays `motion` on `subject` and measures it. `seed` drives the sensor noise and the occlusion
/// (the subject carries its own draws). Throws std::invalid_argument for bad options, naming them.
Recording simulate_recording(const KeyframeMotion& motion, const Subject& subject,
                             const RecordingOptions& options, std::uint64_t seed);

}  // namespace s2kf::sim

#if !defined(S2KF_COMPILED)
#include <s2kf/sim/recording.hxx>
#endif
