/// @file
/// The Smart Sampling Kalman Filter: a linear-regression Kalman filter whose samples are an optimal
/// deterministic (or any other) sample set of N(0, I), mapped through the Cholesky factor of the
/// prior. Prediction and measurement update with additive Gaussian noise, missing measurement
/// components, NIS, gating and iterated (posterior-linearised) update.
#pragma once

#include <s2kf/core/bordered_cholesky.hpp>
#include <s2kf/core/chi_square.hpp>
#include <s2kf/core/compilation_mode.hpp>
#include <s2kf/core/error.hpp>
#include <s2kf/core/gaussian.hpp>
#include <s2kf/core/product_tiles.hpp>
#include <s2kf/core/sample_set.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace s2kf {

/// Which measurement components are present this step; absent ones are dropped from y, y^, Cyy and
/// Cxy before the gain (never zero-filled).
using ObservedMask = Eigen::Array<bool, Eigen::Dynamic, 1>;

struct UpdateOptions {
  /// 1: the ordinary update. k > 1: k passes of posterior linearisation (each re-samples at the
  /// current posterior, fits y ~ H x + b with its residual covariance, and updates from the prior).
  int iterations = 1;
  /// 0 disables gating; otherwise the update is rejected (status gated) when the NIS exceeds the
  /// chi-square quantile of this probability with as many degrees of freedom as observed components.
  double gate_probability = 0;
  /// Robust update against outlying parts of the measurement (a mislabelled or stuck marker): the
  /// measurement is split into blocks of `block_size` consecutive components (a marker's x, y, z),
  /// and a block whose own NIS, against its predicted covariance, exceeds the chi-square quantile
  /// of `block_gate_probability` is left out of this update (rejected_blocks() lists them). When
  /// more than half of the observed blocks would be left out, none is: then the prediction itself
  /// is off, and the data must pull it back. 0 disables it; the ordinary (not iterated) update only.
  double block_gate_probability = 0;
  int block_size = 1;
  /// Accumulate the moments Cyy and Cyx (the sums over all samples, the step's largest cost) in
  /// single precision: the deviations are formed in double and rounded once, the sums run in float
  /// (relative error ~1e-7 of the sum of magnitudes, far below a positive definite noise R), and
  /// the factorisation, gain and update stay in double. About twice as fast with wide SIMD. The
  /// ordinary (not iterated) update with positive weights only; off by default.
  bool single_precision_moments = false;
  /// The gain in information form, for measurements made of independent blocks (a marker's x, y,
  /// z): the samples give the statistical linearisation G = Cyx S^-T (S the prior's Cholesky
  /// factor) and, per block of `block_size` components, the spread of the predictions that G does
  /// not explain; the innovation covariance is taken as G G^T + D, D block-diagonal with those
  /// spreads plus R's blocks, and the update is solved in the state's whitened coordinates:
  /// M = I + G^T D^-1 G (n x n), mean += S M^-1 G^T D^-1 (y - y^), C+ = S M^-1 S^T. The full m x m
  /// Cyy is never formed or factorised, so the cost is O(m n L + m n^2) instead of
  /// O(m^2 L + m^3). Equal to the ordinary update (to rounding) for a linear model, and for any
  /// model when no prediction's nonlinear part is correlated across blocks (with one block for the
  /// whole measurement, always). What it leaves out is the correlation between blocks of the
  /// predictions' nonlinear parts, which is small where the prior is narrow against the model's
  /// curvature. Taken only where it is exact in the linear case: positive weights, a sample set
  /// with zero mean and identity covariance (every LCD, UKF or moment-corrected set), R zero
  /// between blocks, the ordinary (not iterated) update; otherwise the ordinary update runs.
  bool information_form = false;
  /// The information form's limit on how nonlinear the model may be over the samples. Per observed
  /// group, nu_g = trace(C_g - G_g G_g^T) / trace(R_g) is the predictions' spread that the
  /// linearisation does not explain, against the noise. The cross-group correlations the form
  /// leaves out are bounded by those spreads (|Omega_ij| <= sqrt(Omega_ii Omega_jj)), so where the
  /// geometric mean of the two largest nu_g exceeds the limit this update runs the ordinary way;
  /// below it they are small against R, and one nonlinear group alone leaves the form exact.
  /// Infinity: never fall back.
  double information_form_max_nonlinearity = std::numeric_limits<double>::infinity();
  /// The information form's groups: one id per measurement component, for measurements whose
  /// blocks' nonlinear parts are correlated in known groups (the markers of one limb all move with
  /// its shoulder or hip). D is then block-diagonal by group instead of by block: the correlation
  /// within a group is kept and only that between groups is left out, so with one group for the
  /// whole measurement the update is the ordinary one. Ids must not decrease along the components
  /// (a group's components are consecutive), and each block of `block_size` must lie in one
  /// group. Null: every block is a group of its own. Read during update() only.
  const std::vector<int>* information_groups = nullptr;
  /// The information form's shared second order: state coordinates (indices) whose pairwise
  /// products delta_i delta_j every group's predictions depend on, such as the orientation of a
  /// root that all groups hang from. The form then regresses the predictions on those d (d + 1) / 2
  /// products as well (whitened over the samples) and carries them as that many more coordinates
  /// of the information matrix, so their part of the predictions' nonlinearity, which the groups
  /// share, is kept instead of left out; the state's posterior is their marginal. Taken with
  /// symmetric sample sets (pairs +z, -z, on which the products are uncorrelated with the state);
  /// at most 6 coordinates, each once. Null or empty: none. Read during update() only.
  const std::vector<int>* information_quadratic_states = nullptr;
  /// Which state coordinates each block's predictions depend on: one list of state indices per
  /// block of `block_size` components (a marker reads the root's pose and the joints between the
  /// root and its segment). Null: every block reads every state. A state that no observed block
  /// reads is not correlated with this measurement except through its prior correlation with the
  /// states that are read, but a finite sample set gives it a sample cross-covariance all the same;
  /// with innovations that keep their sign frame after frame (a hidden hand while the body moves)
  /// that noise moves the state steadily. With the lists, the update takes the cross-covariance of
  /// the unread states u as their prior regression on the read states o, P_uo P_oo^-1 Cov(x_o, y),
  /// which is exact for a model that reads only x_o: in the whitened coordinates, the regression
  /// projected onto the read states' span. Both gains (not the iterated update, which the tracker
  /// runs only in its first frames); read during update() only.
  const std::vector<std::vector<int>>* block_dependencies = nullptr;
};

