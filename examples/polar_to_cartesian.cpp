// Estimating a 2-D position from range and bearing with the S2KF: a nonlinear measurement model
// evaluated for all samples in one call, compared with the UKF-sized set.
//   ./build/examples/example_polar_to_cartesian
#include <s2kf/core/gaussian.hpp>
#include <s2kf/core/sample_set.hpp>
#include <s2kf/core/smart_sampling_kalman_filter.hpp>
#include <s2kf/io/sample_cache.hpp>

#include <cmath>
#include <cstdio>

int main() {
  // Range/bearing of a target, vectorised over the sample columns.
  auto range_bearing = [](const Eigen::MatrixXd& x, Eigen::MatrixXd& y) {
    y.row(0) = x.colwise().norm();
    for (Eigen::Index i = 0; i < x.cols(); ++i) y(1, i) = std::atan2(x(1, i), x(0, i));
  };
  const Eigen::Vector2d truth(80.0, 60.0);
  Eigen::Vector2d measured(truth.norm() + 0.5, std::atan2(truth.y(), truth.x()) - 0.01);
  const Eigen::Matrix2d noise = Eigen::Vector2d(1.0, 0.02 * 0.02).asDiagonal();

  for (const char* name : {"ukf", "lcd"}) {
    const bool lcd = std::string(name) == "lcd";
    s2kf::S2kf filter(lcd ? s2kf::lcd_sample_set(2, 51).set : s2kf::ukf_sample_set(2));
    s2kf::GaussianXd estimate(Eigen::Vector2d(60.0, 60.0), 400.0 * Eigen::Matrix2d::Identity());
    const s2kf::UpdateResult result = filter.update(estimate, range_bearing, measured, noise);
    if (!result.ok()) {
      std::fprintf(stderr, "update failed: %s\n", s2kf::to_string(result.status));
      return 1;
    }
    std::printf("%s (%2d samples): estimate (%.2f, %.2f), NIS %.2f\n", name,
                static_cast<int>(filter.samples().count()), estimate.mean(0), estimate.mean(1), result.nis);
  }
  return 0;
}
