/// @file
/// The estimation core from Python: sample sets (optimal LCD, UKF, random, user-given), Gaussian
/// states, and SmartSamplingKalmanFilter with Python callables as system and measurement models.
/// A model is called once per step with the whole sample block, samples as rows: h(x) with x of
/// shape (L, N) returns (L, M), so numpy code vectorises across samples.
#include "bindings.hpp"
#include "numpy_bridge.hpp"

#include <s2kf/core/sample_set.hpp>
#include <s2kf/core/smart_sampling_kalman_filter.hpp>
#include <s2kf/io/sample_cache.hpp>

#include <pybind11/stl.h>

#include <cstdint>
#include <string>

namespace s2kf::python {
namespace {

using Filter = SmartSamplingKalmanFilter<Eigen::Dynamic>;

/// (n,) numpy -> Eigen vector (a small copy: the filter's signatures take Eigen vectors).
Eigen::VectorXd vector_argument(const py::handle& value, const std::string& what) {
  const DoubleArray array = as_double_array(value, what);
  if (array.ndim() != 1) throw py::value_error(what + " must be a 1-D array, got shape " + shape_text(array));
  return Eigen::Map<const Eigen::VectorXd>(array.data(), array.shape(0));
}

/// (r, c) numpy -> Eigen matrix.
Eigen::MatrixXd matrix_argument(const py::handle& value, const std::string& what) {
  const DoubleArray array = as_double_array(value, what);
  if (array.ndim() != 2) throw py::value_error(what + " must be a 2-D array, got shape " + shape_text(array));
  return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      array.data(), array.shape(0), array.shape(1));
}

void require_square(const Eigen::MatrixXd& matrix, Eigen::Index n, const std::string& what) {
  if (matrix.rows() != n || matrix.cols() != n)
    throw py::value_error(what + " must be " + std::to_string(n) + " x " + std::to_string(n) + ", got " +
                          std::to_string(matrix.rows()) + " x " + std::to_string(matrix.cols()));
}

/// A read-only numpy view (L, N) of a column-major N x L sample block owned by `owner`.
py::array read_only_samples(const Eigen::MatrixXd& block, const py::handle& owner) {
  py::array view(py::dtype::of<double>(), {block.cols(), block.rows()},
                 {static_cast<py::ssize_t>(sizeof(double)) * block.rows(), py::ssize_t{sizeof(double)}},
                 block.data(), owner);
  py::detail::array_proxy(view.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return view;
}

/// Adapts a Python callable to the filter's block model interface. The samples go to Python as a
/// read-only view of the filter's own buffer (valid during the call; the filter object is its
/// owner), and the result, (L, M), is copied into the filter's output block.
struct PythonModel {
  py::handle function;
  py::handle filter_object;
  const char* role;  // "measurement model" or "system model", for error messages

  void operator()(const Eigen::MatrixXd& states, Eigen::MatrixXd& out) const {
    py::gil_scoped_acquire locked;
    const py::object result = function(read_only_samples(states, filter_object));
    const DoubleArray values = as_double_array(result, std::string("the ") + role + "'s result");
    const py::ssize_t count = states.cols(), rows = out.rows();
    require_shape(values, {count, rows}, std::string("the ") + role + "'s result",
                  "(L, M) = (" + std::to_string(count) + ", " + std::to_string(rows) + ")");
    out = Eigen::Map<const Eigen::MatrixXd>(values.data(), rows, count);  // C (L, M) = column-major M x L
  }
};

void check_callable(const py::handle& function, const char* role) {
  if (!PyCallable_Check(function.ptr()))
    throw py::type_error(std::string("the ") + role + " must be callable: f(x) with x of shape (L, N)");
}

void check_state(const Filter& filter, const GaussianXd& state) {
  if (filter.samples().dimension() != state.dimension())
    throw py::value_error("the state has dimension " + std::to_string(state.dimension()) +
                          " but the filter's samples " + std::to_string(filter.samples().dimension()));
}

SampleSet sample_set_from_points(const py::handle& points_value, const py::handle& weights_value) {
  const DoubleArray points = as_double_array(points_value, "points");
  require_shape(points, {-1, -1}, "points", "(L, N)");
  if (points.shape(0) < 1 || points.shape(1) < 1) throw py::value_error("points must not be empty");
  if (!Eigen::Map<const Eigen::ArrayXd>(points.data(), points.size()).allFinite())
    throw py::value_error("points must be finite");
  SampleSet set = equally_weighted(
      Eigen::Map<const Eigen::MatrixXd>(points.data(), points.shape(1), points.shape(0)), "user");
  if (!weights_value.is_none()) {
    const Eigen::VectorXd weights = vector_argument(weights_value, "weights");
    if (weights.size() != set.count())
      throw py::value_error("weights must have one entry per sample (" + std::to_string(set.count()) +
                            "), got " + std::to_string(weights.size()));
    if (!weights.allFinite()) throw py::value_error("weights must be finite");
    set.weights = weights;
  }
  return set;
}

GaussianXd make_gaussian(const py::handle& mean_value, const py::handle& covariance_value) {
  GaussianXd state;
  state.mean = vector_argument(mean_value, "mean");
  state.covariance = matrix_argument(covariance_value, "covariance");
  require_square(state.covariance, state.mean.size(), "covariance");
  if (!state.mean.allFinite() || !state.covariance.allFinite())
    throw py::value_error("mean and covariance must be finite");
  return state;
}

}  // namespace

void bind_filter(py::module_& module) {
  py::class_<SampleSet>(module, "SampleSet",
                        "Samples z_i of N(0, I) with weights: points (L, N), one sample per row.")
      .def(py::init(&sample_set_from_points), py::arg("points"), py::arg("weights") = py::none(),
           "your own samples (L, N); weights default to 1/L")
      .def_property_readonly(
          "points",
          [](py::object self) {
            const SampleSet& s = self.cast<const SampleSet&>();
            return py::array_t<double>({s.count(), s.dimension()}, s.points.data(), self);
          },
          "(L, N), a view")
      .def_property_readonly("weights", [](const SampleSet& s) { return vector_copy(s.weights); })
      .def_readonly("kind", &SampleSet::kind)
      .def_property_readonly("dimension", &SampleSet::dimension)
      .def_property_readonly("count", &SampleSet::count)
      .def("__repr__", [](const SampleSet& s) {
        return "<s2kf.SampleSet " + s.kind + ": " + std::to_string(s.count()) + " samples in " +
               std::to_string(s.dimension()) + " dimensions>";
      });

  module.def(
      "sample_set",
      [](int dimension, int count, std::uint64_t seed) {
        LcdOptions options;
        options.seed = seed;
        py::gil_scoped_release unlocked;
        return lcd_sample_set(dimension, count, options).set;
      },
      py::arg("dimension"), py::arg("count"), py::arg("seed") = 1,
      "The optimal symmetric LCD sample set of the S2KF (count >= 2 * dimension), from the disk cache "
      "($S2KF_CACHE_DIR, else ~/.cache/s2kf) or computed and stored. Runs without the GIL.");
  module.def(
      "ukf_sample_set", [](int dimension, double kappa) { return ukf_sample_set(dimension, kappa); },
      py::arg("dimension"), py::arg("kappa") = 0.5, "the unscented set: origin and +-sqrt(N + kappa) e_k");
  module.def(
      "random_sample_set",
      [](int dimension, int count, std::uint64_t seed) { return random_sample_set(dimension, count, seed); },
      py::arg("dimension"), py::arg("count"), py::arg("seed") = 1,
      "seeded i.i.d. normal draws, moment-corrected (count > dimension)");

  py::class_<GaussianXd>(module, "Gaussian",
                         "A Gaussian state N(mean, covariance); the filter updates it in place.")
      .def(py::init(&make_gaussian), py::arg("mean"), py::arg("covariance"))
      .def_property(
          "mean",
          [](py::object self) {
            GaussianXd& g = self.cast<GaussianXd&>();
            return py::array_t<double>(g.mean.size(), g.mean.data(), self);
          },
          [](GaussianXd& g, const py::handle& value) {
            Eigen::VectorXd mean = vector_argument(value, "mean");
            if (mean.size() != g.dimension())
              throw py::value_error("mean must have " + std::to_string(g.dimension()) + " entries, got " +
                                    std::to_string(mean.size()));
            g.mean = mean;
          },
          "(N,), a view of the state")
      .def_property(
          "covariance",
          [](py::object self) {
            GaussianXd& g = self.cast<GaussianXd&>();
            // Eigen's column-major storage as a Fortran-ordered view.
            const auto step = static_cast<py::ssize_t>(sizeof(double));
            return py::array_t<double>({g.dimension(), g.dimension()}, {step, step * g.dimension()},
                                       g.covariance.data(), self);
          },
          [](GaussianXd& g, const py::handle& value) {
            Eigen::MatrixXd covariance = matrix_argument(value, "covariance");
            require_square(covariance, g.dimension(), "covariance");
            g.covariance = covariance;
          },
          "(N, N), a view of the state")
      .def_property_readonly("dimension", &GaussianXd::dimension)
      .def("copy", [](const GaussianXd& g) { return g; })
      .def("__repr__", [](const GaussianXd& g) {
        return "<s2kf.Gaussian in " + std::to_string(g.dimension()) + " dimensions>";
      });

  py::class_<UpdateResult>(module, "UpdateResult",
                           "What an update did; on any status but 'ok' the state is unchanged.")
      .def_property_readonly("status", [](const UpdateResult& r) { return std::string(to_string(r.status)); })
      .def_property_readonly("ok", &UpdateResult::ok)
      .def_readonly("nis", &UpdateResult::nis, "normalised innovation squared")
      .def_readonly("observed", &UpdateResult::observed, "observed measurement components used")
      .def("__bool__", &UpdateResult::ok)
      .def("__repr__", [](const UpdateResult& r) {
        return std::string("<s2kf.UpdateResult ") + to_string(r.status) + ", nis " + std::to_string(r.nis) +
               ">";
      });

  py::class_<Filter>(module, "SmartSamplingKalmanFilter",
                     "The S2KF: a linear-regression Kalman filter on a sample set of N(0, I). Models are "
                     "Python callables f(x) with x of shape (L, N) (one sample per row, read-only, valid "
                     "during the call) returning (L, M).")
      .def(py::init<SampleSet>(), py::arg("samples"))
      .def(py::init([](int dimension, int count) { return Filter(lcd_sample_set(dimension, count).set); }),
           py::arg("dimension"), py::arg("count"), "with the optimal LCD set of this size")
      .def_property_readonly("samples", &Filter::samples)
      .def(
          "predict_linear",
          [](const Filter& f, GaussianXd& state, const py::handle& a, const py::handle& q) {
            check_state(f, state);
            const Eigen::MatrixXd a_matrix = matrix_argument(a, "A"), q_matrix = matrix_argument(q, "Q");
            require_square(a_matrix, state.dimension(), "A");
            require_square(q_matrix, state.dimension(), "Q");
            return std::string(to_string(f.predict_linear(state, a_matrix, q_matrix)));
          },
          py::arg("state"), py::arg("A"), py::arg("Q"), "x <- A x + w, w ~ N(0, Q), closed form")
      .def(
          "predict_random_walk",
          [](const Filter& f, GaussianXd& state, const py::handle& q) {
            check_state(f, state);
            const Eigen::MatrixXd q_matrix = matrix_argument(q, "Q");
            require_square(q_matrix, state.dimension(), "Q");
            return std::string(to_string(f.predict_random_walk(state, q_matrix)));
          },
          py::arg("state"), py::arg("Q"), "x <- x + w, w ~ N(0, Q)")
      .def(
          "predict",
          [](py::object self, GaussianXd& state, const py::function& f, const py::handle& q) {
            Filter& filter = self.cast<Filter&>();
            check_state(filter, state);
            check_callable(f, "system model");
            const Eigen::MatrixXd q_matrix = matrix_argument(q, "Q");
            require_square(q_matrix, state.dimension(), "Q");
            const PythonModel model{f, self, "system model"};
            FilterStatus status;
            {
              py::gil_scoped_release unlocked;
              status = filter.predict(state, model, q_matrix);
            }
            return std::string(to_string(status));
          },
          py::arg("state"), py::arg("f"), py::arg("Q"),
          "sample-based prediction through f: (L, N) -> (L, N); returns the status")
      .def(
          "update",
          [](py::object self, GaussianXd& state, const py::function& h, const py::handle& y_value,
             const py::handle& r_value, const py::handle& observed_value, int iterations,
             double gate_probability) {
            Filter& filter = self.cast<Filter&>();
            check_state(filter, state);
            check_callable(h, "measurement model");
            const Eigen::VectorXd y = vector_argument(y_value, "y");
            const Eigen::MatrixXd r = matrix_argument(r_value, "R");
            require_square(r, y.size(), "R");
            ObservedMask observed = ObservedMask::Constant(y.size(), true);
            if (!observed_value.is_none()) {
              const auto mask =
                  py::array_t<bool, py::array::c_style | py::array::forcecast>::ensure(observed_value);
              if (!mask || mask.ndim() != 1 || mask.shape(0) != y.size())
                throw py::value_error("observed must be one bool per measurement component (" +
                                      std::to_string(y.size()) + ")");
              observed = Eigen::Map<const ObservedMask>(mask.data(), y.size());
            }
            if (iterations < 1) throw py::value_error("iterations must be at least 1");
            if (!(gate_probability >= 0 && gate_probability < 1))
              throw py::value_error("gate_probability must lie in [0, 1)");
            UpdateOptions options;
            options.iterations = iterations;
            options.gate_probability = gate_probability;
            const PythonModel model{h, self, "measurement model"};
            py::gil_scoped_release unlocked;
            return filter.update(state, model, y, r, observed, options);
          },
          py::arg("state"), py::arg("h"), py::arg("y"), py::arg("R"), py::arg("observed") = py::none(),
          py::arg("iterations") = 1, py::arg("gate_probability") = 0.0,
          "Measurement update y = h(x) + v, v ~ N(0, R); h: (L, N) -> (L, M), called once per pass with "
          "every sample. `observed` (M,) bool drops absent components (their y may be NaN). The state "
          "changes only when the result is ok.");
}

}  // namespace s2kf::python