struct UpdateResult {
  FilterStatus status = FilterStatus::ok;
  double nis = std::numeric_limits<double>::quiet_NaN();  ///< normalised innovation squared t^T t
  Eigen::Index observed = 0;                              ///< number of observed components used
  Eigen::Index rejected_blocks = 0;  ///< blocks left out by UpdateOptions::block_gate_probability
  bool ok() const { return status == FilterStatus::ok; }
};

namespace detail {

/// The filter's arithmetic, for every state dimension and every model: the checks, drawing the
/// samples, gathering the model's predictions, the moments, the outlier gate, the square-root gain
/// and the update, the prediction's moments and the iterated update's passes. None of it depends on
/// the model's type or on a state dimension fixed at compile time, so it is one class, compiled once
/// (in the compiled library, or once per file header-only); SmartSamplingKalmanFilter adds the
/// model's evaluation and the state's type.
class FilterCore {
 public:
  explicit FilterCore(SampleSet samples);

  const SampleSet& samples() const { return samples_; }

  /// The blocks (component index / block size) the last update left out as outlying.
  const std::vector<Eigen::Index>& rejected_blocks() const { return rejected_blocks_; }

 protected:
  static void check_square(const Eigen::MatrixXd& a, Eigen::Index n, const char* what) {
    if (a.rows() != n || a.cols() != n)
      throw DimensionError(std::string(what) + " is " + std::to_string(a.rows()) + "x" +
                           std::to_string(a.cols()) + ", expected " + std::to_string(n) + "x" +
                           std::to_string(n));
  }

  template <typename Matrix>
  static void symmetrize(Matrix& c) {
    c = (0.5 * (c + c.transpose())).eval();
  }

  bool gated(double nis, Eigen::Index dof, const UpdateOptions& options) const {
    return options.gate_probability > 0 &&
           nis > chi_square_quantile(options.gate_probability, static_cast<double>(dof));
  }

  void select_observed(const ObservedMask& observed) {
    index_.resize(observed.size());
    kept_.resize(observed.size());
    observed_count_ = 0;
    for (Eigen::Index i = 0; i < observed.size(); ++i)
      if (observed(i)) index_(observed_count_++) = i;
  }

  /// The information form's group of a measurement component (UpdateOptions::information_groups,
  /// else its block), as set by begin_update.
  Eigen::Index group_of(Eigen::Index component) const {
    return groups_ != nullptr ? (*groups_)[static_cast<std::size_t>(component)]
                              : component / group_block_size_;
  }

  /// Checks UpdateOptions::information_groups against the measurement and keeps them, with the
  /// largest group's size, for group_of and the moments.
  void set_groups(Eigen::Index m, const UpdateOptions& options);

  /// Checks UpdateOptions::information_quadratic_states against the state and sets
  /// quadratic_count_, the number of products the information form regresses on (0 without them).
  void set_quadratic_states(Eigen::Index n, const UpdateOptions& options);

  /// The checks of update() and the observed components; a status other than ok ends the update.
  UpdateResult begin_update(Eigen::Index state_dimension, const Eigen::VectorXd& y, const Eigen::MatrixXd& r,
                            const ObservedMask& observed, const UpdateOptions& options);

  /// After the model's evaluation: the moments, the square-root gain and the update of `state`.
  UpdateResult finish_update(Eigen::Ref<Eigen::VectorXd> mean, Eigen::Ref<Eigen::MatrixXd> covariance,
                             const Eigen::VectorXd& y, const Eigen::MatrixXd& r, const UpdateOptions& options,
                             UpdateResult result);

