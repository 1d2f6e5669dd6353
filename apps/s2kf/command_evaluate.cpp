// `s2kf evaluate`: its options; the evaluation itself is in evaluate_run.cpp.
#include "command.hpp"
#include "evaluate_run.hpp"

#include <memory>
#include <string>

namespace s2kf::cli {
namespace {

const RegisterCommand evaluate_registration{
    "evaluate",
    "Reproduce the paper's evaluation: S2KF against a gradient baseline, occlusion, sample counts",
    [](CLI::App& app) {
      auto settings = std::make_shared<EvaluateSettings>();
      app.add_option("recording", settings->recording,
                     "C3D recording (default: the bundled handstand with its truth)");
      app.add_option(
          "--truth", settings->truth,
          "ground-truth motion CSV (default: RECORDING_truth.csv beside the recording, if present)");
      app.add_option("--runs", settings->runs, "occlusion Monte Carlo runs (default 100)")
          ->check(CLI::Range(1, 100000));
      app.add_option(
          "--samples", settings->samples,
          "S2KF sample counts to sweep, comma-separated (default 93,301,461); the comparison and the "
          "occlusion study use 301 when listed, else the first");
      app.add_option("--seed", settings->seed, "seed of the occlusion process (default 1)");
      app.add_option("--out", settings->out, "results directory (default results/evaluation)");
      app.add_option("--frames", settings->frames, "use only the first N frames (quick runs)")
          ->check(CLI::Range(1L, 100000000L));
      app.add_option("--warmup", settings->warmup,
                     "frames left out of the accuracy against truth (default 20)")
          ->check(CLI::Range(0L, 100000000L));
      app.add_flag(
          "!--no-calibrate", settings->calibrate,
          "evaluate with the marker set as it is (default: calibrate the subject first, as s2kf track does)");
      app.add_flag(
          "!--uniform-noise", settings->noise_from_calibration,
          "give every marker the same noise (default: after calibrating, each marker's noise follows its "
          "calibration residual, 0.5-2 times the common 10 mm)");
      app.add_flag("--quiet", settings->quiet, "print nothing but errors");
      app.add_option("--motion", settings->motion,
                     "simulate this bundled motion (or motion .json) on a realistic subject instead of "
                     "reading a recording; adds the references a known subject allows (true subject, "
                     "identifiable subject, best constant placement, calibration at the true poses, "
                     "the S2KF itself with the true subject)");
      app.add_option("--subject-seed", settings->subject_seed,
                     "seed of the simulated subject and its sensor noise (default 1)");
      app.add_option("--occlusion", settings->occlusion,
                     "random occlusion p,lambda of the simulated recording (the paper: 0.005,100)");
      app.add_option("--motion-model", settings->motion_model,
                     "S2KF system model: random-walk (default) or constant-velocity")
          ->check(CLI::IsMember({"random-walk", "constant-velocity"}));
      app.add_option("--gain", settings->gain,
                     "S2KF update: information-form (default: the 46 x 46 state system and each body "
                     "part's block of the innovation covariance) or square-root (the whole innovation "
                     "covariance factorised) or information-form-root-products (also the second order of the "
                     "root's orientation, which the parts share)")
          ->check(CLI::IsMember({"information-form", "square-root", "information-form-root-products"}));
      app.add_flag("--smooth", settings->smooth,
                   "also track with the RTS smoother and compare it with the truth");
      app.callback([settings] { run_evaluate(*settings); });
    }};

}  // namespace
}  // namespace s2kf::cli
