// The RTS smoother against the batch answer: for a linear-Gaussian random walk with direct noisy
// measurements, the smoothed mean and covariance of every step are the marginals of the joint
// posterior over all steps, which a dense information-form solve gives independently.
#include <s2kf/core/rts_smoother.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <random>
#include <vector>

namespace {

using namespace s2kf;

struct LinearProblem {
  Eigen::VectorXd prior_mean;
  Eigen::MatrixXd prior_covariance, q, r;
  std::vector<Eigen::VectorXd> y;  // measurement of the whole state per step; empty: none
};

LinearProblem make_problem(int steps, std::uint32_t seed, bool correlated_q = true) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  LinearProblem p;
  p.prior_mean = Eigen::Vector3d(1, -2, 0.5);
  p.prior_covariance = Eigen::Matrix3d::Identity() * 4;
  p.prior_covariance(0, 1) = p.prior_covariance(1, 0) = 1;
  p.q = Eigen::Vector3d(0.3, 0.05, 1.0).asDiagonal();
  if (correlated_q) p.q(0, 2) = p.q(2, 0) = 0.1;
  p.r = Eigen::Vector3d(0.5, 2.0, 0.2).asDiagonal();
  Eigen::VectorXd x = p.prior_mean;
  for (int k = 0; k < steps; ++k) {
    if (k > 0)
      x += Eigen::Vector3d(normal(rng), normal(rng), normal(rng)).cwiseProduct(p.q.diagonal().cwiseSqrt());
    if (k % 4 == 2) {
      p.y.emplace_back();  // a step without measurement: prediction only
    } else {
      p.y.push_back(
          x +
          Eigen::Vector3d(normal(rng), normal(rng), normal(rng)).cwiseProduct(p.r.diagonal().cwiseSqrt()));
    }
  }
  return p;
}

/// The ordinary Kalman filter, written out here so the smoother is checked against independent code.
std::vector<GaussianXd> kalman_filter(const LinearProblem& p) {
  std::vector<GaussianXd> out;
  Eigen::VectorXd m = p.prior_mean;
  Eigen::MatrixXd c = p.prior_covariance;
  for (std::size_t k = 0; k < p.y.size(); ++k) {
    if (k > 0) c += p.q;
    if (p.y[k].size() > 0) {
      const Eigen::MatrixXd s = c + p.r;
      const Eigen::MatrixXd gain = c * s.inverse();
      m += gain * (p.y[k] - m);
      c = (Eigen::MatrixXd::Identity(3, 3) - gain) * c;
      c = 0.5 * (c + c.transpose()).eval();
    }
    out.emplace_back(m, c);
  }
  return out;
}

/// Joint posterior of x_0..x_{N-1}: information matrix and vector, solved densely.
std::vector<GaussianXd> batch_posterior(const LinearProblem& p) {
  const int n = 3, steps = static_cast<int>(p.y.size());
  Eigen::MatrixXd info = Eigen::MatrixXd::Zero(n * steps, n * steps);
  Eigen::VectorXd vec = Eigen::VectorXd::Zero(n * steps);
  const Eigen::MatrixXd p0i = p.prior_covariance.inverse(), qi = p.q.inverse(), ri = p.r.inverse();
  info.block(0, 0, n, n) += p0i;
  vec.segment(0, n) += p0i * p.prior_mean;
  for (int k = 0; k + 1 < steps; ++k) {  // x_{k+1} - x_k ~ N(0, Q)
    info.block(n * k, n * k, n, n) += qi;
    info.block(n * (k + 1), n * (k + 1), n, n) += qi;
    info.block(n * k, n * (k + 1), n, n) -= qi;
    info.block(n * (k + 1), n * k, n, n) -= qi;
  }
  for (int k = 0; k < steps; ++k)
    if (p.y[k].size() > 0) {
      info.block(n * k, n * k, n, n) += ri;
      vec.segment(n * k, n) += ri * p.y[k];
    }
  const Eigen::MatrixXd covariance = info.inverse();
  const Eigen::VectorXd mean = covariance * vec;
  std::vector<GaussianXd> out;
  for (int k = 0; k < steps; ++k)
    out.emplace_back(mean.segment(n * k, n), covariance.block(n * k, n * k, n, n));
  return out;
}