  /// UpdateOptions::information_form, after its moments (G^T in regression_, the diagonal blocks
  /// of Cyy with R's) and the block gate: each block whitened, the n x n information matrix, and
  /// the update of `state`.
  UpdateResult information_form_gain(Eigen::Ref<Eigen::VectorXd> mean, Eigen::Ref<Eigen::MatrixXd> covariance,
                                     const Eigen::VectorXd& y, const UpdateOptions& options,
                                     UpdateResult result);

  /// Copies the lower half of posterior_covariance_ into its upper half and factorises it (into
  /// factor_): whether the posterior is positive definite.
  bool complete_posterior_is_positive_definite() {
    posterior_covariance_.template triangularView<Eigen::StrictlyUpper>() =
        posterior_covariance_.transpose().template triangularView<Eigen::StrictlyUpper>();
    factor_.compute(posterior_covariance_);
    return factor_.info() == Eigen::Success;
  }

  /// UpdateOptions::block_dependencies, after the samples are drawn (it needs the prior's factor
  /// S) and the buffers reserved (m: the measurement's dimension): the states no observed block reads (u) and
  /// an orthonormal basis Q of their whitened directions, W = S^-1 E_u orthonormalised as W L^-T with W^T W =
  /// L L^T. Returns |u| (0 without the lists or when every state is read).
  Eigen::Index prepare_unread_states(Eigen::Index n, Eigen::Index m, const UpdateOptions& options);

  /// Removes the unread states' directions from the whitened regression G^T (n x columns): the
  /// regression on the read states alone (UpdateOptions::block_dependencies).
  void project_out_unread(Eigen::Ref<Eigen::MatrixXd> whitened_regression);

  /// The same for the ordinary update's Cyx (observed x n): with Z = S^-1 Cxy and C = Q^T Z,
  /// Cxy - S Q C, where S Q = E_u L^-T, so only the unread states' columns of Cyx change.
  void localise_cross_covariance(Eigen::Block<Eigen::MatrixXd>& cyx);

  /// Whether the information form applies to this update (see UpdateOptions::information_form).
  bool information_form_applies(const Eigen::MatrixXd& r, const UpdateOptions& options) const;

  /// Adds sum_i d_i d_i^T over the columns of `d` (deviations already scaled by sqrt(w)) to the
  /// diagonal blocks of the lower half of `cyy`, blocks being the observed rows of one group
  /// (group_of) instead of the whole m x m rank update. Small groups (a marker's x, y, z): a
  /// product per row and offset within the group, accumulated column by column; larger ones (a
  /// limb's markers): one rank update per group.
  /// With `centre` (float_deviations_): d holds deviations from another point and no weights, and
  /// the blocks receive `scale` sum d_i d_i^T - centre_weight_ centre centre^T.
  template <typename Scalar, typename Deviations>
  void add_diagonal_block_moments(Eigen::Block<Eigen::MatrixXd>& cyy, const Deviations& d,
                                  Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>& products,
                                  double scale = 1, const double* centre = nullptr) const {
    const auto moment = [&](Eigen::Index i, Eigen::Index j, Scalar product) {
      return centre == nullptr
                 ? static_cast<double>(product)
                 : scale * static_cast<double>(product) - centre_weight_ * centre[i] * centre[j];
    };
    const Eigen::Index mo = d.rows(), width = group_width_;  // `products`: reserve_moment_buffers
    if (width > kMaxBlock) {
      for (Eigen::Index k = 0; k < mo;) {
        Eigen::Index end = k;
        while (end < mo && group_of(index_(end)) == group_of(index_(k))) ++end;
        auto block = products.topLeftCorner(end - k, end - k);
        block.setZero();
        if constexpr (std::is_same_v<Scalar, float>)
          add_self_product_lower(block, d.middleRows(k, end - k));
        else
          block.template selfadjointView<Eigen::Lower>().rankUpdate(d.middleRows(k, end - k));
        for (Eigen::Index j = 0; j < end - k; ++j)
          for (Eigen::Index i = j; i < end - k; ++i) cyy(k + i, k + j) += moment(k + i, k + j, block(i, j));
        k = end;
      }
      return;
    }
    products.topLeftCorner(mo, width).setZero();
    for (Eigen::Index i = 0; i < d.cols(); ++i) {
      const auto column = d.col(i);
      for (Eigen::Index s = 0; s < width && s < mo; ++s)
        products.col(s).head(mo - s).array() +=
            column.head(mo - s).array() * column.segment(s, mo - s).array();
    }
    for (Eigen::Index k = 0; k < mo; ++k)
      for (Eigen::Index s = 0; s < width && k + s < mo; ++s)
        if (group_of(index_(k + s)) == group_of(index_(k))) cyy(k + s, k) += moment(k + s, k, products(k, s));
  }

  /// After the system model's evaluation (in propagated_): the predicted mean and covariance.
  FilterStatus finish_predict(Eigen::Ref<Eigen::VectorXd> mean, Eigen::Ref<Eigen::MatrixXd> covariance,
                              const Eigen::MatrixXd& q);

