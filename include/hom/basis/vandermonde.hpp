#pragma once
/// @file vandermonde.hpp
/// Generalised Vandermonde matrices of the orthonormal basis (orthonormal.hpp):
/// V(i, j) = psi_j(x_i), one row per point, one column per mode. At the n_p
/// nodes of a node set V is square, and the Lagrange shape functions of
/// eq A.1 are N(x)^T = psi(x)^T V^{-1} (lagrange.hpp).

#include <array>
#include <vector>

#include <Eigen/Core>

#include "hom/basis/orthonormal.hpp"
#include "hom/element/family.hpp"

namespace hom {

/// #x by size(p): V(i, j) = psi_j(x_i).
template <ElementFamily F>
Eigen::MatrixXd vandermonde(int p, const std::vector<typename F::Point>& x) {
  using B = OrthonormalBasis<F>;
  const int n = B::size(p);
  // Fill the transpose so each point writes one contiguous column.
  Eigen::MatrixXd vt(n, x.size());
  for (std::size_t i = 0; i < x.size(); ++i) B::evaluate(p, x[i], vt.col(i));
  return vt.transpose();
}

/// Gradient Vandermondes: [k](i, j) = d psi_j / d x_k at x_i, each #x by size(p).
template <ElementFamily F>
std::array<Eigen::MatrixXd, F::dim> vandermonde_gradient(int p, const std::vector<typename F::Point>& x) {
  using B = OrthonormalBasis<F>;
  const int n = B::size(p);
  std::array<Eigen::MatrixXd, F::dim> dv;
  for (auto& m : dv) m.resize(x.size(), n);
  typename B::Gradient g(n, F::dim);
  for (std::size_t i = 0; i < x.size(); ++i) {
    B::gradient(p, x[i], g);
    for (int k = 0; k < F::dim; ++k) dv[k].row(i) = g.col(k).transpose();
  }
  return dv;
}

}  // namespace hom
