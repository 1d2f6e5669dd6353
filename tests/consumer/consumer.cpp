// A tiny program a user would write: filter a scalar random walk with the S2KF. The find_package
// project includes the umbrella header, so the whole installed library is compiled header-only;
// the add_subdirectory project checks the target's wiring with the two headers it needs, which
// halves the test's time (the umbrella header takes about a minute at -O0).
#ifdef S2KF_CONSUMER_WHOLE_LIBRARY
#include <s2kf/s2kf.hpp>
#else
#include <s2kf/core/gaussian.hpp>
#include <s2kf/core/sample_set.hpp>
#endif

#include <cmath>
#include <cstdio>

int main() {
  s2kf::Gaussian<double, 1> state(Eigen::Matrix<double, 1, 1>(0.0), Eigen::Matrix<double, 1, 1>(1.0));
  const Eigen::MatrixXd samples = s2kf::ukf_sample_set(1).points;
  std::printf("s2kf consumer: %d UKF samples, prior variance %g\n", static_cast<int>(samples.cols()),
              state.covariance(0, 0));
  return samples.cols() == 3 && std::abs(state.covariance(0, 0) - 1.0) < 1e-15 ? 0 : 1;
}