  /// x_i = m + S z_i with S the lower Cholesky factor of C; keeps the deviations S z_i in x_dev_
  /// (a symmetric set: S z_k of its + half in half_deviation_, or with `single_precision` in float
  /// in drawn_deviation_f_, and x_ and half_deviation_ only from complete_drawn_samples()).
  FilterStatus draw_samples(const Eigen::Ref<const Eigen::VectorXd>& mean,
                            const Eigen::Ref<const Eigen::MatrixXd>& covariance,
                            bool single_precision = false);

  /// x_ from the mean and half_deviation_ (a symmetric set).
  void mirror_half_deviations(const Eigen::Ref<const Eigen::VectorXd>& mean);

  /// After a draw in single precision: half_deviation_ and x_ in double, for whatever reads them.
  void complete_drawn_samples();

  /// Recognises the symmetric layout of symmetric_set and ukf_sample_set: an optional origin first,
  /// then +s_1..+s_h, then -s_1..-s_h, with equal weights within each pair (exact comparisons).
  void detect_symmetry();

  /// Eigen's matrix products take their packing buffers from the stack up to 128 KiB and from the
  /// heap beyond; products over at most kChunk samples (150 x 96 doubles) stay on the stack, so a
  /// step does not allocate. Measured no slower than one product over all samples.
  static constexpr Eigen::Index kChunk = 96;

  /// Lower half of c += d d^T: in the register tiles compiled for the processor
  /// (core/product_tiles.hpp) where d is column-major, else as rank-kChunk updates.
  template <typename Target, typename Deviations>
  static void rank_update_lower(Target& c, const Deviations& d) {
    using D = std::decay_t<Deviations>;
    if constexpr (!D::IsRowMajor && (D::Flags & Eigen::DirectAccessBit) != 0) {
      add_self_product_lower(c, d);
    } else {
      for (Eigen::Index k = 0; k < d.cols(); k += kChunk)
        c.template selfadjointView<Eigen::Lower>().rankUpdate(
            d.middleCols(k, std::min(kChunk, d.cols() - k)));
    }
  }

  /// Columns times sqrt(w_i); one scalar when all weights are equal.
  template <typename Block>
  void scale_columns_by_sqrt_weights(Block& block) const {
    if (equal_weights_)
      block *= sqrt_weights_(0);
    else
      block = block * sqrt_weights_.asDiagonal();
  }

  /// Sizes the buffers for m predicted components and returns the one the model writes into: with
  /// every component observed the model writes straight into y_dev_ (no gather).
  Eigen::MatrixXd& prepare_predictions(Eigen::Index m);

  /// prepare_predictions for a model that writes float deviations from its mean prediction
  /// (evaluate_symmetric_deviations): the buffer it writes them into, y_dev_f_ itself when every
  /// component is observed, and the double buffers sized for a fallback as well.
  Eigen::Block<Eigen::MatrixXf> prepare_float_predictions(Eigen::Index m);

  /// After evaluate_symmetric_deviations: the observed rows of the deviations d_i in y_dev_f_ (not
  /// centred, not scaled; float_deviations_), their weighted mean in deviation_centre_, the
  /// predictions' mean (mean_prediction_ plus it) in y_mean_, each row's spread in
  /// component_spread_ and the pairs' differences d+_k - d-_k, all in one pass over the columns.
  FilterStatus gather_float_deviations(Eigen::Index m);

  /// y_dev_ (observed rows) = y_i - y^ in double from the float deviations, for the passes that
  /// read them in double (the ordinary update).
  void expand_float_deviations();

  /// y_dev_f_ = sqrt(w_i) (y_i - y^) from the float deviations (what the quadratic regression
  /// reads), after expand_float_deviations.
  void normalise_float_deviations();

  /// The observed rows of the model's predictions in y_dev_ and their weighted mean in y_mean_;
  /// the deviations from it are formed by centre_deviations() where they are read in double.
  FilterStatus gather_observed(Eigen::Index m);

  /// y_dev_ (observed rows) -= y_mean_, once after gather_observed. The default update's
  /// single-precision regression subtracts the mean as it rounds instead: one pass less.
  void centre_deviations() {
    if (centred_) return;
    y_dev_.topRows(observed_count_).colwise() -= y_mean_.head(observed_count_);
    centred_ = true;
  }

  /// The lower half of Cyy += sum w (y_i - y^)(y_i - y^)^T and Cyx = sum w (y_i - y^)(x_i - m)^T
  /// over the observed rows in y_dev_ (deviations) and x_dev_ / half_deviation_ (S z_i).
  /// `deviations_scaled`: y_dev_ already holds sqrt(w_i) (y_i - y^) (after the information
  /// form's moments fell back to the ordinary update).
  void accumulate_moments(Eigen::Block<Eigen::MatrixXd>& cyy, Eigen::Block<Eigen::MatrixXd>& cyx,
                          bool single_precision, bool deviations_scaled = false);

  /// The geometric mean of the two largest trace(C_g - G_g G_g^T) / trace(R_g) over the observed
  /// groups, after accumulate_regression (UpdateOptions::information_form_max_nonlinearity).
  double information_form_nonlinearity(const Eigen::MatrixXd& r) const;