TEST(RtsSmoother, EqualsTheBatchPosteriorOfALinearRandomWalk) {
  const LinearProblem p = make_problem(25, 7);
  const std::vector<GaussianXd> filtered = kalman_filter(p);
  const std::vector<GaussianXd> smoothed = rts_smooth_random_walk(filtered, p.q);
  const std::vector<GaussianXd> batch = batch_posterior(p);
  ASSERT_EQ(smoothed.size(), batch.size());
  for (std::size_t k = 0; k < batch.size(); ++k) {
    EXPECT_LT((smoothed[k].mean - batch[k].mean).cwiseAbs().maxCoeff(), 1e-9) << "step " << k;
    EXPECT_LT((smoothed[k].covariance - batch[k].covariance).cwiseAbs().maxCoeff(), 1e-9) << "step " << k;
  }
  // The last step is the filtered one; earlier steps are strictly more certain than filtered.
  EXPECT_LT((smoothed.back().mean - filtered.back().mean).norm(), 1e-12);
  EXPECT_LT(smoothed[10].covariance.trace(), filtered[10].covariance.trace() - 1e-3);
}

TEST(RtsSmoother, UsesTheChartChangeBetweenSteps) {
  // The same filter run, but every odd step stores its state with the first component negated
  // (as the tracker's re-centring reflects a joint parameter); the chart change undoes that. Q is
  // diagonal, as the tracker's, so it reads the same in both charts.
  const LinearProblem p = make_problem(18, 11, false);
  std::vector<GaussianXd> filtered = kalman_filter(p);
  const std::vector<GaussianXd> batch = batch_posterior(p);
  Eigen::MatrixXd flip = Eigen::MatrixXd::Identity(3, 3);
  flip(0, 0) = -1;
  for (std::size_t k = 1; k < filtered.size(); k += 2) {
    filtered[k].mean = flip * filtered[k].mean;
    filtered[k].covariance = flip * filtered[k].covariance * flip;
  }
  int calls = 0;
  const auto smoothed =
      rts_smooth_random_walk(filtered, p.q, [&](std::size_t, Eigen::VectorXd& m, Eigen::MatrixXd& c) {
        ++calls;  // neighbouring steps always differ by the flip
        m = flip * m;
        c = flip * c * flip;
      });
  EXPECT_EQ(calls, static_cast<int>(filtered.size()) - 1);
  for (std::size_t k = 0; k < batch.size(); ++k) {
    const Eigen::MatrixXd f = k % 2 ? flip : Eigen::MatrixXd::Identity(3, 3);
    EXPECT_LT((f * smoothed[k].mean - batch[k].mean).cwiseAbs().maxCoeff(), 1e-9) << "step " << k;
    EXPECT_LT((f * smoothed[k].covariance * f - batch[k].covariance).cwiseAbs().maxCoeff(), 1e-9);
  }
}

TEST(RtsSmoother, RejectsAProcessNoiseOfTheWrongSize) {
  const std::vector<GaussianXd> filtered = {
      GaussianXd(Eigen::VectorXd::Zero(2), Eigen::MatrixXd::Identity(2, 2))};
  EXPECT_THROW(rts_smooth_random_walk(filtered, Eigen::MatrixXd::Identity(3, 3)), DimensionError);
  EXPECT_TRUE(rts_smooth_random_walk(std::vector<GaussianXd>{}, Eigen::MatrixXd::Identity(3, 3)).empty());
}

}  // namespace

