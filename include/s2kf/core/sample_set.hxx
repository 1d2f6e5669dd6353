/// @file
/// The definitions of <s2kf/core/sample_set.hpp>: inline where the library is used header-only, compiled once
/// into the library s2kf_compiled otherwise (core/compilation_mode.hpp).
#pragma once

#include <s2kf/core/sample_set.hpp>

namespace s2kf {
S2KF_INLINE void correct_moments(Eigen::MatrixXd& z) {
  const double count = static_cast<double>(z.cols());
  z.colwise() -= z.rowwise().mean();
  const Eigen::MatrixXd c = (z * z.transpose()) / count;
  // chol(C^-1) = L^-T up to an orthogonal factor; use the exact definition for clarity of the proof
  // in the spec: A A^T = C^-1, then (A^T Z)(A^T Z)^T / L = A^T C A = I.
  Eigen::LLT<Eigen::MatrixXd> llt_c(c);
  if (llt_c.info() != Eigen::Success) throw DimensionError("correct_moments: samples do not span the space");
  const Eigen::MatrixXd c_inv = llt_c.solve(Eigen::MatrixXd::Identity(c.rows(), c.cols()));
  Eigen::LLT<Eigen::MatrixXd> llt_inv(c_inv);
  if (llt_inv.info() != Eigen::Success)
    throw DimensionError("correct_moments: samples do not span the space");
  const Eigen::MatrixXd a = llt_inv.matrixL();
  z = (a.transpose() * z).eval();
}
}  // namespace s2kf
