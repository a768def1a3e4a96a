#pragma once
/// @file tabulation.hpp
/// Everything about the reference element that the measures and the optimizer
/// need at quadrature points, computed once per (family, node set, p, rule) and
/// shared by all elements (DESIGN.md, "the compile-time axes").
///
/// With X the Dim x n matrix of an element's node coordinates (one column per
/// node, hom's layout order), the Jacobian of the representation map at
/// quadrature point q is (appendix A)
///     D phi_P(xi_q) = X * G_q,      G_q = shape_gradients.middleCols(q * Dim, Dim),
/// so all Jacobians of an element come from one matrix product X * G.

#include <map>
#include <memory>
#include <mutex>
#include <tuple>
#include <vector>

#include <Eigen/Dense>

#include "hom/basis/lagrange.hpp"
#include "hom/element/family.hpp"
#include "hom/quadrature/quadrature_rule.hpp"
#include "hom/quality/ideal.hpp"
#include "hom/quality/sum_factorization.hpp"

namespace hom {

template <ElementFamily Family>
struct Tabulation {
  static constexpr int dim = Family::dim;
  int degree = 0;
  QuadratureRule<dim> rule;
  /// n x (Dim * nq): column q * Dim + k holds dN_j / d xi_k at xi_q.
  Eigen::MatrixXd shape_gradients;
  /// nq x n: N_j(xi_q).
  Eigen::MatrixXd shape_values;
  /// n x (Dim * n): the same gradients at the element's own nodes (scaled
  /// Jacobian "at the quadrature points and the nodes", point-wise coloring).
  Eigen::MatrixXd node_shape_gradients;
  /// Gradients of the vertex shape functions at each quadrature point, for the
  /// ideal's Jacobian (constant on simplices).
  std::vector<Eigen::Matrix<double, Family::num_vertices, dim>> vertex_gradients;
  /// The same at the element's nodes.
  std::vector<Eigen::Matrix<double, Family::num_vertices, dim>> node_vertex_gradients;
  /// Tetrahedra with a collapsed Gauss-Jacobi rule, where it is cheaper: the
  /// products with shape_gradients by sum factorization (sum_factorization.hpp);
  /// null otherwise.
  std::shared_ptr<const TetrahedronSumFactorization> sum_factorization;

  int num_nodes() const { return static_cast<int>(shape_gradients.rows()); }
  int num_points() const { return static_cast<int>(rule.weights.size()); }
};

template <ElementFamily Family, NodeSet Nodes>
Tabulation<Family> make_tabulation(int p, const QuadratureRule<Family::dim>& rule) {
  constexpr int D = Family::dim;
  const LagrangeBasis<Family, Nodes> basis(p);
  Tabulation<Family> t;
  t.degree = p;
  t.rule = rule;
  const auto grads = basis.gradients(rule.points);
  const int nq = static_cast<int>(rule.points.size());
  t.shape_gradients.resize(basis.size(), D * nq);
  for (int q = 0; q < nq; ++q)
    for (int k = 0; k < D; ++k) t.shape_gradients.col(q * D + k) = grads[k].row(q).transpose();
  t.shape_values = basis.values(rule.points);
  const auto node_grads = basis.gradients(basis.nodes());
  t.node_shape_gradients.resize(basis.size(), D * basis.size());
  for (int i = 0; i < basis.size(); ++i)
    for (int k = 0; k < D; ++k) t.node_shape_gradients.col(i * D + k) = node_grads[k].row(i).transpose();
  t.node_vertex_gradients.reserve(basis.size());
  for (const auto& x : basis.nodes()) t.node_vertex_gradients.push_back(vertex_shape_gradients<Family>(x));
  t.vertex_gradients.reserve(nq);
  for (int q = 0; q < nq; ++q) t.vertex_gradients.push_back(vertex_shape_gradients<Family>(rule.points[q]));
  if constexpr (Family::is_simplex && D == 3) {
    const Eigen::MatrixXd inverse_vandermonde_t = basis.vandermonde_matrix().transpose().partialPivLu().inverse();
    t.sum_factorization = make_tetrahedron_sum_factorization(p, inverse_vandermonde_t, rule);
  }
  return t;
}

/// All Jacobians of one element, JP = X * shape_gradients (Dim x Dim nq, point
/// q in columns Dim q ..), by the tabulation's sum factorization where it has
/// one (a dense product with G reads and packs all of G for every element:
/// 23 MB at p = 10).
template <ElementFamily Family>
Eigen::Matrix<double, Family::dim, Eigen::Dynamic> reference_jacobians(
    const Tabulation<Family>& tab, const Eigen::Ref<const Eigen::Matrix<double, Family::dim, Eigen::Dynamic>>& X) {
  if constexpr (Family::is_simplex && Family::dim == 3) {
    if (tab.sum_factorization) {
      thread_local TetrahedronSumFactorization::Workspace w;
      thread_local Eigen::MatrixXd JP;
      tab.sum_factorization->gradients(Eigen::MatrixXd(X), JP, w);
      return JP;
    }
  }
  return X * tab.shape_gradients;
}

/// The shared tabulation for (Family, Nodes, p, rule), built once (thread-safe).
template <ElementFamily Family, NodeSet Nodes>
const Tabulation<Family>& tabulation(int p, const QuadratureRule<Family::dim>& rule) {
  static std::mutex mutex;
  static std::map<std::tuple<int, int, std::size_t>, std::unique_ptr<Tabulation<Family>>> cache;
  std::lock_guard lock(mutex);
  auto& slot = cache[{p, rule.exactness, rule.points.size()}];
  if (!slot) slot = std::make_unique<Tabulation<Family>>(make_tabulation<Family, Nodes>(p, rule));
  return *slot;
}

}  // namespace hom
