/// @file
/// The tuning of the whole-body tracker: noise levels, sample count, initialisation, and the
/// presets ("default", chosen by measurement on the synthetic recordings, and "paper").
#pragma once

#include <cmath>
#include <s2kf/core/compilation_mode.hpp>
#include <stdexcept>
#include <string>
#include <vector>

namespace s2kf::track {

/// Noise levels are given per second of motion and converted per frame with the recording's rate,
/// so the same options track at 100 Hz and at 240 Hz: a random walk whose per-frame standard
/// deviation is speed / rate follows a motion of about that speed.
/// How the state moves between frames. random_walk: x_{k+1} = x_k + w (the paper's). constant_velocity:
/// the state also holds the pose's rate of change v, x_{k+1} = x_k + dt v_k, v_{k+1} = v_k, both
/// disturbed by white-noise acceleration (and x by the random walk's noise as well).
enum class MotionModel { random_walk, constant_velocity };

inline MotionModel motion_model_from_name(const std::string& name) {
  if (name == "random-walk") return MotionModel::random_walk;
  if (name == "constant-velocity") return MotionModel::constant_velocity;
  throw std::invalid_argument("unknown motion model '" + name + "' (use random-walk or constant-velocity)");
}

inline std::string to_string(MotionModel model) {
  return model == MotionModel::random_walk ? "random-walk" : "constant-velocity";
}

struct TrackerOptions {
  int samples = 301;  ///< S2KF sample count L (odd: symmetric set plus the origin)

  MotionModel motion_model = MotionModel::random_walk;
  /// Constant velocity: spectral density sqrt(q) of the white-noise acceleration of the root
  /// position (mm s^-1.5), orientation (rad s^-1.5) and Theta (s^-1.5); over one frame of dt the
  /// velocity's SD grows by sqrt(q dt), and Q = q [dt^3/3, dt^2/2; dt^2/2, dt] per component.
  /// The defaults are the best levels tried; larger ones let the rates chase soft tissue.
  double position_acceleration = 100.0;
  double orientation_acceleration = 1.0;
  double joint_acceleration = 1.0;
  /// Constant velocity: SD of the velocity when tracking starts (the pose's units per second).
  double initial_position_rate_sd = 1000.0;
  double initial_orientation_rate_sd = 3.0;
  double initial_joint_rate_sd = 4.0;

  double marker_noise_mm =
      10.0;  ///< per-coordinate SD of a marker against the model (placement, soft tissue, noise)
  /// Per model marker SD (mm) in place of marker_noise_mm, e.g. a marker set's `noise_mm` for a
  /// marker on loose skin; empty: marker_noise_mm for every marker. NaN entries take marker_noise_mm.
  std::vector<double> marker_noise_mm_per_marker;

  double position_speed_mm_per_s = 1500.0;   ///< random-walk SD of the root position per second
  double orientation_speed_rad_per_s = 6.0;  ///< random-walk SD of the root orientation per second
  /// Random-walk SD per second of the joint parameters Theta: of the limbs' flexion/extension
  /// (body::is_limb_flexion: shoulders, elbows, hips, knees and ankles about x), and of every other
  /// joint (the twists, ab/adduction, the spine, neck and wrists). The others move slower and a
  /// lone visible marker's soft tissue would turn them under a looser walk (docs/tracking.md).
  double flexion_speed_per_s = 8.0;
  double joint_speed_per_s = 4.0;

  double initial_position_sd_mm = 150.0;  ///< around the rigid fit of the first frame
  double initial_orientation_sd_rad = 0.3;
  double initial_joint_sd = 0.5;  ///< in Theta units (radians of the sine argument)

  int min_markers_to_start = 8;   ///< first frame with this many visible mapped markers initialises
  int initial_iterations = 10;    ///< posterior-linearisation passes on the first frame
  int converging_frames = 5;      ///< frames after the first that still use iterated updates
  int converging_iterations = 3;  ///< passes per update during those frames

  double gate_probability = 0;  ///< 0: off; else reject a whole frame whose NIS is beyond this quantile