  /// UpdateOptions::information_form: sets regression_ (n x observed) to G^T = sum w z_i (y_i - y^)^T,
  /// the predictions' regression on the whitened state (the samples z_i of N(0, I) themselves, so
  /// no solve with the prior's factor is needed), and component_spread_ to each observed
  /// component's sum w (y_i - y^)^2. Leaves the deviations scaled by sqrt(w) (in y_dev_f_ in
  /// single precision, in place in y_dev_ in double) for add_diagonal_block_moments.
  void accumulate_regression(bool single_precision);

  /// UpdateOptions::information_quadratic_states, after accumulate_regression: the first
  /// quadratic_count_ rows of regression_ set to the predictions' regression on the whitened
  /// products delta_a delta_b of those states (pairs +z, -z: uncorrelated with z).
  void accumulate_quadratic_regression(bool single_precision);

  /// The top-left rows x cols of a single-precision scratch matrix, grown when needed.
  static Eigen::Block<Eigen::MatrixXf> single_buffer(Eigen::MatrixXf& buffer, Eigen::Index rows,
                                                     Eigen::Index cols) {
    if (buffer.rows() < rows || buffer.cols() < cols)
      buffer.resize(std::max(buffer.rows(), rows), std::max(buffer.cols(), cols));
    return buffer.topLeftCorner(rows, cols);
  }

  /// UpdateOptions::block_gate_probability: finds the observed blocks whose innovation is
  /// improbable under their own predicted covariance, C_b = sum_i w_i d_i d_i^T + R_bb (d_i the
  /// block's sample deviations), which is the block's diagonal block of Cyy (lower half, already
  /// accumulated), and removes their rows (and columns) from Cyy, Cyx, the observed indices and the
  /// predicted mean. Returns the number of observed components kept. With `diagonal_blocks` (the
  /// information form) only the diagonal blocks of Cyy are held and moved, and the columns of
  /// regression_ instead of the rows of Cyx.
  Eigen::Index reject_outlying_blocks(const Eigen::VectorXd& y, const UpdateOptions& options,
                                      bool diagonal_blocks = false);
  static constexpr int kMaxBlock = 6;

  /// Sizes the moments' buffers for every component of an m-dimensional measurement, those of the
  /// ordinary update and, with `information_form`, those of the information form as well (the
  /// information form's steps rely on it and grow nothing themselves): a later frame with more
  /// components observed, or one whose samples are too nonlinear for the information form, then
  /// allocates nothing.
  void reserve_moment_buffers(Eigen::Index m, Eigen::Index n, bool single_precision, bool information_form) {
    cyy_buffer(m);
    cyx_buffer(m, n);
    // The gain's panel: Cyy, a group's D or the information matrix (with the products' rows).
    bordered_.resize(std::max(m, n + quadratic_count_), n + quadratic_count_ + 1);
    const Eigen::Index count = samples_.count(), h = half_count_;
    if (single_precision) {
      single_buffer(y_dev_f_, m, count);
      single_buffer(cyy_f_, m, m);
      single_buffer(cyx_f_, m, n);
      if (symmetric_) {
        single_buffer(pair_difference_f_, m, h);
        single_buffer(half_deviation_f_, n, h);
      }
    }
    if (!information_form) return;
    if (component_spread_.size() < m) component_spread_.resize(m);
    if (single_precision) single_buffer(component_spread_f_, m, 1);
    const Eigen::Index regressors = quadratic_count_ + n;  // the products first, then the state
    if (regression_.rows() != regressors || regression_.cols() < m)
      regression_.resize(regressors, std::max(regression_.cols(), m));
    if (quadratic_count_ > 0) {
      quadratic_features_.resize(quadratic_count_, half_count_);
      if (pair_sum_.rows() < m || pair_sum_.cols() != half_count_) pair_sum_.resize(m, half_count_);
      if (single_precision) {
        single_buffer(quadratic_features_f_, quadratic_count_, half_count_);
        single_buffer(pair_sum_f_, m, half_count_);
        single_buffer(quadratic_cross_f_, quadratic_count_, m);
      }
    }
    Eigen::MatrixXd& products = block_products_;
    Eigen::MatrixXf& products_f = block_products_f_;
    if (products.rows() < m || products.cols() < group_width_) products.resize(m, group_width_);
    if (group_regression_.rows() < group_width_ || group_regression_.cols() != regressors)
      group_regression_.resize(std::max(group_regression_.rows(), group_width_), regressors);
    if (single_precision) {
      single_buffer(regression_f_, regressors, m);
      single_buffer(group_regression_f_, group_width_, regressors);
      single_buffer(group_products_f_, group_width_, group_width_);
      single_buffer(information_f_, regressors, regressors);
      if (products_f.rows() < m || products_f.cols() < group_width_) products_f.resize(m, group_width_);
    }
    state_step_.resize(n);
  }

  Eigen::Block<Eigen::MatrixXd> cyy_buffer(Eigen::Index mo) {
    if (cyy_.rows() < mo) cyy_.resize(mo, mo);
    innovation_.resize(std::max<Eigen::Index>(innovation_.size(), mo));
    return cyy_.topLeftCorner(mo, mo);
  }
  Eigen::Block<Eigen::MatrixXd> cyx_buffer(Eigen::Index mo, Eigen::Index n) {
    if (cyx_.rows() < mo || cyx_.cols() != n) cyx_.resize(std::max<Eigen::Index>(cyx_.rows(), mo), n);
    return cyx_.topRows(mo);
  }