namespace {

// A constant-velocity model in two dimensions: state [x, y, vx, vy], x_{k+1} = A x_k + w with
// A = [I dt I; 0 I] and the white-noise-acceleration Q; the positions are measured, the velocities
// never. The linear RTS smoother must give the marginals of the batch posterior.
TEST(RtsSmoother, EqualsTheBatchPosteriorOfAConstantVelocityModel) {
  const int n = 4, steps = 30;
  const double dt = 0.1, q = 2.0;
  Eigen::MatrixXd a = Eigen::MatrixXd::Identity(n, n);
  a(0, 2) = a(1, 3) = dt;
  Eigen::MatrixXd qm = Eigen::MatrixXd::Zero(n, n);
  for (int k = 0; k < 2; ++k) {
    qm(k, k) = q * dt * dt * dt / 3;
    qm(k, k + 2) = qm(k + 2, k) = q * dt * dt / 2;
    qm(k + 2, k + 2) = q * dt;
  }
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(2, n);
  h(0, 0) = h(1, 1) = 1;
  const Eigen::Matrix2d r = Eigen::Vector2d(0.05, 0.2).asDiagonal();
  const Eigen::VectorXd m0 = (Eigen::VectorXd(n) << 0, 1, 2, -1).finished();
  const Eigen::MatrixXd p0 = Eigen::VectorXd::Constant(n, 1.5).asDiagonal();
  std::mt19937 rng(3);
  std::normal_distribution<double> normal;
  Eigen::VectorXd x = m0;
  std::vector<Eigen::VectorXd> y;
  for (int k = 0; k < steps; ++k) {
    if (k > 0)
      x = a * x + qm.llt().matrixL() * Eigen::Vector4d(normal(rng), normal(rng), normal(rng), normal(rng));
    y.push_back(h * x + Eigen::Vector2d(normal(rng) * std::sqrt(0.05), normal(rng) * std::sqrt(0.2)));
  }
  // The Kalman filter, written out.
  std::vector<GaussianXd> filtered;
  Eigen::VectorXd m = m0;
  Eigen::MatrixXd c = p0;
  for (int k = 0; k < steps; ++k) {
    if (k > 0) m = a * m, c = a * c * a.transpose() + qm;
    const Eigen::MatrixXd s = h * c * h.transpose() + r;
    const Eigen::MatrixXd gain = c * h.transpose() * s.inverse();
    m += gain * (y[k] - h * m);
    c -= gain * s * gain.transpose();
    c = 0.5 * (c + c.transpose()).eval();
    filtered.emplace_back(m, c);
  }
  // The batch posterior in information form.
  Eigen::MatrixXd info = Eigen::MatrixXd::Zero(n * steps, n * steps);
  Eigen::VectorXd vec = Eigen::VectorXd::Zero(n * steps);
  const Eigen::MatrixXd qi = qm.inverse(), ri = r.inverse(), p0i = p0.inverse();
  info.topLeftCorner(n, n) += p0i;
  vec.head(n) += p0i * m0;
  for (int k = 0; k + 1 < steps; ++k) {  // x_{k+1} - A x_k ~ N(0, Q)
    info.block(n * k, n * k, n, n) += a.transpose() * qi * a;
    info.block(n * (k + 1), n * (k + 1), n, n) += qi;
    info.block(n * k, n * (k + 1), n, n) -= a.transpose() * qi;
    info.block(n * (k + 1), n * k, n, n) -= qi * a;
  }
  for (int k = 0; k < steps; ++k) {
    info.block(n * k, n * k, n, n) += h.transpose() * ri * h;
    vec.segment(n * k, n) += h.transpose() * ri * y[k];
  }
  const Eigen::MatrixXd covariance = info.inverse();
  const Eigen::VectorXd mean = covariance * vec;
  const std::vector<GaussianXd> smoothed = rts_smooth_linear(filtered, a, qm);
  ASSERT_EQ(smoothed.size(), static_cast<std::size_t>(steps));
  for (int k = 0; k < steps; ++k) {
    EXPECT_LT((smoothed[k].mean - mean.segment(n * k, n)).cwiseAbs().maxCoeff(), 1e-8) << "step " << k;
    EXPECT_LT((smoothed[k].covariance - covariance.block(n * k, n * k, n, n)).cwiseAbs().maxCoeff(), 1e-8)
        << "step " << k;
  }
  // The unmeasured velocity is where smoothing helps most.
  EXPECT_LT(smoothed[5].covariance(2, 2), 0.8 * filtered[5].covariance(2, 2));
  EXPECT_THROW(rts_smooth_linear(filtered, Eigen::MatrixXd::Identity(3, 3), qm), DimensionError);
}

}  // namespace
