/// @file
/// The definitions of <s2kf/core/smart_sampling_kalman_filter.hpp>: inline where the library is used
/// header-only, compiled once into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/core/smart_sampling_kalman_filter.hpp>

#include <s2kf/core/instruction_set.hpp>

namespace s2kf {
namespace detail {

S2KF_INLINE FilterCore::FilterCore(SampleSet samples) : samples_(std::move(samples)) {
  if (samples_.count() < 1 || samples_.dimension() < 1 || samples_.weights.size() != samples_.count())
    throw DimensionError("SmartSamplingKalmanFilter: the sample set is empty or its weights do not match");
  positive_weights_ = (samples_.weights.array() > 0).all();
  sqrt_weights_ = samples_.weights.array().abs().sqrt().matrix();
  {
    // The information form takes the predictions' regression on the whitened state from the unit
    // samples z_i themselves, which is that regression only when their own moments are exactly
    // those of N(0, I) (the LCD and UKF sets are corrected to it).
    const Eigen::Index n = samples_.dimension();
    const Eigen::VectorXd first = samples_.points * samples_.weights;
    const Eigen::MatrixXd second =
        samples_.points * samples_.weights.asDiagonal() * samples_.points.transpose();
    unit_moments_ = first.cwiseAbs().maxCoeff() < 1e-10 &&
                    (second - Eigen::MatrixXd::Identity(n, n)).cwiseAbs().maxCoeff() < 1e-10;
  }
  detect_symmetry();
  if (unit_moments_ && positive_weights_) {
    scaled_points_ = symmetric_
                         ? Eigen::MatrixXd(samples_.points.middleCols(origin_count_, half_count_) *
                                           sqrt_weights_.segment(origin_count_, half_count_).asDiagonal())
                         : Eigen::MatrixXd(samples_.points * sqrt_weights_.asDiagonal());
    scaled_points_f_ = scaled_points_.cast<float>();
  }
  if (symmetric_) {
    half_points_t_ = samples_.points.middleCols(origin_count_, half_count_).transpose();
    half_points_t_f_ = half_points_t_.cast<float>();
  }
}

// Out of the class, so that a program that links the compiled library (S2KF_COMPILED) takes
// these from it for the dynamic-size filter instead of compiling them again (see the end).

S2KF_INLINE FilterStatus FilterCore::linear_prediction(Eigen::Ref<Eigen::VectorXd> mean,
                                                       Eigen::Ref<Eigen::MatrixXd> covariance,
                                                       const Eigen::MatrixXd& a,
                                                       const Eigen::MatrixXd& q) const {
  const Eigen::Index n = mean.size();
  check_square(q, n, "predict_linear: Q");
  check_square(a, n, "predict_linear: A");
  mean = (a * mean).eval();
  covariance = (a * covariance * a.transpose() + q).eval();
  symmetrize(covariance);
  return FilterStatus::ok;
}

S2KF_INLINE FilterStatus FilterCore::finish_predict(Eigen::Ref<Eigen::VectorXd> state_mean,
                                                    Eigen::Ref<Eigen::MatrixXd> state_covariance,
                                                    const Eigen::MatrixXd& q) {
  if (!propagated_.allFinite()) return FilterStatus::non_finite_model_output;
  const Eigen::VectorXd mean = propagated_ * samples_.weights;
  propagated_.colwise() -= mean;
  Eigen::MatrixXd covariance = q;
  covariance.noalias() += propagated_ * samples_.weights.asDiagonal() * propagated_.transpose();
  state_mean = mean;
  state_covariance = covariance;
  symmetrize(state_covariance);
  return FilterStatus::ok;
}

S2KF_INLINE UpdateResult FilterCore::begin_update(Eigen::Index state_dimension, const Eigen::VectorXd& y,
                                                  const Eigen::MatrixXd& r, const ObservedMask& observed,
                                                  const UpdateOptions& options) {
  const Eigen::Index n = state_dimension;
  const Eigen::Index m = y.size();
  if (samples_.dimension() != n)
    throw DimensionError("update: the state has dimension " + std::to_string(n) + " but the samples " +
                         std::to_string(samples_.dimension()));
  check_square(r, m, "update: R");
  if (observed.size() != m)
    throw DimensionError("update: the observed mask must have one entry per component");
  if (options.iterations < 1) throw DimensionError("update: iterations must be at least 1");
  if (options.block_size < 1 || m % options.block_size != 0)
    throw DimensionError("update: the block size must divide the measurement dimension");
  set_groups(m, options);
  set_quadratic_states(n, options);
  if (options.block_dependencies != nullptr) {
    const std::vector<std::vector<int>>& lists = *options.block_dependencies;
    if (static_cast<Eigen::Index>(lists.size()) != m / options.block_size)
      throw DimensionError("update: " + std::to_string(lists.size()) + " block dependency lists for " +
                           std::to_string(m / options.block_size) + " blocks");
    for (const std::vector<int>& list : lists)
      for (const int state : list)
        if (state < 0 || state >= n)
          throw DimensionError("update: a block dependency names state " + std::to_string(state) + " of " +
                               std::to_string(n));
  }

  UpdateResult result;
  rejected_blocks_.clear();
  if (rejected_blocks_.capacity() < static_cast<std::size_t>(m / options.block_size))
    rejected_blocks_.reserve(static_cast<std::size_t>(m / options.block_size));  // once, not per step
  select_observed(observed);
  const Eigen::Index mo = result.observed = observed_count_;
  if (mo == 0) {
    result.status = FilterStatus::nothing_observed;
    return result;
  }
  for (Eigen::Index k = 0; k < mo; ++k)
    if (!std::isfinite(y(index_(k)))) {
      result.status = FilterStatus::non_finite_measurement;
      return result;
    }
  return result;
}

S2KF_INLINE UpdateResult FilterCore::finish_update(Eigen::Ref<Eigen::VectorXd> mean,
                                                   Eigen::Ref<Eigen::MatrixXd> covariance,
                                                   const Eigen::VectorXd& y, const Eigen::MatrixXd& r,
                                                   const UpdateOptions& options, UpdateResult result) {
  const Eigen::Index n = mean.size();
  const Eigen::Index mo = observed_count_;

  // Cyy = sum w (y_i - y^)(y_i - y^)^T + R_oo and Cyx = sum w (y_i - y^)(x_i - m)^T, using the
  // exactly zero-mean deviations S z_i for x.
  const bool single = options.single_precision_moments && positive_weights_;
  reserve_moment_buffers(y.size(), n, single, options.information_form);
  prepare_unread_states(n, y.size(), options);
  auto cyy = cyy_buffer(mo);
  bool deviations_scaled = false;
  if (information_form_applies(r, options)) {
    // Only the diagonal blocks of Cyy (and of R) are needed.
    for (Eigen::Index j = 0; j < mo; ++j)
      for (Eigen::Index i = j; i < mo && group_of(index_(i)) == group_of(index_(j)); ++i)
        cyy(i, j) = r(index_(i), index_(j));
    // The regression and each component's spread decide whether the form applies; the groups'
    // blocks of Cyy are summed only where it does, so a frame that falls back does not pay for them.
    accumulate_regression(single);
    if (unread_count_ > 0) project_out_unread(regression_.block(quadratic_count_, 0, n, mo));
    if (information_form_nonlinearity(r) <= options.information_form_max_nonlinearity) {
      if (single && float_deviations_)
        add_diagonal_block_moments(cyy, y_dev_f_.topLeftCorner(mo, samples_.count()), block_products_f_,
                                   samples_.weights(0), deviation_centre_.data());
      else if (single)
        add_diagonal_block_moments(cyy, y_dev_f_.topLeftCorner(mo, samples_.count()), block_products_f_);
      else
        add_diagonal_block_moments(cyy, y_dev_.topRows(mo), block_products_);
      if (options.block_gate_probability > 0) result.observed = reject_outlying_blocks(y, options, true);
      result.rejected_blocks = static_cast<Eigen::Index>(rejected_blocks_.size());
      return information_form_gain(mean, covariance, y, options, result);
    }
    deviations_scaled = !single;  // the double-precision moments scaled y_dev_ in place
  }
  for (Eigen::Index j = 0; j < mo; ++j)
    for (Eigen::Index i = j; i < mo; ++i) cyy(i, j) = r(index_(i), index_(j));
  auto cyx = cyx_buffer(mo, n);
  accumulate_moments(cyy, cyx, single, deviations_scaled);
  if (unread_count_ > 0) localise_cross_covariance(cyx);
  // The outlier gate reads each marker's predicted covariance off the diagonal blocks of Cyy and
  // drops the rows (and columns) of the blocks it rejects.
  if (options.block_gate_probability > 0 && positive_weights_)
    result.observed = reject_outlying_blocks(y, options);
  const Eigen::Index mo_kept = result.observed;
  result.rejected_blocks = static_cast<Eigen::Index>(rejected_blocks_.size());

  // Square-root gain: Lyy = chol(Cyy), A = Cyx^T Lyy^-T, t = Lyy^-1 (y - y^), on the kept rows,
  // in one bordered factorisation of [Cyy; Cyx^T; (y - y^)^T].
  bordered_.resize(mo_kept, n + 1);
  auto panel = bordered_.panel();
  panel.topRows(mo_kept).template triangularView<Eigen::Lower>() = cyy_.topLeftCorner(mo_kept, mo_kept);
  panel.middleRows(mo_kept, n) = cyx_.topRows(mo_kept).transpose();
  for (Eigen::Index k = 0; k < mo_kept; ++k) panel(mo_kept + n, k) = y(index_(k)) - y_mean_(k);
  if (!bordered_.factorise()) {
    result.status = FilterStatus::innovation_not_positive_definite;
    return result;
  }
  const auto gain_factor = panel.middleRows(mo_kept, n);
  const auto whitened_innovation = panel.row(mo_kept + n).transpose();
  result.nis = whitened_innovation.squaredNorm();
  if (gated(result.nis, mo_kept, options)) {
    result.status = FilterStatus::gated;
    return result;
  }
  // C+ = C - A A^T must stay positive definite; check on a copy before touching the state.
  posterior_covariance_ = covariance;
  add_self_product_lower(posterior_covariance_, gain_factor, -1.0);
  if (!complete_posterior_is_positive_definite()) {
    result.status = FilterStatus::posterior_not_positive_definite;
    return result;
  }
  mean.noalias() += gain_factor * whitened_innovation;
  covariance = posterior_covariance_;
  return result;
}

S2KF_INLINE void FilterCore::set_groups(Eigen::Index m, const UpdateOptions& options) {
  groups_ = options.information_groups;
  group_block_size_ = group_width_ = options.block_size;
  if (groups_ == nullptr) return;
  const std::vector<int>& groups = *groups_;
  if (static_cast<Eigen::Index>(groups.size()) != m)
    throw DimensionError("update: " + std::to_string(groups.size()) + " information groups for " +
                         std::to_string(m) + " measurement components");
  Eigen::Index run = 0;
  for (Eigen::Index i = 0; i < m; ++i) {
    const int group = groups[static_cast<std::size_t>(i)];
    const int previous = i > 0 ? groups[static_cast<std::size_t>(i - 1)] : group;
    if (group < previous)
      throw DimensionError("update: the information groups must not decrease (component " +
                           std::to_string(i) + ")");
    if (i % options.block_size != 0 && group != previous)
      throw DimensionError("update: block " + std::to_string(i / options.block_size) +
                           " spans two information groups");
    run = i > 0 && group == previous ? run + 1 : 1;
    group_width_ = std::max(group_width_, run);
  }
}

S2KF_INLINE void FilterCore::set_quadratic_states(Eigen::Index n, const UpdateOptions& options) {
  quadratic_states_ = options.information_quadratic_states;
  quadratic_count_ = 0;
  if (quadratic_states_ == nullptr || quadratic_states_->empty()) return;
  const std::vector<int>& states = *quadratic_states_;
  if (states.size() > 6) throw DimensionError("update: at most 6 information_quadratic_states");
  for (std::size_t i = 0; i < states.size(); ++i) {
    if (states[i] < 0 || states[i] >= n)
      throw DimensionError("update: information_quadratic_states names state " + std::to_string(states[i]) +
                           " of " + std::to_string(n));
    for (std::size_t j = 0; j < i; ++j)
      if (states[j] == states[i])
        throw DimensionError("update: state " + std::to_string(states[i]) +
                             " appears twice in information_quadratic_states");
  }
  const auto d = static_cast<Eigen::Index>(states.size());
  if (options.information_form && symmetric_) quadratic_count_ = d * (d + 1) / 2;
}

S2KF_INLINE Eigen::Index FilterCore::prepare_unread_states(Eigen::Index n, Eigen::Index m,
                                                           const UpdateOptions& options) {
  unread_count_ = 0;
  if (options.block_dependencies == nullptr) return 0;
  const std::vector<std::vector<int>>& lists = *options.block_dependencies;
  // Sized for the whole measurement on the first update with the lists, whatever is unread then,
  // so that a later frame with unread states allocates nothing.
  if (unread_basis_.rows() != n || unread_whitened_.cols() < m) {
    unread_states_.resize(n);
    unread_basis_.resize(n, n);
    unread_factor_.resize(n, n);
    unread_whitened_.resize(n, m);
    unread_coefficients_.resize(n, m);
  }
  state_read_.assign(static_cast<std::size_t>(n), 0);
  for (Eigen::Index k = 0, last = -1; k < observed_count_; ++k) {
    const Eigen::Index block = index_(k) / options.block_size;
    if (block == last) continue;
    last = block;
    for (const int state : lists[static_cast<std::size_t>(block)])
      state_read_[static_cast<std::size_t>(state)] = 1;
  }
  for (Eigen::Index j = 0; j < n; ++j)
    if (!state_read_[static_cast<std::size_t>(j)]) unread_states_(unread_count_++) = j;
  const Eigen::Index u = unread_count_;
  if (u == 0) return 0;
  // W = S^-1 E_u, then [W^T W; W] factorised in place into [L; W L^-T] = [L; Q].
  auto w = unread_basis_.leftCols(u);
  w.setZero();
  for (Eigen::Index j = 0; j < u; ++j) w(unread_states_(j), j) = 1;
  factor_.matrixL().solveInPlace(w);
  bordered_.resize(u, n);
  auto panel = bordered_.panel();
  auto gram = panel.topRows(u);
  gram.template triangularView<Eigen::Lower>().setZero();
  rank_update_lower(gram, w.transpose());  // W^T W, lower half
  panel.bottomRows(n) = w;
  if (!bordered_.factorise()) {  // only if S is singular to rounding: then keep the plain update
    unread_count_ = 0;
    return 0;
  }
  w = panel.bottomRows(n);
  unread_factor_.topLeftCorner(u, u).template triangularView<Eigen::Lower>() =
      panel.topRows(u).template triangularView<Eigen::Lower>();
  return u;
}

S2KF_INLINE void FilterCore::project_out_unread(Eigen::Ref<Eigen::MatrixXd> whitened_regression) {
  const Eigen::Index u = unread_count_, columns = whitened_regression.cols();
  const auto q = unread_basis_.leftCols(u);
  auto c = unread_coefficients_.topLeftCorner(u, columns);
  c.noalias() = q.transpose() * whitened_regression;
  whitened_regression.noalias() -= q * c;
}

S2KF_INLINE void FilterCore::localise_cross_covariance(Eigen::Block<Eigen::MatrixXd>& cyx) {
  const Eigen::Index u = unread_count_, n = cyx.cols(), mo = cyx.rows();
  auto z = unread_whitened_.topLeftCorner(n, mo);
  z = cyx.transpose();
  factor_.matrixL().solveInPlace(z);
  auto c = unread_coefficients_.topLeftCorner(u, mo);
  c.noalias() = unread_basis_.leftCols(u).transpose() * z;
  unread_factor_.topLeftCorner(u, u).template triangularView<Eigen::Lower>().transpose().solveInPlace(c);
  for (Eigen::Index j = 0; j < u; ++j) cyx.col(unread_states_(j)) -= c.row(j).transpose();
}

S2KF_INLINE bool FilterCore::information_form_applies(const Eigen::MatrixXd& r,
                                                      const UpdateOptions& options) const {
  if (!options.information_form || !positive_weights_ || !unit_moments_ || options.iterations > 1)
    return false;
  // R must not couple the groups: the information form keeps only its diagonal blocks. Checked
  // on the whole of R below each group, column by column, as an OR of the entries' bits without
  // the sign (so -0 counts as zero): an integer reduction the compiler vectorises.
  const Eigen::Index m = r.rows();
  std::uint64_t bits = 0;
  Eigen::Index group_end = 0;
  for (Eigen::Index j = 0; j < m; ++j) {
    if (group_end <= j)
      for (group_end = j + 1; group_end < m && group_of(group_end) == group_of(j);) ++group_end;
    const double* column = r.data() + j * m;
    for (Eigen::Index i = group_end; i < m; ++i) {
      std::uint64_t entry;
      std::memcpy(&entry, column + i, sizeof entry);
      bits |= entry;
    }
  }
  return (bits & ~(std::uint64_t{1} << 63)) == 0;
}

S2KF_INLINE double FilterCore::information_form_nonlinearity(const Eigen::MatrixXd& r) const {
  const Eigen::Index mo = observed_count_;
  const auto gt = regression_.leftCols(mo);
  double largest = 0, second = 0;
  for (Eigen::Index k = 0; k < mo;) {
    double unexplained = 0, noise = 0;
    const Eigen::Index group = group_of(index_(k));
    for (; k < mo && group_of(index_(k)) == group; ++k) {
      const double variance = r(index_(k), index_(k));
      noise += variance;
      unexplained += component_spread_(k) - gt.col(k).squaredNorm();
    }
    const double ratio = noise > 0 ? unexplained / noise : std::numeric_limits<double>::infinity();
    if (std::isnan(ratio)) return ratio;  // not below any limit: the ordinary update runs
    if (ratio > largest) {
      second = largest;
      largest = ratio;
    } else if (ratio > second) {
      second = ratio;
    }
  }
  // What the form leaves out, the correlation between two groups' nonlinear parts, is bounded
  // by sqrt(Omega_ii Omega_jj): a single nonlinear group (a limb whose markers were hidden for a
  // while) costs nothing; two make it inexact.
  return std::sqrt(largest * second);
}

S2KF_INLINE UpdateResult FilterCore::information_form_gain(Eigen::Ref<Eigen::VectorXd> mean,
                                                           Eigen::Ref<Eigen::MatrixXd> covariance,
                                                           const Eigen::VectorXd& y,
                                                           const UpdateOptions& options,
                                                           UpdateResult result) {
  using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxBlock, kMaxBlock>;
  const Eigen::Index n = mean.size(), mo = result.observed, p = quadratic_count_, na = p + n;
  const bool single = options.single_precision_moments;
  // In the whitened coordinates u = S^-1 (x - m) the prior is N(0, I) and the predictions regress
  // on u with G (regression_ holds G^T, one column per observed component), and on the whitened
  // products q~ (UpdateOptions::information_quadratic_states, prior N(0, I) too, uncorrelated
  // with u) in its first p rows: below, G stands for both, [H~ G].
  auto gt = regression_.leftCols(mo);
  auto innovation = innovation_.head(mo);
  for (Eigen::Index k = 0; k < mo; ++k) innovation(k) = y(index_(k)) - y_mean_(k);
  // Per group: D_b = C_b + R_b - G_b G_b^T (the spread G does not explain, plus the noise), then
  // G_b and the innovation whitened by D_b's Cholesky factor L_b (forward substitution on the
  // group's columns of G^T).
  const auto whiten_block = [&](auto& d_block, Eigen::Index k, Eigen::Index d) {
    for (Eigen::Index j = 0; j < d; ++j)
      for (Eigen::Index i = j; i < d; ++i)
        d_block(i, j) = d_block(j, i) = cyy_(k + i, k + j) - gt.col(k + i).dot(gt.col(k + j));
    using Matrix = std::decay_t<decltype(d_block)>;
    const Eigen::LLT<Matrix> llt(d_block);
    if (llt.info() != Eigen::Success) return false;
    const auto& l = llt.matrixLLT();
    for (Eigen::Index i = 0; i < d; ++i) {
      for (Eigen::Index j = 0; j < i; ++j) {
        gt.col(k + i) -= l(i, j) * gt.col(k + j);
        innovation(k + i) -= l(i, j) * innovation(k + j);
      }
      gt.col(k + i) /= l(i, i);
      innovation(k + i) /= l(i, i);
    }
    return true;
  };
  // A large group (a limb's markers): D_b formed in the panel of the bordered factorisation, with
  // G_b^T and the innovation as its border, so that one pass gives L_b, G_b^T L_b^-T and L_b^-1 e_b.
  const auto whiten_group = [&](Eigen::Index k, Eigen::Index d) {
    bordered_.resize(d, na + 1);
    auto panel = bordered_.panel();
    auto d_group = panel.topRows(d);
    auto g_group = gt.middleCols(k, d);
    if (single) {
      // G_b G_b^T in float, as C_b was summed: both round relative to C_b, far below R_b.
      auto g_rows = single_buffer(group_regression_f_, d, na);
      g_rows = g_group.transpose().template cast<float>();
      auto explained = single_buffer(group_products_f_, d, d);
      explained.template triangularView<Eigen::Lower>().setZero();
      add_self_product_lower(explained, g_rows);
      for (Eigen::Index j = 0; j < d; ++j)
        for (Eigen::Index i = j; i < d; ++i)
          d_group(i, j) = cyy_(k + i, k + j) - static_cast<double>(explained(i, j));
    } else {
      d_group.template triangularView<Eigen::Lower>() = cyy_.block(k, k, d, d);
      auto g_rows = group_regression_.topRows(d);
      g_rows = g_group.transpose();
      add_self_product_lower(d_group, g_rows, -1.0);  // the tiles of the processor, not the build's
    }
    panel.middleRows(d, na) = g_group;
    panel.row(d + na) = innovation.segment(k, d).transpose();
    if (!bordered_.factorise()) return false;
    g_group = panel.middleRows(d, na);
    innovation.segment(k, d) = panel.row(d + na).transpose();
    return true;
  };
  for (Eigen::Index k = 0; k < mo;) {
    Eigen::Index end = k;
    while (end < mo && group_of(index_(end)) == group_of(index_(k))) ++end;
    bool positive;
    if (end - k <= kMaxBlock) {
      Small d_block(end - k, end - k);
      positive = whiten_block(d_block, k, end - k);
    } else {
      positive = whiten_group(k, end - k);
    }
    if (!positive) {
      result.status = FilterStatus::innovation_not_positive_definite;
      return result;
    }
    k = end;
  }
  // M = I + W^T W with W = D^-1/2 G; u+ = M^-1 W^T e; NIS = e^T (G G^T + D)^-1 e by Woodbury.
  // M = L_M L_M^T is factorised with the prior's factor S and v = W^T e as its border, giving
  // T = S L_M^-T and t = L_M^-1 v: then the NIS is |e|^2 - |t|^2, the step S M^-1 v = T t and the
  // posterior covariance S M^-1 S^T = T T^T. With the products first, the factor's trailing block
  // L_uu factorises the state's Schur complement, so the border [0 S] gives [0, S L_uu^-T]: the
  // state's marginal posterior T T^T and step T t_u, the products integrated out.
  bordered_.resize(na, n + 1);
  auto panel = bordered_.panel();
  auto information = panel.topRows(na);
  information.setIdentity();
  if (single) {
    // G^T G in float, as G itself was summed: the same relative rounding of W = D^-1/2 G.
    auto gt_f = single_buffer(regression_f_, na, mo);
    gt_f = gt.template cast<float>();
    auto products = single_buffer(information_f_, na, na);
    products.template triangularView<Eigen::Lower>().setZero();
    add_self_product_lower(products, gt_f);
    information.template triangularView<Eigen::Lower>() += products.template cast<double>();
  } else {
    rank_update_lower(information, gt);
  }
  auto prior_factor = panel.middleRows(na, n);
  prior_factor.leftCols(p).setZero();
  prior_factor.rightCols(n).template triangularView<Eigen::Lower>() = factor_.matrixL();
  prior_factor.rightCols(n).template triangularView<Eigen::StrictlyUpper>().setZero();
  panel.row(na + n).noalias() = innovation.transpose() * gt.transpose();
  if (!bordered_.factorise()) {
    result.status = FilterStatus::innovation_not_positive_definite;
    return result;
  }
  const auto whitening = panel.block(na, p, n, n);
  const auto whitened_information = panel.row(na + n).transpose();
  result.nis = std::max(0.0, innovation.squaredNorm() - whitened_information.squaredNorm());
  if (gated(result.nis, mo, options)) {
    result.status = FilterStatus::gated;
    return result;
  }
  // mean += S u+ = T t_u, C+ = T T^T.
  state_step_.noalias() = whitening * whitened_information.tail(n);
  posterior_covariance_.setZero(n, n);
  add_self_product_lower(posterior_covariance_, whitening);
  if (!complete_posterior_is_positive_definite()) {
    result.status = FilterStatus::posterior_not_positive_definite;
    return result;
  }
  mean += state_step_;
  covariance = posterior_covariance_;
  return result;
}

S2KF_INLINE FilterStatus FilterCore::draw_samples(const Eigen::Ref<const Eigen::VectorXd>& mean,
                                                  const Eigen::Ref<const Eigen::MatrixXd>& covariance,
                                                  bool single_precision) {
  if (samples_.dimension() != mean.size())
    throw DimensionError("the state has dimension " + std::to_string(mean.size()) + " but the samples " +
                         std::to_string(samples_.dimension()));
  double_samples_pending_ = false;
  factor_.compute(covariance);
  if (factor_.info() != Eigen::Success || !mean.allFinite()) return FilterStatus::prior_not_positive_definite;
  if (symmetric_ && !keep_full_deviations_) {
    // S (-z) = -(S z) exactly: map the half set only, then mirror it.
    const Eigen::Index h = half_count_;
    if (single_precision) {
      // S Z in float: each deviation rounded relative to its own size, as the model's float
      // deviations are; the samples in double only where something reads them
      // (complete_drawn_samples).
      const Eigen::Index n = mean.size();
      const Eigen::MatrixXd& l = factor_.matrixLLT();
      lower_factor_f_.resize(n, n);
      for (Eigen::Index j = 0; j < n; ++j)
        for (Eigen::Index i = 0; i < n; ++i)
          lower_factor_f_(i, j) = i < j ? 0.0f : static_cast<float>(l(i, j));
      drawn_deviation_f_.setZero(mean.size(), h);
      half_deviation_.resize(mean.size(), h);  // sized now, so that a later fallback allocates nothing
      x_.resize(mean.size(), samples_.count());
      add_triangular_product_transposed(drawn_deviation_f_, lower_factor_f_, half_points_t_f_);
      drawn_mean_ = mean;
      double_samples_pending_ = true;
      return FilterStatus::ok;
    }
    // S Z in the register tiles of the processor's instruction set (core/product_tiles.hpp).
    lower_factor_ = factor_.matrixL();
    half_deviation_.setZero(mean.size(), h);
    add_triangular_product_transposed(half_deviation_, lower_factor_, half_points_t_);
    mirror_half_deviations(mean);
    return FilterStatus::ok;
  }
  x_dev_.noalias() = factor_.matrixL() * samples_.points;
  x_ = x_dev_;
  x_.colwise() += mean;
  return FilterStatus::ok;
}

S2KF_INLINE void FilterCore::mirror_half_deviations(const Eigen::Ref<const Eigen::VectorXd>& mean) {
  const Eigen::Index h = half_count_, o = origin_count_;
  x_.resize(mean.size(), samples_.count());
  if (o == 1) x_.col(0) = mean;
  x_.middleCols(o, h) = half_deviation_.colwise() + mean;
  x_.rightCols(h) = (-half_deviation_).colwise() + mean;
}

S2KF_INLINE void FilterCore::complete_drawn_samples() {
  if (!double_samples_pending_) return;
  half_deviation_ = drawn_deviation_f_.cast<double>();
  mirror_half_deviations(drawn_mean_);
  double_samples_pending_ = false;
}

S2KF_INLINE void FilterCore::detect_symmetry() {
  const Eigen::Index count = samples_.count();
  origin_count_ = count % 2;
  half_count_ = count / 2;
  const Eigen::Index h = half_count_, o = origin_count_;
  symmetric_ = positive_weights_ && h > 0 && (o == 0 || samples_.points.col(0).isZero(0)) &&
               samples_.points.middleCols(o, h) == -samples_.points.rightCols(h) &&
               samples_.weights.segment(o, h) == samples_.weights.tail(h);
  equal_weights_ = (samples_.weights.array() == samples_.weights(0)).all();
}

S2KF_INLINE Eigen::MatrixXd& FilterCore::prepare_predictions(Eigen::Index m) {
  const Eigen::Index mo = observed_count_;
  const Eigen::Index count = samples_.count();
  if (y_dev_.rows() < m || y_dev_.cols() != count)
    y_dev_.resize(std::max<Eigen::Index>(y_dev_.rows(), m), count);
  // With every component observed the model writes straight into y_dev_ (no gather).
  direct_ = mo == m && y_dev_.rows() == m;
  // Sized even when unused now, so that a later frame with hidden rows does not allocate.
  predictions_.resize(m, count);
  return direct_ ? y_dev_ : predictions_;
}

S2KF_INLINE Eigen::Block<Eigen::MatrixXf> FilterCore::prepare_float_predictions(Eigen::Index m) {
  const Eigen::Index count = samples_.count();
  prepare_predictions(m);  // the double buffers, for a fallback that reads y_dev_
  // Every buffer gather_float_deviations fills, for all m rows at once: reserve_moment_buffers,
  // which runs after it, must not grow (and so clear) one of them.
  single_buffer(predictions_f_, m, count);
  single_buffer(pair_difference_f_, m, half_count_);
  single_buffer(component_spread_f_, m, 1);
  mean_prediction_.resize(m);
  auto y_dev_f = single_buffer(y_dev_f_, m, count);
  return observed_count_ == m ? y_dev_f : predictions_f_.topLeftCorner(m, count);
}

S2KF_INLINE FilterStatus FilterCore::gather_float_deviations(Eigen::Index m) {
  const Eigen::Index mo = observed_count_, count = samples_.count(), h = half_count_, o = origin_count_;
  auto y_dev_f = single_buffer(y_dev_f_, mo, count);
  auto spread_f = single_buffer(component_spread_f_, mo, 1).col(0);
  auto pair_difference_f = single_buffer(pair_difference_f_, mo, h);
  if (deviation_centre_.size() < m) deviation_centre_.resize(m);
  if (component_spread_.size() < m) component_spread_.resize(m);
  y_mean_.resize(std::max<Eigen::Index>(y_mean_.size(), m));
  auto sum = deviation_centre_.head(mo);
  sum.setZero();
  spread_f.setZero();
  // One pass over the columns, compiled for the processor's instruction set as in gather_observed:
  // the observed rows (a gather where some are hidden), their sums and sums of squares, and each
  // pair's difference.
  const Eigen::Index* index = index_.data();
  double* sums = sum.data();
  float* spread = spread_f.data();
  const bool gather = mo < m;
  run_with_instruction_set(active_instruction_set(), [&](auto) S2KF_ALWAYS_INLINE_LAMBDA {
    for (Eigen::Index i = 0; i < count; ++i) {
      float* to = y_dev_f.data() + i * y_dev_f.outerStride();
      if (gather) {
        const float* from = predictions_f_.data() + i * predictions_f_.outerStride();
        for (Eigen::Index k = 0; k < mo; ++k) to[k] = from[index[k]];
      }
      for (Eigen::Index k = 0; k < mo; ++k) {
        sums[k] += static_cast<double>(to[k]);
        spread[k] += to[k] * to[k];
      }
      if (i >= o + h) {
        const float* plus = y_dev_f.data() + (i - h) * y_dev_f.outerStride();
        float* difference = pair_difference_f.data() + (i - o - h) * pair_difference_f.outerStride();
        for (Eigen::Index k = 0; k < mo; ++k) difference[k] = plus[k] - to[k];
      }
    }
  });
  // Equal weights w: the centre c = w sum d_i, and sum w (d_i - c)^2 = w sum d_i^2 - (2 - L w) c^2.
  const double w = samples_.weights(0);
  centre_weight_ = 2.0 - w * static_cast<double>(count);
  sum *= w;
  for (Eigen::Index k = 0; k < mo; ++k) {
    y_mean_(k) = mean_prediction_(index_(k)) + sum(k);
    component_spread_(k) = w * static_cast<double>(spread_f(k)) - centre_weight_ * sum(k) * sum(k);
  }
  if (!y_mean_.head(mo).allFinite()) return FilterStatus::non_finite_model_output;
  float_deviations_ = true;
  centred_ = false;
  return FilterStatus::ok;
}

S2KF_INLINE void FilterCore::expand_float_deviations() {
  if (!float_deviations_) return;
  const Eigen::Index mo = observed_count_;
  y_dev_.topRows(mo) = y_dev_f_.topLeftCorner(mo, samples_.count()).template cast<double>();
  y_dev_.topRows(mo).colwise() -= deviation_centre_.head(mo);
  centred_ = true;
  float_deviations_ = false;
}

S2KF_INLINE void FilterCore::normalise_float_deviations() {
  if (!float_deviations_) return;
  expand_float_deviations();  // y_dev_ too, for a fallback to the ordinary update
  const Eigen::Index mo = observed_count_;
  y_dev_f_.topLeftCorner(mo, samples_.count()) =
      (sqrt_weights_(0) * y_dev_.topRows(mo)).template cast<float>();
}

S2KF_INLINE FilterStatus FilterCore::gather_observed(Eigen::Index m) {
  const Eigen::Index mo = observed_count_;
  const Eigen::Index count = samples_.count();
  if (symmetric_ && (pair_difference_.rows() < m || pair_difference_.cols() != half_count_))
    pair_difference_.resize(std::max<Eigen::Index>(pair_difference_.rows(), m), half_count_);
  y_mean_.resize(std::max<Eigen::Index>(y_mean_.size(), m));
  auto y_mean = y_mean_.head(mo);
  y_mean.setZero();
  // Gather the observed rows a column at a time (both matrices are column-major) and add the
  // column to the weighted mean while it is in cache: plain loops compiled for the processor's
  // instruction set (the rest of the filter is compiled for the build's baseline).
  const Eigen::Index* index = index_.data();
  const double* weights = samples_.weights.data();
  double* mean = y_mean.data();
  const bool all_rows = mo == m;
  run_with_instruction_set(active_instruction_set(), [&](auto) S2KF_ALWAYS_INLINE_LAMBDA {
    for (Eigen::Index i = 0; i < count; ++i) {
      double* to = y_dev_.data() + i * y_dev_.outerStride();
      const double* from = predictions_.data() + i * predictions_.outerStride();
      if (direct_) {
        // already there
      } else if (all_rows) {
        std::copy_n(from, mo, to);
      } else {
        for (Eigen::Index k = 0; k < mo; ++k) to[k] = from[index[k]];
      }
      const double w = weights[i];
      for (Eigen::Index k = 0; k < mo; ++k) mean[k] += w * to[k];
    }
  });
  // A NaN or infinite prediction makes its row's weighted mean NaN or infinite whatever the
  // weight (0 * inf is NaN), so checking the mean checks every prediction.
  if (!y_mean.allFinite()) return FilterStatus::non_finite_model_output;
  centred_ = false;
  float_deviations_ = false;
  return FilterStatus::ok;
}

S2KF_INLINE void FilterCore::accumulate_moments(Eigen::Block<Eigen::MatrixXd>& cyy,
                                                Eigen::Block<Eigen::MatrixXd>& cyx, bool single_precision,
                                                bool deviations_scaled) {
  const Eigen::Index mo = observed_count_;
  expand_float_deviations();
  centre_deviations();
  auto y_dev = y_dev_.topRows(mo);
  if (symmetric_) {
    // Pairs +s_k, -s_k with equal weights: sum over a pair of w (y_i - y^)(x_i - m)^T is
    // w (y+_k - y-_k) s_k^T (y^ cancels), so Cyx costs half the product over all samples.
    const Eigen::Index h = half_count_, o = origin_count_;
    complete_drawn_samples();
    half_deviation_ = half_deviation_ * sqrt_weights_.segment(o, h).asDiagonal();
    if (single_precision) {
      // sqrt(w_i) (y_i - y^), scaled in double and rounded once.
      auto y_dev_f = single_buffer(y_dev_f_, mo, y_dev.cols());
      if (equal_weights_)
        y_dev_f = (sqrt_weights_(0) * y_dev).template cast<float>();
      else
        y_dev_f = (y_dev * sqrt_weights_.asDiagonal()).template cast<float>();
      auto cyy_f = single_buffer(cyy_f_, mo, mo);
      cyy_f.template triangularView<Eigen::Lower>().setZero();
      add_self_product_lower(cyy_f, y_dev_f);
      cyy.template triangularView<Eigen::Lower>() += cyy_f.template cast<double>();
      auto pair_difference_f = single_buffer(pair_difference_f_, mo, h);
      pair_difference_f.noalias() = y_dev_f.middleCols(o, h) - y_dev_f.rightCols(h);
      auto half_f = single_buffer(half_deviation_f_, half_deviation_.rows(), h);
      half_f = half_deviation_.template cast<float>();
      auto cyx_f = single_buffer(cyx_f_, mo, cyx.cols());
      cyx_f.setZero();
      add_product_transposed(cyx_f, pair_difference_f, half_f);
      cyx = cyx_f.template cast<double>();
      return;
    }
    if (!deviations_scaled) scale_columns_by_sqrt_weights(y_dev);
    rank_update_lower(cyy, y_dev);
    auto pair_difference = pair_difference_.topRows(mo);
    pair_difference.noalias() = y_dev.middleCols(o, h) - y_dev.rightCols(h);
    cyx.setZero();
    for (Eigen::Index k = 0; k < h; k += kChunk) {
      const Eigen::Index c = std::min(kChunk, h - k);
      cyx.noalias() += pair_difference.middleCols(k, c) * half_deviation_.middleCols(k, c).transpose();
    }
  } else if (positive_weights_) {
    if (!deviations_scaled) scale_columns_by_sqrt_weights(y_dev);
    rank_update_lower(cyy, y_dev);
    x_dev_ = x_dev_ * sqrt_weights_.asDiagonal();
    cyx.noalias() = y_dev * x_dev_.transpose();
  } else {
    cyy.template triangularView<Eigen::Lower>() += y_dev * samples_.weights.asDiagonal() * y_dev.transpose();
    cyx.noalias() = y_dev * samples_.weights.asDiagonal() * x_dev_.transpose();
  }
}

S2KF_INLINE void FilterCore::accumulate_regression(bool single_precision) {
  const Eigen::Index mo = observed_count_, n = samples_.dimension(), count = samples_.count();
  auto y_dev = y_dev_.topRows(mo);
  // Sized by reserve_moment_buffers: the products' rows first (accumulate_quadratic_regression).
  auto regression = regression_.block(quadratic_count_, 0, n, mo);
  // Pairs +z_k, -z_k with equal weights: sum over a pair of w z (y_i - y^)^T is
  // w z_k (y+_k - y-_k)^T, so G^T costs half the product over all samples.
  const Eigen::Index h = half_count_, o = origin_count_;
  // Each row's sum of squares, column by column (the matrices are column-major).
  const auto sum_of_squares = [count](auto& spread, const auto& deviations) {
    spread.setZero();
    for (Eigen::Index i = 0; i < count; ++i) spread += deviations.col(i).cwiseAbs2();
  };
  const auto product = [](auto& target, const auto& points, const auto& deviations) {
    target.setZero();
    for (Eigen::Index k = 0; k < points.cols(); k += kChunk) {
      const Eigen::Index c = std::min(kChunk, points.cols() - k);
      target.noalias() += points.middleCols(k, c) * deviations.middleCols(k, c).transpose();
    }
  };
  if (single_precision && float_deviations_) {
    // The model's float deviations, summed and paired by gather_float_deviations: the pairs'
    // differences need no centring, and sqrt(w) is the product's factor.
    auto regression_f = single_buffer(regression_f_, n, mo);
    regression_f.setZero();
    add_product_transposed(regression_f, scaled_points_f_, single_buffer(pair_difference_f_, mo, h),
                           static_cast<float>(sqrt_weights_(0)));
    regression = regression_f.template cast<double>();
    if (quadratic_count_ > 0) {
      normalise_float_deviations();
      accumulate_quadratic_regression(true);
    }
    return;
  }
  expand_float_deviations();
  if (single_precision) {
    // sqrt(w_i) (y_i - y^), scaled in double and rounded once; in the same pass over the columns,
    // while each is in cache, the rows' sums of squares and each pair's difference y+_k - y-_k.
    auto y_dev_f = single_buffer(y_dev_f_, mo, count);
    auto spread_f = single_buffer(component_spread_f_, mo, 1).col(0);
    auto pair_difference_f = single_buffer(pair_difference_f_, mo, symmetric_ ? h : 0);
    spread_f.setZero();
    // Plain loops compiled for the processor's instruction set, as in gather_observed.
    const double* mean = y_mean_.data();
    float* spread = spread_f.data();
    const bool centred = centred_, pairs = symmetric_;
    run_with_instruction_set(active_instruction_set(), [&](auto) S2KF_ALWAYS_INLINE_LAMBDA {
      for (Eigen::Index i = 0; i < count; ++i) {
        const double scale = sqrt_weights_(equal_weights_ ? 0 : i);
        const double* from = y_dev.data() + i * y_dev.outerStride();
        float* to = y_dev_f.data() + i * y_dev_f.outerStride();
        if (centred)
          for (Eigen::Index k = 0; k < mo; ++k) to[k] = static_cast<float>(scale * from[k]);
        else
          for (Eigen::Index k = 0; k < mo; ++k) to[k] = static_cast<float>(scale * (from[k] - mean[k]));
        for (Eigen::Index k = 0; k < mo; ++k) spread[k] += to[k] * to[k];
        if (pairs && i >= o + h) {
          const float* plus = y_dev_f.data() + (i - h) * y_dev_f.outerStride();
          float* difference = pair_difference_f.data() + (i - o - h) * pair_difference_f.outerStride();
          for (Eigen::Index k = 0; k < mo; ++k) difference[k] = plus[k] - to[k];
        }
      }
    });
    component_spread_.head(mo) = spread_f.template cast<double>();
    auto regression_f = single_buffer(regression_f_, n, mo);
    regression_f.setZero();
    if (symmetric_) {
      add_product_transposed(regression_f, scaled_points_f_, pair_difference_f);
    } else {
      add_product_transposed(regression_f, scaled_points_f_, y_dev_f);
    }
    regression = regression_f.template cast<double>();
    if (quadratic_count_ > 0) accumulate_quadratic_regression(true);
    return;
  }
  centre_deviations();
  scale_columns_by_sqrt_weights(y_dev);
  auto spread = component_spread_.head(mo);
  sum_of_squares(spread, y_dev);
  if (symmetric_) {
    auto pair_difference = pair_difference_.topRows(mo);
    pair_difference.noalias() = y_dev.middleCols(o, h) - y_dev.rightCols(h);
    product(regression, scaled_points_, pair_difference);
  } else {
    product(regression, scaled_points_, y_dev);
  }
  if (quadratic_count_ > 0) accumulate_quadratic_regression(false);
}

S2KF_INLINE void FilterCore::accumulate_quadratic_regression(bool single_precision) {
  using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 21, 21>;
  using SmallVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 21, 1>;
  const Eigen::Index mo = observed_count_, p = quadratic_count_, h = half_count_, o = origin_count_;
  const std::vector<int>& states = *quadratic_states_;
  const auto d = static_cast<Eigen::Index>(states.size());
  // f_k = sqrt(w_k) q_k, q_k the products delta_a delta_b (a <= b) of the + sample's deviations
  // S z_k (half_deviation_, not yet scaled); the - sample has the same products.
  complete_drawn_samples();
  auto features = quadratic_features_.leftCols(h);
  for (Eigen::Index k = 0; k < h; ++k) {
    const double scale = sqrt_weights_(o + k);
    Eigen::Index row = 0;
    for (Eigen::Index a = 0; a < d; ++a)
      for (Eigen::Index b = a; b < d; ++b)
        features(row++, k) = scale * half_deviation_(states[static_cast<std::size_t>(a)], k) *
                             half_deviation_(states[static_cast<std::size_t>(b)], k);
  }
  // Over all samples (the origin's products are zero): mean 2 sum_k w_k q_k, covariance
  // 2 F F^T - mean mean^T, and the cross moment with the predictions
  // sum_k w_k q_k (y+_k + y-_k - 2 y^)^T = F P^T, P the scaled pair sums (the mean of the
  // deviations is zero, so the products need no centring there).
  SmallVector mean = 2.0 * (features * sqrt_weights_.segment(o, h));
  Small covariance = 2.0 * features * features.transpose();
  covariance -= mean * mean.transpose();
  auto cross = regression_.topLeftCorner(p, mo);
  if (single_precision) {
    auto y_dev_f = y_dev_f_.topLeftCorner(mo, samples_.count());
    auto pair_sum_f = single_buffer(pair_sum_f_, mo, h);
    pair_sum_f.noalias() = y_dev_f.middleCols(o, h) + y_dev_f.rightCols(h);
    auto features_f = single_buffer(quadratic_features_f_, p, h);
    features_f = features.template cast<float>();
    auto cross_f = single_buffer(quadratic_cross_f_, p, mo);
    cross_f.noalias() = features_f * pair_sum_f.transpose();
    cross = cross_f.template cast<double>();
  } else {
    auto y_dev = y_dev_.topRows(mo);  // scaled by sqrt(w) already
    auto pair_sum = pair_sum_.topRows(mo);
    pair_sum.noalias() = y_dev.middleCols(o, h) + y_dev.rightCols(h);
    cross.noalias() = features * pair_sum.transpose();
  }
  // Whitened products q~ = L_q^-1 (q - mean), Cov(q~) = I: their regression is L_q^-1 times the
  // cross moment. Products the samples do not spread (a state without variance) add nothing.
  covariance.diagonal().array() += 1e-12 * covariance.trace() / static_cast<double>(p);
  const Eigen::LLT<Small> factor(covariance);
  if (factor.info() != Eigen::Success || !(covariance.trace() > 0)) {
    cross.setZero();
    return;
  }
  const auto& l = factor.matrixLLT();
  for (Eigen::Index i = 0; i < p; ++i) {
    for (Eigen::Index j = 0; j < i; ++j) cross.row(i) -= l(i, j) * cross.row(j);
    cross.row(i) /= l(i, i);
  }
}

S2KF_INLINE Eigen::Index FilterCore::reject_outlying_blocks(const Eigen::VectorXd& y,
                                                            const UpdateOptions& options,
                                                            bool diagonal_blocks) {
  using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxBlock, kMaxBlock>;
  using SmallVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxBlock, 1>;
  const Eigen::Index mo = observed_count_, b = options.block_size;
  if (b > kMaxBlock) throw DimensionError("update: blocks of more than 6 components cannot be gated");
  // The quantile for as many degrees of freedom as a block has observed components (a bisection
  // that costs more than the gate itself: computed when the probability changes).
  if (block_limit_probability_ != options.block_gate_probability) {
    for (int d = 1; d <= kMaxBlock; ++d)
      block_limit_[d] = chi_square_quantile(options.block_gate_probability, static_cast<double>(d));
    block_limit_probability_ = options.block_gate_probability;
  }
  const double* limit = block_limit_;
  Eigen::Index observed_blocks = 0;
  for (Eigen::Index k = 0; k < mo;) {
    const Eigen::Index block = index_(k) / b;
    Eigen::Index end = k;
    while (end < mo && index_(end) / b == block) ++end;
    const Eigen::Index d = end - k;
    Small c(d, d);
    SmallVector e(d);
    for (Eigen::Index j = 0; j < d; ++j) {
      e(j) = y(index_(k + j)) - y_mean_(k + j);
      for (Eigen::Index i = j; i < d; ++i) c(i, j) = c(j, i) = cyy_(k + i, k + j);
    }
    const Eigen::LLT<Small> llt(c);
    if (llt.info() == Eigen::Success && e.dot(llt.solve(e)) > limit[d]) rejected_blocks_.push_back(block);
    ++observed_blocks;
    k = end;
  }
  if (rejected_blocks_.empty()) return mo;
  if (2 * static_cast<Eigen::Index>(rejected_blocks_.size()) > observed_blocks) {
    rejected_blocks_.clear();
    return mo;
  }
  // The positions (in the observed rows) that stay, in order.
  Eigen::Index kept = 0;
  std::size_t next_rejected = 0;
  for (Eigen::Index k = 0; k < mo; ++k) {
    const Eigen::Index block = index_(k) / b;
    while (next_rejected < rejected_blocks_.size() && rejected_blocks_[next_rejected] < block)
      ++next_rejected;
    if (next_rejected < rejected_blocks_.size() && rejected_blocks_[next_rejected] == block) continue;
    kept_(kept++) = k;
  }
  // Compact in place: every source position is at or after its destination, and the columns
  // (then rows) are written in ascending order, so nothing is read after it was overwritten.
  for (Eigen::Index j = 0; j < kept; ++j) {
    const Eigen::Index from_j = kept_(j);
    for (Eigen::Index i = j; i < kept; ++i) {
      if (diagonal_blocks && group_of(index_(kept_(i))) != group_of(index_(from_j))) break;  // past j's group
      cyy_(i, j) = cyy_(kept_(i), from_j);
    }
  }
  if (diagonal_blocks)
    for (Eigen::Index i = 0; i < kept; ++i) regression_.col(i) = regression_.col(kept_(i));
  else
    for (Eigen::Index c = 0; c < cyx_.cols(); ++c)
      for (Eigen::Index i = 0; i < kept; ++i) cyx_(i, c) = cyx_(kept_(i), c);
  for (Eigen::Index i = 0; i < kept; ++i) {
    index_(i) = index_(kept_(i));
    y_mean_(i) = y_mean_(kept_(i));
  }
  observed_count_ = kept;
  return kept;
}

S2KF_INLINE FilterCore::Iteration FilterCore::begin_iteration(
    const Eigen::Ref<const Eigen::VectorXd>& mean, const Eigen::Ref<const Eigen::MatrixXd>& covariance,
    const Eigen::VectorXd& y, const Eigen::MatrixXd& r) const {
  const Eigen::Index mo = observed_count_;
  Iteration iteration;
  iteration.y_observed.resize(mo);
  iteration.r_observed.resize(mo, mo);
  for (Eigen::Index i = 0; i < mo; ++i) {
    iteration.y_observed(i) = y(index_(i));
    for (Eigen::Index j = 0; j < mo; ++j) iteration.r_observed(i, j) = r(index_(i), index_(j));
  }
  iteration.mean = mean;
  iteration.covariance = covariance;
  return iteration;
}

S2KF_INLINE FilterStatus FilterCore::iteration_pass(const Eigen::Ref<const Eigen::VectorXd>& mean,
                                                    const Eigen::Ref<const Eigen::MatrixXd>& covariance,
                                                    Iteration& iteration, double& nis) {
  const Eigen::Index mo = observed_count_;
  centre_deviations();
  const Eigen::MatrixXd y_dev = y_dev_.topRows(mo);
  const Eigen::MatrixXd pyy = y_dev * samples_.weights.asDiagonal() * y_dev.transpose();
  const Eigen::MatrixXd pxy = x_dev_ * samples_.weights.asDiagonal() * y_dev.transpose();
  // H = Pxy^T C_i^-1 via the Cholesky factor of C_i already in factor_.
  const Eigen::MatrixXd h_lin = factor_.solve(pxy).transpose();
  const Eigen::MatrixXd omega = pyy - h_lin * iteration.covariance * h_lin.transpose();
  const Eigen::VectorXd offset = y_mean_.head(mo) - h_lin * iteration.mean;
  Eigen::MatrixXd s = h_lin * covariance * h_lin.transpose() + iteration.r_observed + omega;
  symmetrize(s);
  Eigen::LLT<Eigen::MatrixXd> llt(s);
  if (llt.info() != Eigen::Success) return FilterStatus::innovation_not_positive_definite;
  const Eigen::VectorXd innovation = iteration.y_observed - h_lin * mean - offset;
  const Eigen::MatrixXd gain_t = llt.solve(h_lin * covariance);  // K^T = S^-1 H C
  nis = innovation.dot(llt.solve(innovation));
  iteration.mean = mean + gain_t.transpose() * innovation;
  iteration.covariance = covariance - gain_t.transpose() * s * gain_t;
  symmetrize(iteration.covariance);
  return FilterStatus::ok;
}

S2KF_INLINE UpdateResult FilterCore::finish_iteration(Eigen::Ref<Eigen::VectorXd> mean,
                                                      Eigen::Ref<Eigen::MatrixXd> covariance,
                                                      const Iteration& iteration,
                                                      const UpdateOptions& options,
                                                      UpdateResult result) const {
  if (gated(result.nis, observed_count_, options)) {
    result.status = FilterStatus::gated;
    return result;
  }
  if (Eigen::LLT<Eigen::MatrixXd>(iteration.covariance).info() != Eigen::Success) {
    result.status = FilterStatus::posterior_not_positive_definite;
    return result;
  }
  mean = iteration.mean;
  covariance = iteration.covariance;
  return result;
}

}  // namespace detail
}  // namespace s2kf