  /// Sum the update's sample moments Cyy, Cyx in single precision from deviations formed in double
  /// (UpdateOptions::single_precision_moments); factorisation, gain and update stay in double.
  /// A quarter of the rank update's time, with an effect far below the marker noise.
  bool single_precision_moments = true;
  /// The update's gain in information form (UpdateOptions::information_form): the state's 46 x 46
  /// information matrix solved instead of the 150 x 150 innovation covariance, and Cyy formed only
  /// within each body part (the pelvis, the upper body, each leg: Tracker's information groups).
  /// It leaves out only the correlation between body parts of the predictions' nonlinear parts
  /// (the first, iterated frames and the calibration's tracking pass always use the ordinary
  /// update). On by default: faster than the exact gain and as accurate (docs/tracking.md, "The gain").
  bool information_form_update = true;
  /// UpdateOptions::information_form_max_nonlinearity: a frame in which two body parts' predicted
  /// spreads that the linearisation does not explain exceed this multiple of their noise variance
  /// (their geometric mean; a wide prior over a curved model: a segment hidden for a while, a fast
  /// motion) is updated the ordinary way. 2 sits above steady tracking (1.1-1.8 for the parts with
  /// hands) and keeps the accuracy within 1 % of the ordinary update's.
  double information_form_max_nonlinearity = 2.0;
  /// The information form regresses the predictions on the products of the root's orientation
  /// error as well (UpdateOptions::information_quadratic_states): the second order of the
  /// orientation, which every body part shares, is then kept instead of left out with the other
  /// cross-part correlations.
  bool information_form_root_products = false;
  /// Tell the update which states each marker depends on (UpdateOptions::block_dependencies: the
  /// root's pose and the joints between the root and the marker's segment). A joint that no
  /// visible marker depends on (a hand whose markers are all hidden) is then moved only through
  /// its prior correlation with the joints the markers see, not by the sample set's spurious
  /// cross-covariance, which would drift it steadily.
  bool marker_dependencies = true;

  /// After every update each joint's Theta is kept learnable (keep_joint_parameters_learnable):
  /// its mean at least this far (rad) inside +-pi/2, where the sine's slope vanishes and a joint
  /// that reached its limit would stay there whatever the markers show; and its SD at most
  /// joint_parameter_max_sd. 0 disables either bound. 0.1 rad keeps a joint within 0.5 % of its
  /// half range of the limit, with a tenth of the sine's slope left to come back by.
  double joint_parameter_margin = 0.1;
  double joint_parameter_max_sd = 0.5;
  /// Forward kinematics of the samples in single precision
  /// (MarkerMeasurementModel::set_single_precision): off, because float rounds lab coordinates
  /// to about 1e-4 mm, not small against the samples' spread along well-determined directions.
  bool single_precision_kinematics = false;
  /// The samples' forward kinematics as deviations from the mean pose's
  /// (MarkerMeasurementModel::set_single_precision_deviations): the mean pose in double, each
  /// sample's difference from it in float, which rounds it relative to its own size (about 1e-7
  /// of it, as the single-precision moments round it anyway) and computes the sine and cosine in
  /// float: the model in 62 instead of 89 us at L = 301 with AVX2 (docs/benchmarks.md), the same
  /// motion to rounding.
  bool single_precision_kinematic_deviations = true;

  /// Per-marker gate: a marker whose innovation is beyond this chi-square quantile (3 degrees of
  /// freedom) of its predicted covariance is left out of the frame's update, so a mislabelled,
  /// swapped or jumping marker does not pull the pose (FrameEstimate::rejected_markers); 0: off.
  double marker_gate_probability = 0.99999;
  /// A marker whose coordinates repeat exactly for this long (s) while the body moves is stuck (a
  /// real marker's coordinates always carry some noise) and is left out until it moves; 0: off.
  double frozen_marker_s = 0.1;

  /// Two stacked twists of the spine (BPz, BTz) and of the neck (BLNz, BUNz) are seen by the
  /// markers only through their sum; each frame a pseudo-measurement that the two angles are equal,
  /// with this SD (rad), splits the sum evenly, so the answer is unique and smooth instead of
  /// wandering along the unseen difference; 0: off.
  double axial_split_sd_rad = 0.05;

  /// Initialise the root pose by a rigid fit of the first frame's markers to the model (true), or
  /// as the paper does: position = mean of the markers, orientation = 0 (false).
  bool rigid_initialisation = true;