  /// The iterated update's working copy: the observed y and R and the current posterior.
  struct Iteration {
    Eigen::VectorXd y_observed;
    Eigen::MatrixXd r_observed;
    Eigen::VectorXd mean;
    Eigen::MatrixXd covariance;
  };

  Iteration begin_iteration(const Eigen::Ref<const Eigen::VectorXd>& mean,
                            const Eigen::Ref<const Eigen::MatrixXd>& covariance, const Eigen::VectorXd& y,
                            const Eigen::MatrixXd& r) const;
  /// One pass on the samples just evaluated; sets the NIS of the linearised update.
  FilterStatus iteration_pass(const Eigen::Ref<const Eigen::VectorXd>& mean,
                              const Eigen::Ref<const Eigen::MatrixXd>& covariance, Iteration& iteration,
                              double& nis);
  UpdateResult finish_iteration(Eigen::Ref<Eigen::VectorXd> mean, Eigen::Ref<Eigen::MatrixXd> covariance,
                                const Iteration& iteration, const UpdateOptions& options,
                                UpdateResult result) const;

  /// Closed-form linear prediction (SmartSamplingKalmanFilter::predict_linear).
  FilterStatus linear_prediction(Eigen::Ref<Eigen::VectorXd> mean, Eigen::Ref<Eigen::MatrixXd> covariance,
                                 const Eigen::MatrixXd& a, const Eigen::MatrixXd& q) const;

  SampleSet samples_;
  bool positive_weights_ = true;
  bool unit_moments_ = false;  ///< the sample set has zero mean and identity covariance
  bool equal_weights_ = false;
  bool symmetric_ = false;             ///< see detect_symmetry
  bool keep_full_deviations_ = false;  ///< draw_samples fills x_dev_ even for a symmetric set
  Eigen::Index origin_count_ = 0, half_count_ = 0;
  Eigen::VectorXd sqrt_weights_;

  // Scratch space, grown to the largest sizes seen and then reused.
  Eigen::LLT<Eigen::MatrixXd> factor_;
  Eigen::MatrixXd x_dev_, x_, propagated_, predictions_, y_dev_, cyy_, cyx_, posterior_covariance_;
  Eigen::MatrixXd half_deviation_;  ///< S z_k of the +s half of a symmetric set (then times sqrt w)
  Eigen::MatrixXd half_points_t_;   ///< the z_k of that half, transposed (h x n): S Z^T's operand
  // draw_samples in single precision: S and Z^T in float, S z_k of the + half, the mean drawn
  // around, and whether x_ and half_deviation_ are still to be formed from them.
  Eigen::MatrixXf half_points_t_f_, lower_factor_f_, drawn_deviation_f_;
  Eigen::VectorXd drawn_mean_;
  bool double_samples_pending_ = false;
  Eigen::MatrixXd lower_factor_;     ///< S with zeros above its diagonal
  Eigen::MatrixXd pair_difference_;  ///< sqrt(w) (y+_k - y-_k) of the observed rows
  Eigen::VectorXd y_mean_, innovation_;
  Eigen::Matrix<Eigen::Index, Eigen::Dynamic, 1> index_;
  Eigen::Matrix<Eigen::Index, Eigen::Dynamic, 1> kept_;  ///< observed positions the block gate keeps
  Eigen::MatrixXf y_dev_f_, cyy_f_, pair_difference_f_, half_deviation_f_, cyx_f_;  ///< single precision
  // The information form: sqrt(w) z of the samples (the + half of a symmetric set), G^T, the
  // n x n system and the products per block (see add_diagonal_block_moments).
  Eigen::MatrixXd scaled_points_, regression_, block_products_;
  Eigen::MatrixXd group_regression_;  ///< a large group's G_b (G^T's columns transposed): G_b G_b^T's operand
  Eigen::MatrixXf scaled_points_f_, regression_f_, block_products_f_, component_spread_f_;
  // The information form in single precision: a large group's G_b and G_b G_b^T, and G^T G.
  Eigen::MatrixXf group_regression_f_, group_products_f_, information_f_;
  // UpdateOptions::information_quadratic_states: sqrt(w) times the products of each + sample, the
  // pair sums sqrt(w) (y+_k + y-_k - 2 y^) and the products' cross moments with them.
  const std::vector<int>* quadratic_states_ = nullptr;
  Eigen::Index quadratic_count_ = 0;
  Eigen::MatrixXd quadratic_features_, pair_sum_;
  Eigen::MatrixXf quadratic_features_f_, pair_sum_f_, quadratic_cross_f_;
  BorderedCholesky bordered_;  ///< Cyy, or a large group's D_g and then the information matrix
  Eigen::VectorXd state_step_;
  Eigen::Index observed_count_ = 0;
  bool direct_ = false;   ///< the model writes straight into y_dev_ (see prepare_predictions)
  bool centred_ = false;  ///< y_dev_ holds deviations from y_mean_, not the predictions
  /// y_dev_f_ holds the model's float deviations d_i from mean_prediction_ (observed rows), neither
  /// centred nor scaled (gather_float_deviations); y_dev_ is not filled.
  bool float_deviations_ = false;
  Eigen::MatrixXf predictions_f_;  ///< the float deviations of every row, where some are not observed
  Eigen::VectorXd mean_prediction_, deviation_centre_;  ///< h(mean); sum w d_i (observed rows)
  double centre_weight_ = 1;  ///< 2 - sum w: sum w (d - c)(d - c)^T = sum w d d^T - centre_weight_ c c^T
  std::vector<Eigen::Index> rejected_blocks_;  ///< ascending
  const std::vector<int>* groups_ = nullptr;   ///< UpdateOptions::information_groups of this update
  Eigen::Index group_block_size_ = 1;          ///< the block size, when groups_ is null
  Eigen::Index group_width_ = 1;               ///< the largest group's component count
  Eigen::VectorXd component_spread_;           ///< per observed component: sum w (y_i - y^)^2
  double block_limit_probability_ = 0;
  double block_limit_[kMaxBlock + 1] = {};  ///< chi-square quantiles by degrees of freedom
  // UpdateOptions::block_dependencies: per state whether an observed block reads it, the unread
  // states, their whitened basis Q (n x |u|), the factor L of W^T W, and scratch.
  std::vector<char> state_read_;
  Eigen::Matrix<Eigen::Index, Eigen::Dynamic, 1> unread_states_;
  Eigen::Index unread_count_ = 0;
  Eigen::MatrixXd unread_basis_, unread_factor_, unread_whitened_, unread_coefficients_;
};

/// Whether a measurement model has `evaluate_symmetric_deviations(mean, half_deviations (float),
/// origin_count, deviations (float), mean_prediction)` (see SmartSamplingKalmanFilter).
template <typename Model, typename = void>
struct EvaluatesSymmetricDeviations : std::false_type {};
template <typename Model>
struct EvaluatesSymmetricDeviations<
    Model, std::void_t<decltype(std::declval<Model&>().evaluate_symmetric_deviations(
               std::declval<const Eigen::VectorXd&>(), std::declval<const Eigen::MatrixXf&>(), Eigen::Index{},
               std::declval<Eigen::Block<Eigen::MatrixXf>&>(), std::declval<Eigen::VectorXd&>()))>>
    : std::true_type {};

/// Whether a measurement model has `evaluate_symmetric(states, mean, half_deviations, origin_count,
/// out)` (see SmartSamplingKalmanFilter).
template <typename Model, typename = void>
struct EvaluatesSymmetricSets : std::false_type {};
template <typename Model>
struct EvaluatesSymmetricSets<
    Model, std::void_t<decltype(std::declval<Model&>().evaluate_symmetric(
               std::declval<const Eigen::MatrixXd&>(), std::declval<const Eigen::VectorXd&>(),
               std::declval<const Eigen::MatrixXd&>(), Eigen::Index{}, std::declval<Eigen::MatrixXd&>()))>>
    : std::true_type {};
}  // namespace detail

