/// @file
/// The LCD distance between an equally weighted Dirac mixture and the standard normal N(0, I), and
/// the objective -2 D2 + D3 with its analytic gradient, for a general set and for the symmetric
/// half-sample form {+s_k, -s_k} (+ origin) that the S2KF optimises.
#pragma once

#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/core/constants.hpp>
#include <s2kf/core/error.hpp>
#include <s2kf/core/exponential_integral.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

namespace s2kf {

/// The largest kernel width bMax of the LCD distance by dimension N (the Nonlinear Estimation
/// Toolbox's table): 1 -> 5; 2..10 -> 10; 11..100 -> 50; 101..1000 -> 100; above -> 200.
inline double default_bmax(int dimension) {
  if (dimension < 1) throw DimensionError("default_bmax: the dimension must be at least 1");
  if (dimension == 1) return 5.0;
  if (dimension <= 10) return 10.0;
  if (dimension <= 100) return 50.0;
  if (dimension <= 1000) return 100.0;
  return 200.0;
}

/// The default number of samples: 10 N rounded up to the next odd number (N = 46 gives 461). Odd,
/// so that the symmetric set contains the origin.
inline int default_sample_count(int dimension) {
  if (dimension < 1) throw DimensionError("default_sample_count: the dimension must be at least 1");
  const int count = 10 * dimension;
  return count % 2 == 0 ? count + 1 : count;
}

namespace detail {

/// Gauss-Legendre nodes and weights on [-1, 1], by Newton's method on P_n from the Chebyshev-like
/// initial guesses (exact to rounding for the small n used here).
void gauss_legendre(int n, std::vector<double>& nodes, std::vector<double>& weights);

/// A composite Gauss-Legendre rule on [0, bmax]: subintervals [0, 1/2], [1/2, 1], [1, 2], ... that
/// double in length up to bmax, with `per_interval` nodes each. The integrands of the LCD distance
/// are analytic with their nearest singularities at b = +-i/sqrt(2) (from 1 + 2 b^2 = 0) or +-i (from
/// 1 + b^2), so each doubling interval sees them at a fixed relative distance and the rule converges
/// geometrically on every interval alike, however large bmax is.
void lcd_b_rule(double bmax, int per_interval, std::vector<double>& nodes, std::vector<double>& weights);

/// Power series of phi(x) = exp(-x) - x E1(x) without its x ln x part:
/// phi(x) = x ln x + sum_m p_m x^m, p_0 = 1, p_1 = gamma - 1, p_m = (-1)^m (1/m! - 1/((m-1)(m-1)!)).
template <std::size_t Terms>
constexpr std::array<double, Terms> phi_series_coefficients() {
  std::array<double, Terms> p{};
  p[0] = 1.0;
  if (Terms > 1) p[1] = euler_gamma - 1.0;
  double factorial = 1.0;  // (m-1)!
  for (std::size_t m = 2; m < Terms; ++m) {
    const double previous = factorial;  // (m-1)!
    factorial *= static_cast<double>(m);
    const double sign = (m % 2 == 0) ? 1.0 : -1.0;
    p[m] = sign * (1.0 / factorial - 1.0 / (static_cast<double>(m - 1) * previous));
  }
  return p;
}

template <std::size_t Terms>
inline double phi_series_sum(double x) {
  static constexpr std::array<double, Terms> p = phi_series_coefficients<Terms>();
  double sum = p[Terms - 1];
  for (std::size_t k = Terms - 1; k-- > 0;) sum = p[k] + x * sum;
  return sum;
}

/// phi(x) = exp(-x) - x E1(x) and E1(x) for x > 0 with one logarithm (x <= 1) or one exponential
/// (x > 1). The pairwise term of the LCD distance is g(s) = a/8 phi(s/a) with a = 4 bmax^2 and its
/// derivative g'(s) = -E1(s/a)/8, so both come out of one call.
inline void phi_and_e1(double x, double& phi, double& e1) {
  if (x <= 1.0) {
    const double log_x = std::log(x);
    if (x <= 0.125) {
      // Degree 11: 0.125^12/12! ~ 1.4e-20.
      e1 = e1_series_remainder(x) - log_x;
      phi = x * log_x + phi_series_sum<12>(x);
    } else {
      e1 = e1_series_remainder(x) - log_x;
      phi = x * log_x + phi_series_sum<21>(x);
    }
    return;
  }
  if (x > 745.0) {
    phi = 0.0;
    e1 = 0.0;
    return;
  }
  const double exp_minus_x = std::exp(-x);
  const double fraction = e1_continued_fraction(x) / exp_minus_x;  // E1(x) exp(x)
  e1 = fraction * exp_minus_x;
  phi = exp_minus_x * (1.0 - x * fraction);
}

}  // namespace detail

/// The LCD distance D = D1 - 2 D2 + D3 (spec section 2) between N(0, I) in `dimension` dimensions
/// and equally weighted Dirac mixtures, for one kernel-width limit bmax. Precomputes the b-quadrature
/// once; keeps a workspace so that repeated evaluations (an optimiser's) do not allocate once the
/// sizes are settled. Not thread-safe: use one object per thread.
class LcdObjective {
 public:
  /// `nodes_per_interval` Gauss-Legendre nodes on each doubling subinterval of [0, bmax]; 16 gives
  /// a relative error near 1e-14 for the D2 integrals over the radii that occur (see the tests).
  LcdObjective(int dimension, double bmax, int nodes_per_interval = 16) : dimension_(dimension), bmax_(bmax) {
    if (dimension < 1) throw DimensionError("LcdObjective: the dimension must be at least 1");
    if (!(bmax > 0.0) || !std::isfinite(bmax))
      throw DimensionError("LcdObjective: bmax must be a positive finite number");
    if (nodes_per_interval < 2) throw DimensionError("LcdObjective: need at least 2 quadrature nodes");
    scale_ = 4.0 * bmax * bmax;
    std::vector<double> nodes, weights;
    detail::lcd_b_rule(bmax, nodes_per_interval, nodes, weights);
    const double half_n = 0.5 * dimension;
    for (std::size_t j = 0; j < nodes.size(); ++j) {
      const double b = nodes[j];
      const double two_b2 = 2.0 * b * b;
      const double c = std::pow(two_b2 / (1.0 + two_b2), half_n) * b;  // c(b) of D2
      const double q = 0.5 / (1.0 + two_b2);                           // exp(-r q) in D2
      if (weights[j] * c == 0.0) continue;  // b^(N+1) underflows near 0 for large N
      exponent_.push_back(q);
      weight_c_.push_back(weights[j] * c);
      weight_cq_.push_back(weights[j] * c * q);
    }
    // D1 = bmax^2/2 - int_0^bmax (1 - (b^2/(1+b^2))^(N/2)) b db: the quadrature only sees the small
    // deficit (order N ln bmax), so its rounding stays far below D. Twice the nodes: computed once.
    detail::lcd_b_rule(bmax, 2 * nodes_per_interval, nodes, weights);
    double deficit = 0.0;
    for (std::size_t j = 0; j < nodes.size(); ++j) {
      const double b = nodes[j];
      const double ratio = b * b / (1.0 + b * b);
      // 1 - ratio^(N/2) without cancellation: -expm1(N/2 ln ratio).
      deficit += weights[j] * (-std::expm1(half_n * std::log(ratio))) * b;
    }
    d1_ = 0.5 * bmax * bmax - deficit;
  }

