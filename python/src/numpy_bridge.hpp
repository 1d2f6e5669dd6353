/// @file
/// Moving arrays between numpy and Eigen without copies: checked views of numpy input as Eigen
/// maps, and numpy arrays that own (through a capsule) the Eigen storage C++ produced.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <Eigen/Core>

#include <cstdio>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace s2kf::python {

namespace py = pybind11;

/// Float64, C-ordered: what every function here takes. Arrays already in that form pass through
/// without a copy; anything else (lists, float32, Fortran order) is converted once.
using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

/// "(10, 4)" for error messages.
inline std::string shape_text(const py::array& array) {
  std::ostringstream out;
  out << "(";
  for (py::ssize_t d = 0; d < array.ndim(); ++d) out << (d ? ", " : "") << array.shape(d);
  out << (array.ndim() == 1 ? ",)" : ")");
  return out.str();
}

/// `value` as a float64 C-ordered array, or ValueError naming `what`.
inline DoubleArray as_double_array(const py::handle& value, const std::string& what) {
  if (value.is_none()) throw py::value_error(what + " must be an array of numbers, not None");
  DoubleArray array = DoubleArray::ensure(value);
  if (!array) {
    PyErr_Clear();
    throw py::value_error(what + " must be an array of numbers");
  }
  return array;
}

/// Throws ValueError unless `array` has `ndim` dimensions and, where `shape` is not -1, that size.
/// `form` spells the expected shape for the message, e.g. "(F, P, 3)".
inline void require_shape(const py::array& array, const std::vector<py::ssize_t>& shape,
                          const std::string& what, const std::string& form) {
  bool ok = array.ndim() == static_cast<py::ssize_t>(shape.size());
  for (std::size_t d = 0; ok && d < shape.size(); ++d)
    ok = shape[d] < 0 || array.shape(static_cast<py::ssize_t>(d)) == shape[d];
  if (!ok) throw py::value_error(what + " must have shape " + form + ", got " + shape_text(array));
}

/// A numpy array over `storage`'s data that keeps `storage` alive (moved to the heap and freed by
/// the array's capsule): C++ results reach Python without a copy.
template <typename Storage>
py::array_t<double> owning_array(Storage&& storage, std::vector<py::ssize_t> shape) {
  auto* owned = new std::decay_t<Storage>(std::forward<Storage>(storage));
  py::capsule free_when_done(owned, [](void* p) { delete static_cast<std::decay_t<Storage>*>(p); });
  return py::array_t<double>(std::move(shape), owned->data(), free_when_done);
}

/// A numpy copy of an Eigen column vector, shape (n,).
inline py::array_t<double> vector_copy(const Eigen::Ref<const Eigen::VectorXd>& values) {
  py::array_t<double> out(values.size());
  std::copy(values.data(), values.data() + values.size(), out.mutable_data());
  return out;
}

/// A numpy copy of an Eigen matrix with rows and columns kept: (rows, cols), C order.
inline py::array_t<double> matrix_copy(const Eigen::Ref<const Eigen::MatrixXd>& values) {
  py::array_t<double> out({values.rows(), values.cols()});
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      out.mutable_data(), values.rows(), values.cols()) = values;
  return out;
}

/// A numpy copy of 3 x N points as (N, 3): one point per row, the way numpy users index them.
inline py::array_t<double> points_copy(const Eigen::Ref<const Eigen::Matrix3Xd>& points) {
  py::array_t<double> out({points.cols(), Eigen::Index{3}});
  double* row = out.mutable_data();
  for (Eigen::Index n = 0; n < points.cols(); ++n, row += 3)
    for (int a = 0; a < 3; ++a) row[a] = points(a, n);
  return out;
}

/// A number as %g writes it, for messages.
inline std::string number_text(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", value);
  return buffer;
}

/// Python list of str from a vector of strings.
inline py::list string_list(const std::vector<std::string>& values) {
  py::list out;
  for (const std::string& value : values) out.append(value);
  return out;
}

}  // namespace s2kf::python
