/// @file
/// Hiding markers the way a camera system loses them: the paper's random process (a marker
/// vanishes for a Poisson number of frames), and planned losses of one segment or of everything.
#pragma once

#include <s2kf/sim/random.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace s2kf::sim {

/// visible(m, k): marker m is seen in frame k.
using Visibility = Eigen::Array<bool, Eigen::Dynamic, Eigen::Dynamic>;

/// The occlusion experiment of the paper (section 5): 0.5 % per frame and Poisson(100) frames.
inline constexpr double kPaperOcclusionProbability = 0.005;
inline constexpr double kPaperOcclusionMeanFrames = 100.0;

/// The paper's process: in every frame each marker that is visible vanishes with probability
/// `probability`, starting in that frame, for n ~ Poisson(mean_frames) frames (n = 0: it stays).
struct RandomOcclusion {
  double probability = 0.0;  ///< per visible marker and frame, in [0, 1]; 0 switches it off
  double mean_frames = kPaperOcclusionMeanFrames;  ///< lambda, in frames
};

/// Throws std::invalid_argument unless 0 <= probability <= 1 and 0 <= mean_frames <= 1e5.
inline void validate(const RandomOcclusion& occlusion) {
  if (!(occlusion.probability >= 0.0 && occlusion.probability <= 1.0))
    throw std::invalid_argument("the occlusion probability must lie in [0, 1]");
  if (!(occlusion.mean_frames >= 0.0 && occlusion.mean_frames <= kMaxPoissonMean))
    throw std::invalid_argument("the mean occlusion length must lie in [0, 100000] frames");
}

/// Runs the random process on every marker and clears the frames it hides in `visible`
/// (markers x frames). The process runs on its own state, so markers hidden already for other
/// reasons still follow the same statistics.
inline void apply_random_occlusion(Visibility& visible, const RandomOcclusion& occlusion,
                                   std::mt19937_64& rng) {
  validate(occlusion);
  if (occlusion.probability == 0.0) return;
  const Eigen::Index frames = visible.cols();
  for (Eigen::Index m = 0; m < visible.rows(); ++m) {
    Eigen::Index hidden_until = 0;  // first frame at which the current gap has ended
    for (Eigen::Index k = 0; k < frames; ++k) {
      if (k >= hidden_until && uniform01(rng) < occlusion.probability)
        hidden_until = k + static_cast<Eigen::Index>(poisson(rng, occlusion.mean_frames));
      if (k < hidden_until) visible(m, k) = false;
    }
  }
}

/// The long-run fraction of frames a marker spends hidden under the random process: a cycle is a
/// visible run of mean (1 - p') / p' frames, p' = p (1 - e^-lambda) the chance of a gap of at least
/// one frame, then a gap of mean lambda / (1 - e^-lambda); so the fraction is
/// p lambda / (p lambda + 1 - p'), about p lambda / (1 + p lambda) = 1/3 for the paper's values.
inline double stationary_hidden_fraction(const RandomOcclusion& occlusion) {
  const double p = occlusion.probability, lambda = occlusion.mean_frames;
  if (p == 0.0 || lambda == 0.0) return 0.0;
  const double effective = p * (1.0 - std::exp(-lambda));
  return p * lambda / (p * lambda + 1.0 - effective);
}

/// Hides the markers `markers` for frames [first, first + count), clipped to the recording.
inline void hide(Visibility& visible, const std::vector<Eigen::Index>& markers, Eigen::Index first,
                 Eigen::Index count) {
  const Eigen::Index begin = std::max<Eigen::Index>(first, 0);
  const Eigen::Index end = std::min<Eigen::Index>(first + std::max<Eigen::Index>(count, 0), visible.cols());
  for (Eigen::Index m : markers) {
    if (m < 0 || m >= visible.rows()) throw std::out_of_range("hide: marker index out of range");
    for (Eigen::Index k = begin; k < end; ++k) visible(m, k) = false;
  }
}

/// All markers of one body segment (named as the frame they ride on, e.g. "LE") vanish for a time.
struct SegmentDropout {
  std::string segment;
  double start_s = 0.0;  ///< from the first frame of the recording
  double duration_s = 1.0;
};

/// Every marker vanishes for a time (a tracker must recover afterwards).
struct Blackout {
  double start_s = 0.0;
  double duration_s = 1.0;
};

/// The frames [first, first + count) an interval of `start_s` and `duration_s` covers at
/// `frame_rate`: frame k (at time k / rate) is covered when start <= k / rate < start + duration.
inline std::pair<Eigen::Index, Eigen::Index> frames_of_interval(double start_s, double duration_s,
                                                                double frame_rate) {
  if (!(start_s >= 0.0) || !(duration_s >= 0.0) || !std::isfinite(start_s + duration_s))
    throw std::invalid_argument("an occlusion interval needs a start and a duration of at least 0 s");
  const auto first = static_cast<Eigen::Index>(std::ceil(start_s * frame_rate - 1e-9));
  const auto end = static_cast<Eigen::Index>(std::ceil((start_s + duration_s) * frame_rate - 1e-9));
  return {first, end - first};
}

}  // namespace s2kf::sim
