/// @file
/// The definitions of <s2kf/sim/recording.hpp>: inline where the library is used header-only, compiled once
/// into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/sim/recording.hpp>

namespace s2kf::sim {

S2KF_INLINE io::MotionTable truth_motion(const Recording& recording,
                                         const std::vector<std::string>& joint_names) {
  io::MotionTable table;
  table.joint_names = joint_names;
  table.values.resize(recording.frames(), static_cast<Eigen::Index>(body::kRootValues + joint_names.size()));
  for (Eigen::Index k = 0; k < recording.frames(); ++k) {
    table.frame.push_back(static_cast<long>(k));
    table.time.push_back(recording.time_s(k));
    body::write_pose_row(recording.truth[static_cast<std::size_t>(k)], table.values.row(k).transpose());
  }
  return table;
}

S2KF_INLINE Recording simulate_recording(const KeyframeMotion& motion, const Subject& subject,
                                         const RecordingOptions& options, std::uint64_t seed) {
  if (!(options.frame_rate > 0.0) || !std::isfinite(options.frame_rate))
    throw std::invalid_argument("the frame rate must be a positive number of Hz");
  if (options.frames < 0) throw std::invalid_argument("the number of frames must not be negative");
  validate(options.occlusion);
  validate_motion(motion, subject.lower, subject.upper, subject.joint_names);
  const InterpolatedMotion trajectory(motion);
  const double span = motion.end_time() - motion.start_time();
  const Eigen::Index frames =
      options.frames > 0 ? options.frames
                         : static_cast<Eigen::Index>(std::floor(span * options.frame_rate + 1e-9)) + 1;
  if (frames > 10'000'000) throw std::invalid_argument("more than 10 million frames requested");

  Recording recording;
  recording.motion_name = motion.name;
  recording.rate_hz = options.frame_rate;
  recording.labels = subject.marker_names;
  recording.resize(frames);
  const auto markers = static_cast<Eigen::Index>(recording.labels.size());
  std::mt19937_64 noise_rng(derive_seed(seed, static_cast<std::uint64_t>(RandomStream::noise)));
  for (Eigen::Index k = 0; k < frames; ++k) {
    const double t = static_cast<double>(k) / options.frame_rate;
    recording.truth.push_back(pose_from_sample(trajectory.at(motion.start_time() + t), subject.height_mm));
    recording.clean.push_back(subject_marker_positions(subject, recording.truth.back(), t));
    auto measured = recording.frame(k);
    measured = recording.clean.back();
    if (subject.noise_sd_mm > 0.0)
      for (Eigen::Index m = 0; m < markers; ++m)
        for (int c = 0; c < 3; ++c) measured(c, m) += subject.noise_sd_mm * standard_normal(noise_rng);
  }

  recording.visible = Visibility::Constant(markers, frames, true);
  std::mt19937_64 occlusion_rng(derive_seed(seed, static_cast<std::uint64_t>(RandomStream::occlusion)));
  apply_random_occlusion(recording.visible, options.occlusion, occlusion_rng);
  for (const SegmentDropout& dropout : options.segment_dropouts) {
    const std::vector<Eigen::Index> segment_markers = markers_of_segment(subject, dropout.segment);
    const auto [first, count] = frames_of_interval(dropout.start_s, dropout.duration_s, options.frame_rate);
    hide(recording.visible, segment_markers, first, count);
  }
  std::vector<Eigen::Index> everyone(static_cast<std::size_t>(markers));
  for (Eigen::Index m = 0; m < markers; ++m) everyone[static_cast<std::size_t>(m)] = m;
  for (const Blackout& blackout : options.blackouts) {
    const auto [first, count] = frames_of_interval(blackout.start_s, blackout.duration_s, options.frame_rate);
    hide(recording.visible, everyone, first, count);
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (Eigen::Index k = 0; k < frames; ++k)
    for (Eigen::Index m = 0; m < markers; ++m)
      if (!recording.visible(m, k)) recording.frame(k).col(m).setConstant(nan);
  return recording;
}

}  // namespace s2kf::sim