  int dimension() const { return dimension_; }
  double bmax() const { return bmax_; }
  /// The constant part D1 of the distance (about bmax^2/2, far larger than D itself).
  double d1() const { return d1_; }
  /// Number of b-nodes of the D2 quadrature (cost per sample of one evaluation).
  std::size_t quadrature_nodes() const { return exponent_.size(); }

  /// h(r) = int_0^bmax c(b) exp(-r/(2(1+2b^2))) db and hq(r) = int c(b)/(2(1+2b^2)) exp(..) db
  /// = -h'(r), for the squared radius r = ||x||^2 of one sample.
  void radial_integrals(double r, double& h, double& hq) const {
    double sum_h = 0.0, sum_hq = 0.0;
    const std::size_t n = exponent_.size();
    for (std::size_t j = 0; j < n; ++j) {
      const double e = std::exp(-r * exponent_[j]);
      sum_h += weight_c_[j] * e;
      sum_hq += weight_cq_[j] * e;
    }
    h = sum_h;
    hq = sum_hq;
  }

  /// g(s) = bmax^2/2 exp(-s/(4 bmax^2)) + s/8 Ei(-s/(4 bmax^2)) and g'(s) = Ei(-s/(4 bmax^2))/8 for
  /// a squared distance s >= 0. At s = 0, g = bmax^2/2 and g' is reported as 0: it is -inf there, but
  /// it always multiplies a difference vector of length sqrt(s) = 0 and the product tends to 0.
  void pair_kernel(double s, double& g, double& dg) const {
    if (s <= 0.0) {
      g = 0.125 * scale_;
      dg = 0.0;
      return;
    }
    double phi, e1;
    detail::phi_and_e1(s / scale_, phi, e1);
    g = 0.125 * scale_ * phi;
    dg = -0.125 * e1;
  }

  /// -2 D2 + D3 of the equally weighted set `samples` (N x L, one sample per column), and its
  /// gradient with respect to every sample (N x L) written to `gradient`.
  double evaluate(const Eigen::Ref<const Eigen::MatrixXd>& samples, Eigen::Ref<Eigen::MatrixXd> gradient);

