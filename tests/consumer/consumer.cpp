// A tiny program a user would write: filter a scalar random walk with the S2KF. Both outside
// projects (find_package and add_subdirectory) check the wiring of the target (include paths,
// Eigen, Threads, C++17) with the two headers the program needs. Every definition is compiled by
// the project's own build (the library s2kf_compiled, one unit per concept folder).
#include <s2kf/core/gaussian.hpp>
#include <s2kf/core/sample_set.hpp>

#include <cmath>
#include <cstdio>

int main() {
  s2kf::Gaussian<double, 1> state(Eigen::Matrix<double, 1, 1>(0.0), Eigen::Matrix<double, 1, 1>(1.0));
  const Eigen::MatrixXd samples = s2kf::ukf_sample_set(1).points;
  std::printf("s2kf consumer: %d UKF samples, prior variance %g\n", static_cast<int>(samples.cols()),
              state.covariance(0, 0));
  return samples.cols() == 3 && std::abs(state.covariance(0, 0) - 1.0) < 1e-15 ? 0 : 1;
}
