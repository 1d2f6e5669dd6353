/// @file
/// `s2kf evaluate`'s settings (its options) and the evaluation they run (evaluate_run.cpp).
#pragma once

#include <cstdint>
#include <string>

namespace s2kf::cli {

struct EvaluateSettings {
  std::string recording;
  std::string truth;
  int runs = 100;
  std::string samples = "93,301,461";
  std::uint64_t seed = 1;
  std::string out = "results/evaluation";
  long frames = 0;
  long warmup = 20;
  bool calibrate = true;
  bool noise_from_calibration = true;  ///< false: --uniform-noise
  bool quiet = false;
  std::string motion;              ///< simulate this motion instead of reading a recording
  std::uint64_t subject_seed = 1;  ///< the simulated subject's (and its noise's) seed
  std::string occlusion;           ///< p,lambda: random occlusion of the simulated recording
  bool smooth = false;             ///< also the S2KF with the RTS smoother, against the truth
  std::string motion_model = "random-walk";
  std::string gain = "information-form";  ///< square-root, information-form-root-products (TrackerOptions)
};

void run_evaluate(const EvaluateSettings& settings);

}  // namespace s2kf::cli
