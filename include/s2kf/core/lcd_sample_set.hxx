/// @file
/// The definitions of <s2kf/core/lcd_sample_set.hpp>: inline where the library is used header-only, compiled
/// once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/core/lcd_sample_set.hpp>

namespace s2kf {
namespace detail {

/// Outcome of minimize_lbfgs.
struct LbfgsReport {
  int iterations = 0;
  int evaluations = 0;
  double value = 0.0;
  const char* stop = "";  ///< which rule ended the run
};

/// Minimises f over x with L-BFGS (two-loop recursion, history `memory`) and a line search for the
/// strong Wolfe conditions (Nocedal & Wright, Algorithms 3.5/3.6, c1 = 1e-4, c2 = 0.9, cubic
/// interpolation in the zoom). `evaluate(x, gradient)` returns f(x) and writes the gradient.
/// Stops when max|gradient| <= gradient_tolerance, when one iteration lowers f by at most
/// relative_tolerance * |f + value_offset| (the offset turns f into the quantity whose relative
/// change matters), after max_iterations, or when no step along the search direction lowers f.
template <class Evaluate>
LbfgsReport minimize_lbfgs(Evaluate&& evaluate, Eigen::VectorXd& x, int memory, int max_iterations,
                           double gradient_tolerance, double relative_tolerance, double value_offset) {
  const Eigen::Index n = x.size();
  LbfgsReport report;
  Eigen::VectorXd gradient(n), direction(n), trial(n), trial_gradient(n);
  std::vector<Eigen::VectorXd> steps(static_cast<std::size_t>(memory), Eigen::VectorXd(n));
  std::vector<Eigen::VectorXd> changes(static_cast<std::size_t>(memory), Eigen::VectorXd(n));
  std::vector<double> rho(static_cast<std::size_t>(memory)), alpha(static_cast<std::size_t>(memory));
  int stored = 0, newest = -1;

  double value = evaluate(x, gradient);
  ++report.evaluations;
  constexpr double c1 = 1e-4, c2 = 0.9;

  // phi(a) = f(x + a d) with its slope; the last evaluated point stays in trial / trial_gradient.
  auto line_value = [&](double step, double& slope) {
    trial = x + step * direction;
    const double v = evaluate(trial, trial_gradient);
    ++report.evaluations;
    slope = trial_gradient.dot(direction);
    return v;
  };
  // Minimiser of the cubic through (a, fa, da) and (b, fb, db), kept inside the middle 80 % of the
  // bracket; the midpoint when the cubic has no real minimiser.
  auto cubic_step = [](double a, double fa, double da, double b, double fb, double db) {
    const double d1 = da + db - 3.0 * (fa - fb) / (a - b);
    const double radicand = d1 * d1 - da * db;
    double t = 0.5 * (a + b);
    if (radicand >= 0.0) {
      const double d2 = std::copysign(std::sqrt(radicand), b - a);
      const double candidate = b - (b - a) * (db + d2 - d1) / (db - da + 2.0 * d2);
      if (std::isfinite(candidate)) t = candidate;
    }
    const double lo = std::min(a, b), hi = std::max(a, b), margin = 0.1 * (hi - lo);
    return std::clamp(t, lo + margin, hi - margin);
  };

  bool first = true;
  while (true) {
    if (gradient.lpNorm<Eigen::Infinity>() <= gradient_tolerance) {
      report.stop = "gradient tolerance";
      break;
    }
    if (report.iterations >= max_iterations) {
      report.stop = "iteration limit";
      break;
    }
    // Two-loop recursion: direction = -H gradient with H0 = (s'y / y'y) I.
    direction = -gradient;
    for (int i = 0; i < stored; ++i) {
      const auto j = static_cast<std::size_t>((newest - i + memory) % memory);
      alpha[j] = rho[j] * steps[j].dot(direction);
      direction -= alpha[j] * changes[j];
    }
    if (stored > 0) {
      const auto j = static_cast<std::size_t>(newest);
      direction *= 1.0 / (rho[j] * changes[j].squaredNorm());
    }
    for (int i = stored - 1; i >= 0; --i) {
      const auto j = static_cast<std::size_t>((newest - i + memory) % memory);
      const double beta = rho[j] * changes[j].dot(direction);
      direction += (alpha[j] - beta) * steps[j];
    }
    double slope0 = gradient.dot(direction);
    if (!(slope0 < 0.0)) {  // lost descent (rounding in a stale memory): restart from steepest descent
      stored = 0;
      direction = -gradient;
      slope0 = gradient.dot(direction);
      first = true;
    }
    // The first step has no curvature information: move by about 1 in the largest component.
    double step = first ? std::min(1.0, 1.0 / direction.lpNorm<Eigen::Infinity>()) : 1.0;

    // Strong Wolfe line search.
    double previous_step = 0.0, previous_value = value, previous_slope = slope0;
    double accepted_value = 0.0;
    bool accepted = false;
    for (int attempt = 0; attempt < 30 && !accepted; ++attempt) {
      double slope;
      const double v = line_value(step, slope);
      double lo = 0.0, f_lo = 0.0, d_lo = 0.0, hi = 0.0, f_hi = 0.0, d_hi = 0.0;
      bool bracketed = false;
      if (!std::isfinite(v) || v > value + c1 * step * slope0 || (attempt > 0 && v >= previous_value)) {
        lo = previous_step, f_lo = previous_value, d_lo = previous_slope;
        hi = step, f_hi = v, d_hi = slope;
        bracketed = true;
      } else if (std::abs(slope) <= -c2 * slope0) {
        accepted = true;
        accepted_value = v;
        break;
      } else if (slope >= 0.0) {
        lo = step, f_lo = v, d_lo = slope;
        hi = previous_step, f_hi = previous_value, d_hi = previous_slope;
        bracketed = true;
      }
      if (bracketed) {
        for (int zoom = 0; zoom < 30; ++zoom) {
          const double a = (std::isfinite(f_hi) && std::isfinite(d_hi))
                               ? cubic_step(lo, f_lo, d_lo, hi, f_hi, d_hi)
                               : 0.5 * (lo + hi);
          double da;
          const double fa = line_value(a, da);
          if (!std::isfinite(fa) || fa > value + c1 * a * slope0 || fa >= f_lo) {
            hi = a, f_hi = fa, d_hi = da;
          } else {
            if (std::abs(da) <= -c2 * slope0) {
              accepted = true;
              accepted_value = fa;
              break;
            }
            if (da * (hi - lo) >= 0.0) hi = lo, f_hi = f_lo, d_hi = d_lo;
            lo = a, f_lo = fa, d_lo = da;
          }
          if (std::abs(hi - lo) <= 1e-16 * std::max(1.0, std::abs(lo))) break;
        }
        if (!accepted && lo > 0.0 && f_lo < value) {
          // The interval collapsed without the curvature condition: take the best sufficient decrease.
          line_value(lo, slope);
          accepted = true;
          accepted_value = f_lo;
        }
        break;
      }
      previous_step = step, previous_value = v, previous_slope = slope;
      step *= 2.0;  // still descending steeply: extrapolate
    }
    if (!accepted) {
      if (stored > 0) {  // retry once from steepest descent before giving up
        stored = 0;
        first = true;
        continue;
      }
      report.stop = "line search found no decrease";
      break;
    }

    // Update the memory with s = trial - x, y = trial_gradient - gradient.
    const int slot = (newest + 1) % memory;
    const auto js = static_cast<std::size_t>(slot);
    steps[js] = trial - x;
    changes[js] = trial_gradient - gradient;
    const double curvature = steps[js].dot(changes[js]);
    if (curvature > 1e-12 * changes[js].squaredNorm()) {  // keeps H positive definite
      rho[js] = 1.0 / curvature;
      newest = slot;
      stored = std::min(stored + 1, memory);
    }
    const double decrease = value - accepted_value;
    x = trial;
    gradient = trial_gradient;
    value = accepted_value;
    ++report.iterations;
    first = false;
    if (decrease <= relative_tolerance * std::abs(value + value_offset)) {
      report.stop = "relative tolerance";
      break;
    }
  }
  report.value = value;
  return report;
}

/// Standard normal draws from a std::mt19937_64 by the Box-Muller transform, written out so that a
/// seed gives the same start with every standard library (std::normal_distribution is
/// implementation-defined); only the last bits of std::log/std::cos/std::sin may differ between
/// C libraries.
class BoxMuller {
 public:
  explicit BoxMuller(std::uint64_t seed) : engine_(seed) {}
  double operator()() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    // u1 in (0, 1] so that log(u1) is finite; 53 random bits each.
    const double u1 = (static_cast<double>(engine_() >> 11) + 1.0) * 0x1.0p-53;
    const double u2 = static_cast<double>(engine_() >> 11) * 0x1.0p-53;
    const auto [first, second] = box_muller(u1, u2);
    spare_ = second;
    has_spare_ = true;
    return first;
  }