  /// Start every joint near the zero pose (standing), a little inside a limit that lies at zero so
  /// sin still has slope there (true); or at mid-range, Theta = 0, as the paper does (false).
  bool joints_start_near_zero_pose = true;

  /// The preset these options came from, for reports only: no behaviour depends on it (a preset
  /// is expanded into the fields above).
  std::string preset = "default";

  void validate() const {
    if (samples < 3) throw std::invalid_argument("the sample count must be at least 3");
    if (!(marker_noise_mm > 0)) throw std::invalid_argument("the marker noise must be positive");
    for (double sd : marker_noise_mm_per_marker)
      if (!std::isnan(sd) && !(sd > 0 && std::isfinite(sd)))
        throw std::invalid_argument("every per-marker noise must be a positive number of mm");
    if (!(position_speed_mm_per_s >= 0 && orientation_speed_rad_per_s >= 0 && joint_speed_per_s >= 0 &&
          flexion_speed_per_s >= 0 && position_acceleration >= 0 && orientation_acceleration >= 0 &&
          joint_acceleration >= 0))
      throw std::invalid_argument("process noise levels must not be negative");
    if (!(initial_position_rate_sd > 0 && initial_orientation_rate_sd > 0 && initial_joint_rate_sd > 0))
      throw std::invalid_argument("initial standard deviations must be positive");
    if (min_markers_to_start < 3) throw std::invalid_argument("at least 3 markers are needed to start");
    if (initial_iterations < 1 || converging_iterations < 1 || converging_frames < 0)
      throw std::invalid_argument("iteration counts must be at least 1");
    if (!(initial_position_sd_mm > 0 && initial_orientation_sd_rad > 0 && initial_joint_sd > 0))
      throw std::invalid_argument("initial standard deviations must be positive");
    if (!(gate_probability >= 0 && gate_probability < 1))
      throw std::invalid_argument("the gate probability must be in [0, 1)");
    if (!(marker_gate_probability >= 0 && marker_gate_probability < 1))
      throw std::invalid_argument("the marker gate probability must be in [0, 1)");
    if (!(axial_split_sd_rad >= 0 && std::isfinite(axial_split_sd_rad)))
      throw std::invalid_argument("the axial-split SD must be a non-negative number of radians");
    if (!(information_form_max_nonlinearity >= 0))
      throw std::invalid_argument("the information form's nonlinearity limit must not be negative");
    if (!(joint_parameter_margin >= 0 && joint_parameter_margin < 1.5 && joint_parameter_max_sd >= 0 &&
          std::isfinite(joint_parameter_max_sd)))
      throw std::invalid_argument(
          "the joint-parameter margin must lie in [0, 1.5) rad and its largest SD be a non-negative number");
    if (!(frozen_marker_s >= 0 && std::isfinite(frozen_marker_s)))
      throw std::invalid_argument("the frozen-marker time must be a non-negative number of seconds");
  }
};

/// The gain by its command-line name: information-form (TrackerOptions' default), square-root, or
/// information-form-root-products (information_form_update, information_form_root_products).
inline void set_gain_from_name(TrackerOptions& options, const std::string& name) {
  if (name != "information-form" && name != "square-root" && name != "information-form-root-products")
    throw std::invalid_argument("unknown gain '" + name +
                                "' (use information-form, square-root or information-form-root-products)");
  options.information_form_update = name != "square-root";
  options.information_form_root_products = name == "information-form-root-products";
}

inline std::string gain_name(const TrackerOptions& options) {
  if (!options.information_form_update) return "square-root";
  return options.information_form_root_products ? "information-form-root-products" : "information-form";
}

/// The seed paper's numbers (its section 5), read with R in m^2 (1e-4 m^2 = (10 mm)^2),
/// Q_r = 25 mm^2 per frame, and 1e-10 for orientation and joints per frame; initial orientation 0
/// with variance 1e-6, joints at mid-range with variance 1e-10, root from the marker mean. They are
/// kept for comparison: with them the joints can barely move.
TrackerOptions paper_preset(double rate_hz);

TrackerOptions preset_options(const std::string& name, double rate_hz);

}  // namespace s2kf::track

#if !defined(S2KF_COMPILED)
#include <s2kf/track/tracker_options.hxx>
#endif
