// A tiny program a user would write: filter a scalar random walk with the S2KF.
#include <s2kf/s2kf.hpp>

#include <cmath>
#include <cstdio>

int main() {
  s2kf::Gaussian<double, 1> state(Eigen::Matrix<double, 1, 1>(0.0), Eigen::Matrix<double, 1, 1>(1.0));
  const Eigen::MatrixXd samples = s2kf::ukf_sample_set(1).points;
  std::printf("s2kf consumer: %d UKF samples, prior variance %g\n", static_cast<int>(samples.cols()),
              state.covariance(0, 0));
  return samples.cols() == 3 && std::abs(state.covariance(0, 0) - 1.0) < 1e-15 ? 0 : 1;
}