 private:
  std::mt19937_64 engine_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

/// The objective that compute_lcd_sample_set minimises: -2 D2 + D3 of the *moment-corrected*
/// symmetric set, as a function of the raw half samples S (N x L'). The correction whitens
/// Y = chol(C)^-1 S with C = 2 S S^T / L (the set is symmetric, so its mean is already 0). Because
/// D depends only on norms and distances it is invariant under rotations, and every whitening
/// (the spec's A^T = chol(C^-1)^T included) differs from this one by a rotation: optimising D(Y)
/// optimises exactly the distance that is reported. Correcting only after an unconstrained
/// optimisation instead costs about 2 % of D (for N = 46, L = 301: 0.01399 against 0.01376).
/// Gradient by the chain rule through the Cholesky factor: with G = dD/dY and P the symmetric
/// part of tril(G Y^T) (diagonal halved), dF/dS = L^-T (G - (4/L) P Y).
class WhitenedSymmetricObjective {
 public:
  WhitenedSymmetricObjective(LcdObjective& objective, Eigen::Index half_count, bool with_origin)
      : objective_(objective),
        half_count_(half_count),
        with_origin_(with_origin),
        count_(2.0 * static_cast<double>(half_count) + (with_origin ? 1.0 : 0.0)) {
    const Eigen::Index n = objective.dimension();
    covariance_.resize(n, n);
    whitened_.resize(n, half_count);
    gradient_.resize(n, half_count);
    projection_.resize(n, n);
  }