/// A measurement model is any callable `h(const Eigen::MatrixXd& states, Eigen::MatrixXd& out)`
/// that maps a block of state samples (state dimension x L, one sample per column) to the block of
/// predicted measurements (measurement dimension x L; `out` arrives sized). A system model has the
/// same shape with the state dimension on both sides. Evaluating all samples in one call lets a
/// model vectorise across samples. A model may also have `evaluate_symmetric(states, mean,
/// half_deviations, origin_count, out)`: for a symmetric sample set (origin_count columns at the
/// mean, then mean + H and mean - H) the update calls it instead, with H = half_deviations, so the
/// model can evaluate the samples as deviations from the mean
/// (body::MarkerMeasurementModel::evaluate_symmetric).
///
/// The filter owns scratch buffers, so after the first step with the largest sizes, update() and
/// predict() do not allocate (for the non-iterated update with positive weights).
template <int Dim = Eigen::Dynamic>
class SmartSamplingKalmanFilter : public detail::FilterCore {
 public:
  using State = Gaussian<double, Dim>;

  explicit SmartSamplingKalmanFilter(SampleSet samples) : detail::FilterCore(std::move(samples)) {
    if (Dim != Eigen::Dynamic && samples_.dimension() != Dim)
      throw DimensionError("SmartSamplingKalmanFilter: sample dimension " +
                           std::to_string(samples_.dimension()) + " differs from the state dimension " +
                           std::to_string(Dim));
  }

  /// Closed-form linear prediction x <- A x + w, w ~ N(0, Q).
  FilterStatus predict_linear(State& state, const Eigen::MatrixXd& a, const Eigen::MatrixXd& q) const {
    return linear_prediction(state.mean, state.covariance, a, q);
  }

  /// Random walk x <- x + w, w ~ N(0, Q): only the covariance grows.
  FilterStatus predict_random_walk(State& state, const Eigen::MatrixXd& q) const {
    check_square(q, state.dimension(), "predict_random_walk: Q");
    state.covariance += q;
    return FilterStatus::ok;
  }