  /// -2 D2 + D3 of the symmetric set {+s_k, -s_k} (plus the origin when `with_origin`, so
  /// L = 2 L' or 2 L' + 1) from the half samples `half` (N x L'), and its gradient with respect to
  /// the half samples (N x L'). Each pair (k, l) contributes g(||s_k - s_l||^2) + g(||s_k + s_l||^2):
  /// one Gram matrix gives both distances, and the gradient is two matrix products.
  double evaluate_symmetric(const Eigen::Ref<const Eigen::MatrixXd>& half, bool with_origin,
                            Eigen::Ref<Eigen::MatrixXd> gradient) {
    check_rows(half.rows(), "evaluate_symmetric");
    const Eigen::Index m = half.cols();
    if (m < 1) throw DimensionError("LcdObjective::evaluate_symmetric: there are no half samples");
    if (gradient.rows() != half.rows() || gradient.cols() != m)
      throw DimensionError(
          "LcdObjective::evaluate_symmetric: the gradient must have the shape of the samples");
    const double origin = with_origin ? 1.0 : 0.0;
    const double w = 1.0 / (2.0 * static_cast<double>(m) + origin);
    const double g0 = 0.125 * scale_;
    // Only the upper triangle of the Gram matrix is read: a symmetric rank update halves its cost.
    gram_.setZero(m, m);
    gram_.selfadjointView<Eigen::Upper>().rankUpdate(half.transpose());
    radius_ = gram_.diagonal();
    coefficient_.resize(m);
    row_sum_.setZero(m);
    double pair_sum = 0.0;  // sum_{k<l} g(d-) + g(d+)
    double self_sum = 0.0;  // sum_k g(4 r_k) (+s_k against -s_k)
    double origin_sum = 0.0;
    for (Eigen::Index l = 0; l < m; ++l) {
      for (Eigen::Index k = 0; k < l; ++k) {
        const double sum = radius_(k) + radius_(l);
        const double cross = 2.0 * gram_(k, l);
        double g_minus, dg_minus, g_plus, dg_plus;
        pair_kernel(std::max(0.0, sum - cross), g_minus, dg_minus);
        pair_kernel(std::max(0.0, sum + cross), g_plus, dg_plus);
        pair_sum += g_minus + g_plus;
        // gram_ becomes P - Q (P = g'(d-), Q = g'(d+)); row_sum_ collects the rows of P + Q.
        gram_(k, l) = gram_(l, k) = dg_minus - dg_plus;
        row_sum_(k) += dg_minus + dg_plus;
        row_sum_(l) += dg_minus + dg_plus;
      }
      double g_self, dg_self;
      pair_kernel(4.0 * radius_(l), g_self, dg_self);
      self_sum += g_self;
      gram_(l, l) = -dg_self;  // P_ll = 0, Q_ll = g'(4 r_l)
      row_sum_(l) += dg_self;
      if (with_origin) {
        double g_origin, dg_origin;
        pair_kernel(radius_(l), g_origin, dg_origin);
        origin_sum += g_origin;
        row_sum_(l) += dg_origin;  // 8 w^2 g'(r_l) s_l: the same factor as the pairs
      }
    }
    const double d3 = w * w *
                      (2.0 * static_cast<double>(m) * g0 + 2.0 * self_sum + 4.0 * pair_sum +
                       origin * (4.0 * origin_sum + g0));
    double radial_sum = 0.0;
    for (Eigen::Index k = 0; k < m; ++k) {
      double h, hq;
      radial_integrals(radius_(k), h, hq);
      radial_sum += h;
      coefficient_(k) = 8.0 * w * hq + 8.0 * w * w * row_sum_(k);
    }
    double radial_origin = 0.0;
    if (with_origin) {
      double hq;
      radial_integrals(0.0, radial_origin, hq);
    }
    const double d2 = w * (2.0 * radial_sum + origin * radial_origin);
    gradient.noalias() = half * coefficient_.asDiagonal();
    gradient.noalias() -= (8.0 * w * w) * (half * gram_);
    return d3 - 2.0 * d2;
  }

  /// The full distance D = D1 - 2 D2 + D3 of the equally weighted set `samples` (N x L).
  double distance(const Eigen::Ref<const Eigen::MatrixXd>& samples) {
    Eigen::MatrixXd gradient(samples.rows(), samples.cols());
    return d1_ + evaluate(samples, gradient);
  }

 private:
  void check_rows(Eigen::Index rows, const char* what) const {
    if (rows != dimension_)
      throw DimensionError(std::string("LcdObjective::") + what + ": the samples have " +
                           std::to_string(rows) + " rows but the objective was made for dimension " +
                           std::to_string(dimension_));
  }

  int dimension_;
  double bmax_;
  double scale_;  // 4 bmax^2
  double d1_ = 0.0;
  std::vector<double> exponent_, weight_c_, weight_cq_;
  Eigen::MatrixXd gram_;
  Eigen::VectorXd radius_, coefficient_, row_sum_;
};

/// The LCD distance D (D1 included) between the equally weighted set `samples` (N x L, one sample
/// per column) and N(0, I), for the kernel-width limit bmax (see default_bmax).
double lcd_distance(const Eigen::MatrixXd& samples, double bmax);

}  // namespace s2kf

#if !defined(S2KF_COMPILED)
#include <s2kf/core/lcd_distance.hxx>
#endif