  /// Value at the half samples stored column-major in `point`; writes the gradient.
  double operator()(const Eigen::VectorXd& point, Eigen::VectorXd& gradient) {
    const Eigen::Index n = objective_.dimension();
    Eigen::Map<const Eigen::MatrixXd> half(point.data(), n, half_count_);
    Eigen::Map<Eigen::MatrixXd> result(gradient.data(), n, half_count_);
    covariance_.noalias() = (2.0 / count_) * half * half.transpose();
    cholesky_.compute(covariance_);
    if (cholesky_.info() != Eigen::Success) {  // degenerate trial point: reject it in the line search
      result.setZero();
      return std::numeric_limits<double>::infinity();
    }
    whitened_ = half;
    cholesky_.matrixL().solveInPlace(whitened_);
    const double value = objective_.evaluate_symmetric(whitened_, with_origin_, gradient_);
    projection_.noalias() = gradient_ * whitened_.transpose();
    projection_.diagonal() *= 0.5;
    projection_.triangularView<Eigen::StrictlyUpper>().setZero();
    projection_ = 0.5 * (projection_ + projection_.transpose()).eval();
    gradient_.noalias() -= (4.0 / count_) * projection_ * whitened_;
    cholesky_.matrixU().solveInPlace(gradient_);
    result = gradient_;
    return value;
  }