  /// Sample-based prediction through a nonlinear system model f (block form, see above):
  /// m <- sum w_i f(x_i), C <- sum w_i (f(x_i) - m)(f(x_i) - m)^T + Q.
  template <typename SystemModel>
  FilterStatus predict(State& state, SystemModel&& f, const Eigen::MatrixXd& q) {
    check_square(q, state.dimension(), "predict: Q");
    if (const FilterStatus s = draw_samples(state.mean, state.covariance); s != FilterStatus::ok) return s;
    propagated_.resize(state.dimension(), samples_.count());
    f(static_cast<const Eigen::MatrixXd&>(x_), propagated_);
    return finish_predict(state.mean, state.covariance, q);
  }

  /// Measurement update y = h(x) + v, v ~ N(0, R), with every component observed.
  template <typename MeasurementModel>
  UpdateResult update(State& state, MeasurementModel&& h, const Eigen::VectorXd& y, const Eigen::MatrixXd& r,
                      const UpdateOptions& options = {}) {
    return update(state, std::forward<MeasurementModel>(h), y, r, ObservedMask::Constant(y.size(), true),
                  options);
  }

  /// Measurement update with a mask of observed components. On any status but ok the state is
  /// left exactly as it was.
  template <typename MeasurementModel>
  UpdateResult update(State& state, MeasurementModel&& h, const Eigen::VectorXd& y, const Eigen::MatrixXd& r,
                      const ObservedMask& observed, const UpdateOptions& options = {}) {
    // Only the model's evaluation depends on the model's type; everything around it is
    // detail::FilterCore, compiled once, so a new model costs its own code and not another copy
    // of the filter.
    UpdateResult result = begin_update(state.dimension(), y, r, observed, options);
    if (!result.ok()) return result;
    if (options.iterations > 1) return iterated_update(state, h, y, r, options, result);
    if ((result.status = draw_samples(state.mean, state.covariance,
                                      options.single_precision_moments && positive_weights_)) !=
        FilterStatus::ok)
      return result;
    if ((result.status = evaluate_observed(h, y.size(), state.mean)) != FilterStatus::ok) return result;
    return finish_update(state.mean, state.covariance, y, r, options, result);
  }

 private:
  /// Runs h on the current samples (drawn around `mean`), keeps the observed rows as deviations
  /// from their weighted mean.
  template <typename MeasurementModel>
  FilterStatus evaluate_observed(MeasurementModel& h, Eigen::Index m,
                                 const Eigen::Ref<const Eigen::VectorXd>& mean) {
    if constexpr (detail::EvaluatesSymmetricDeviations<std::remove_reference_t<MeasurementModel>>::value) {
      // Samples drawn in float (single-precision moments): the model's deviations go to the
      // moments in float, never through double predictions.
      if (double_samples_pending_ && equal_weights_) {
        auto deviations = prepare_float_predictions(m);
        if (h.evaluate_symmetric_deviations(mean, drawn_deviation_f_, origin_count_, deviations,
                                            mean_prediction_))
          return gather_float_deviations(m);
      }
    }
    Eigen::MatrixXd& predictions = prepare_predictions(m);
    complete_drawn_samples();
    if constexpr (detail::EvaluatesSymmetricSets<std::remove_reference_t<MeasurementModel>>::value) {
      if (symmetric_ && !keep_full_deviations_) {  // half_deviation_ holds S z of the + half, unscaled
        h.evaluate_symmetric(static_cast<const Eigen::MatrixXd&>(x_), mean,
                             static_cast<const Eigen::MatrixXd&>(half_deviation_), origin_count_,
                             predictions);
        return gather_observed(m);
      }
    }
    h(static_cast<const Eigen::MatrixXd&>(x_), predictions);
    return gather_observed(m);
  }

  /// Posterior linearisation: fit y ~ H x + b (residual covariance Omega) at the current posterior,
  /// update the prior with that linear model, repeat.
  template <typename MeasurementModel>
  UpdateResult iterated_update(State& state, MeasurementModel& h, const Eigen::VectorXd& y,
                               const Eigen::MatrixXd& r, const UpdateOptions& options, UpdateResult result) {
    Iteration iteration = begin_iteration(state.mean, state.covariance, y, r);
    keep_full_deviations_ = true;  // this rarely used path works on all deviations
    struct Restore {
      bool& flag;
      ~Restore() { flag = false; }
    } restore{keep_full_deviations_};
    for (int pass = 0; pass < options.iterations; ++pass) {
      if ((result.status = draw_samples(iteration.mean, iteration.covariance)) != FilterStatus::ok)
        return result;
      if ((result.status = evaluate_observed(h, y.size(), iteration.mean)) != FilterStatus::ok) return result;
      if ((result.status = iteration_pass(state.mean, state.covariance, iteration, result.nis)) !=
          FilterStatus::ok)
        return result;
    }
    return finish_iteration(state.mean, state.covariance, iteration, options, result);
  }
};

using S2kf = SmartSamplingKalmanFilter<Eigen::Dynamic>;

}  // namespace s2kf

#if !defined(S2KF_COMPILED)
#include <s2kf/core/smart_sampling_kalman_filter.hxx>
#endif
