#pragma once
/// @file continuation.hpp
/// p-continuation (appendix C): a better starting configuration for the
/// high-order optimization when the mesh is badly tangled.
///
/// Policies (concept: `name` and `run<Quadrature>(mesh, ideal, options, threads, measure, alpha)`
/// returning std::optional<SolverResult>, empty when nothing was done):
///   - NoContinuation: nothing.
///   - LinearSubMeshContinuation: the three steps of appendix C.
///       1. Split every degree-p element into its linear sub-elements
///          (element/sub_elements.hpp: p^2 triangles, p^3 tetrahedra, p^Dim
///          cells) on the same nodes. Each sub-element's ideal is the matching
///          sub-element of the ideal high-order element: the ideal element's
///          nodes (its straight-sided map at the node set's reference points)
///          at the sub-element's vertex nodes.
///       2. If the linear sub-mesh has inverted sub-elements (an untangled
///          linear sub-mesh is necessary for a valid high-order mesh), optimize
///          it as a p = 1 problem with the same measure, regularization and
///          fixed nodes and the policy's solver (`solver`, Gauss-Seidel by
///          default) (one quadrature point per
///          simplex, whose Jacobian is constant). Otherwise do nothing: "we only
///          apply our procedure when this necessary condition is not hold".
///       3. The high-order mesh takes the optimized node positions (the
///          sub-mesh's nodes are the high-order nodes; nothing is interpolated).
///     The high-order optimization then starts from the recovered positions
///     (the sub-mesh being valid is necessary, not sufficient, for validity).

#include <optional>
#include <string_view>
#include <vector>

#include "hom/element/sub_elements.hpp"
#include "hom/mesh/mesh.hpp"
#include "hom/optimize/mesh_problem.hpp"
#include "hom/optimize/problem.hpp"
#include "hom/optimize/solve.hpp"
#include "hom/optimize/solver.hpp"
#include "hom/quadrature/quadrature_policy.hpp"

namespace hom {

struct NoContinuation {
  static constexpr std::string_view name = "none";

  template <QuadraturePolicy Q, class Measure, ElementFamily Family, NodeSet Nodes, int SpaceDim>
  std::optional<SolverResult> run(Mesh<Family, Nodes, SpaceDim>&, const IdealMesh<Family>&, const SolverOptions&, int,
                                  const Measure&, double = thesis_regularization_alpha) const {
    return std::nullopt;
  }
};

/// The linear sub-problem of appendix C for `mesh` (its current coordinates):
/// p = 1 elements of the same family on the same nodes, free nodes as in the
/// mesh, ideals from the sub-elements of the ideal high-order elements.
template <class Measure = ShapeMeasure, QuadraturePolicy Q = DefaultExactness, ElementFamily Family, NodeSet Nodes, int SpaceDim>
OptimizationProblem<Family, Measure> make_linear_sub_problem(const Mesh<Family, Nodes, SpaceDim>& mesh,
                                                             const IdealMesh<Family>& ideal, const Measure& measure = {}) {
  static_assert(SpaceDim == Family::dim, "hom::make_linear_sub_problem: planar and volume meshes only");
  constexpr int nv = Family::num_vertices;
  const int p = mesh.degree();
  const auto split = linear_sub_elements<Family>(p);
  const int ns = int(split.size());
  // A linear simplex has a constant Jacobian: one point integrates eq 4.10
  // exactly and decides validity exactly. Cubes keep the policy's rule.
  const QuadratureRule<Family::dim>& rule = Family::is_simplex ? cached_gauss_rule<Family>(1) : quadrature_for<Family, Q>(1);
  const Tabulation<Family>& tab = tabulation<Family, Nodes>(1, rule);
  const Eigen::MatrixXd& to_nodes = detail::vertex_shape_matrix<Family, Nodes>(p);  // num_vertices x n_p
  Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic> conn(nv, Eigen::Index(ns) * mesh.num_elements());
  std::vector<IdealAtPoints<Family::dim>> ideals(conn.cols());
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const Eigen::Matrix<double, Family::dim, Eigen::Dynamic> ideal_nodes = ideal.vertices(e) * to_nodes;
    for (int s = 0; s < ns; ++s) {
      IdealVertices<Family> v;
      for (int k = 0; k < nv; ++k) {
        conn(k, e * ns + s) = mesh.element(e)[split[s][k]];
        v.col(k) = ideal_nodes.col(split[s][k]);
      }
      ideals[e * ns + s] = ideal_at_points<Family>(tab, v);
    }
  }
  return OptimizationProblem<Family, Measure>(tab, mesh.nodes(), std::move(conn), free_node_mask(mesh), std::move(ideals),
                                              measure);
}

struct LinearSubMeshContinuation {
  static constexpr std::string_view name = "linear-sub-mesh";
  SolverKind solver = SolverKind::gauss_seidel;  ///< solver of the linear stage

  template <QuadraturePolicy Q, class Measure, ElementFamily Family, NodeSet Nodes, int SpaceDim>
  std::optional<SolverResult> run(Mesh<Family, Nodes, SpaceDim>& mesh, const IdealMesh<Family>& ideal,
                                  const SolverOptions& options, int threads, const Measure& measure,
                                  double regularization_alpha = thesis_regularization_alpha) const {
    if (mesh.degree() == 1) return std::nullopt;
    auto sub = make_linear_sub_problem<Measure, Q>(mesh, ideal, measure);
    sub.set_threads(threads);
    sub.set_regularization_alpha(regularization_alpha);
    if (sub.status(sub.coordinates()).all_valid()) return std::nullopt;
    SolverResult r = solve_with(solver, sub, options);
    mesh.nodes() = sub.coordinates();
    return r;
  }
};

}  // namespace hom