  /// The whitened half samples chol(C)^-1 S of `point`.
  Eigen::MatrixXd whiten(const Eigen::VectorXd& point) {
    Eigen::VectorXd gradient(point.size());
    if (!std::isfinite((*this)(point, gradient)))
      throw std::runtime_error("compute_lcd_sample_set: the optimised samples do not span the space");
    return whitened_;
  }

 private:
  LcdObjective& objective_;
  Eigen::Index half_count_;
  bool with_origin_;
  double count_;
  Eigen::MatrixXd covariance_, whitened_, gradient_, projection_;
  Eigen::LLT<Eigen::MatrixXd> cholesky_;
};

/// The full N x L set from half samples: the origin (when L is odd) first, then +s_1..+s_L', then
/// -s_1..-s_L'.
inline Eigen::MatrixXd symmetric_set(const Eigen::MatrixXd& half, bool with_origin) {
  const Eigen::Index m = half.cols();
  const Eigen::Index offset = with_origin ? 1 : 0;
  Eigen::MatrixXd set = Eigen::MatrixXd::Zero(half.rows(), 2 * m + offset);
  set.middleCols(offset, m) = half;
  set.rightCols(m) = -half;
  return set;
}

}  // namespace detail
S2KF_INLINE LcdResult compute_lcd_sample_set(int dimension, int count, const LcdOptions& options) {
  if (dimension < 1) throw DimensionError("compute_lcd_sample_set: the dimension must be at least 1");
  if (count < 2 * dimension)
    throw DimensionError("compute_lcd_sample_set: a symmetric sample set in " + std::to_string(dimension) +
                         " dimensions needs at least " + std::to_string(2 * dimension) +
                         " samples (2N), but " + std::to_string(count) + " were requested");
  if (options.bmax < 0.0 || !std::isfinite(options.bmax))
    throw std::invalid_argument("compute_lcd_sample_set: bmax must be positive (or 0 for the default)");
  if (options.history < 1) throw std::invalid_argument("compute_lcd_sample_set: history must be at least 1");
  if (options.max_iterations < 0)
    throw std::invalid_argument("compute_lcd_sample_set: max_iterations must not be negative");
  if (!(options.gradient_tolerance >= 0.0) || !(options.relative_tolerance >= 0.0))
    throw std::invalid_argument("compute_lcd_sample_set: tolerances must not be negative");

  const auto start = std::chrono::steady_clock::now();
  const double bmax = options.bmax > 0.0 ? options.bmax : default_bmax(dimension);
  const bool with_origin = count % 2 == 1;
  const Eigen::Index half_count = count / 2;
  LcdObjective objective(dimension, bmax);

  Eigen::MatrixXd half(dimension, half_count);
  detail::BoxMuller normal(options.seed);
  for (Eigen::Index k = 0; k < half_count; ++k)
    for (Eigen::Index i = 0; i < dimension; ++i) half(i, k) = normal();

  Eigen::VectorXd x = Eigen::Map<Eigen::VectorXd>(half.data(), half.size());
  detail::WhitenedSymmetricObjective whitened(objective, half_count, with_origin);
  const detail::LbfgsReport report =
      detail::minimize_lbfgs(whitened, x, options.history, options.max_iterations, options.gradient_tolerance,
                             options.relative_tolerance, objective.d1());
  half = whitened.whiten(x);

  Eigen::MatrixXd points = detail::symmetric_set(half, with_origin);
  correct_moments(points);  // the whitened set is corrected already: this removes the last rounding
  // Subtracting the (rounding-size) sample mean breaks the exact symmetry; restore it, and the
  // exact zero of the origin, from the corrected halves.
  const Eigen::Index offset = with_origin ? 1 : 0;
  half = 0.5 * (points.middleCols(offset, half_count) - points.rightCols(half_count));
  points = detail::symmetric_set(half, with_origin);
  LcdResult result;
  result.distance = objective.distance(points);
  result.set = equally_weighted(std::move(points), "lcd");
  result.iterations = report.iterations;
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.cached = false;
  return result;
}
}  // namespace s2kf
