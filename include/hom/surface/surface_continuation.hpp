#pragma once
/// @file surface_continuation.hpp
/// p-continuation (appendix C) for meshes on a parameterized surface
/// (chapter 5): the surface analogue of LinearSubMeshContinuation
/// (optimize/continuation.hpp).
///
///   1. Split every degree-p element into its linear sub-elements
///      (element/sub_elements.hpp: p^2 triangles or quadrilaterals) on the same
///      nodes, with the same parameters (u, v) and the same free nodes. The
///      ideal of a sub-element is the matching sub-element of its element's
///      straight-sided ideal in R^3 (the ideal's map at the node set's
///      reference points, at the sub-element's vertex nodes).
///   2. If that linear sub-mesh has inverted sub-elements (it is necessary for
///      a valid high-order surface mesh that it has none), optimize it as a
///      p = 1 surface problem (eqs 5.19-5.22 with flat sub-elements, one
///      quadrature point per triangle) with the same measure and
///      regularization.
///   3. The high-order problem takes the optimized parameters (the sub-mesh's
///      nodes are the high-order nodes; nothing is interpolated) and is then
///      optimized from there.
///
/// Why: from a start whose nodes are scrambled within their elements (section
/// 5.5.1.3's perturbed surface mesh), the degree-p objective is full of local
/// minima where an element's interior nodes have crossed; the p = 1 sub-mesh
/// has far fewer (each of its elements is one linear triangle), and its
/// optimum puts every node back in its own sub-triangle, the neighbourhood of
/// the high-order optimum.

#include <optional>
#include <vector>

#include <Eigen/Dense>

#include "hom/element/sub_elements.hpp"
#include "hom/mesh/mesh.hpp"
#include "hom/optimize/newton.hpp"
#include "hom/optimize/solver.hpp"
#include "hom/quadrature/quadrature_policy.hpp"
#include "hom/surface/surface_problem.hpp"

namespace hom {

/// The linear sub-problem of appendix C for a degree-p surface mesh:
/// `uv` (2 x N), `elements` (n_p x nE, the local layout of degree p),
/// `free` and `ideals` as SurfaceOptimizationProblem's.
template <ElementFamily Family, NodeSet Nodes, QuadraturePolicy Q = DefaultExactness, class Measure = ShapeMeasure,
          SurfaceGeometry Surface>
SurfaceOptimizationProblem<Family, Measure, Surface> make_linear_sub_surface_problem(
    int p, const Surface& surface, const Eigen::Matrix<double, 2, Eigen::Dynamic>& uv,
    const Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic>& elements, const std::vector<bool>& free,
    const std::vector<SurfaceIdealVertices<Family>>& ideals, const Measure& measure = {}) {
  constexpr int nv = Family::num_vertices;
  const auto split = linear_sub_elements<Family>(p);
  const int ns = int(split.size());
  // A flat linear triangle has a constant tangent basis: one point integrates
  // it; the reference normals still vary, which one point averages.
  // Quadrilaterals keep the policy's rule (their Jacobian is bilinear).
  const QuadratureRule<2>& rule = Family::is_simplex ? cached_gauss_rule<Family>(1) : quadrature_for<Family, Q>(1);
  const Tabulation<Family>& tab = tabulation<Family, Nodes>(1, rule);
  const Eigen::MatrixXd& to_nodes = detail::vertex_shape_matrix<Family, Nodes>(p);  // nv x n_p
  Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic> conn(nv, Eigen::Index(ns) * elements.cols());
  std::vector<SurfaceIdealVertices<Family>> sub_ideals(conn.cols());
  for (Eigen::Index e = 0; e < elements.cols(); ++e) {
    const Eigen::Matrix<double, 3, Eigen::Dynamic> ideal_nodes = ideals[e] * to_nodes;
    for (int s = 0; s < ns; ++s)
      for (int k = 0; k < nv; ++k) {
        conn(k, e * ns + s) = elements(split[s][k], e);
        sub_ideals[e * ns + s].col(k) = ideal_nodes.col(split[s][k]);
      }
  }
  return SurfaceOptimizationProblem<Family, Measure, Surface>(tab, surface, uv, std::move(conn), free, sub_ideals,
                                                              measure);
}

/// Appendix C's steps 1-3 on `problem` (a degree-p surface problem whose
/// elements have `ideals`): when the linear sub-mesh of the current
/// parameters is tangled, it is untangled and smoothed with `solver` and the
/// problem's free nodes take its result. Returns the linear stage's record,
/// empty when the sub-mesh was valid (nothing done) or p = 1.
template <NodeSet Nodes, QuadraturePolicy Q = DefaultExactness, class Problem>
std::optional<SolverResult> surface_linear_sub_mesh_continuation(Problem& problem,
                                                                  const std::vector<SurfaceIdealVertices<typename Problem::family>>& ideals,
                                                                  const SolverOptions& options = {},
                                                                  const NewtonSolver& solver = {}) {
  using Family = typename Problem::family;
  const int p = problem.tabulation().degree;
  if (p == 1) return std::nullopt;
  std::vector<bool> free(problem.num_nodes());
  for (int i = 0; i < problem.num_nodes(); ++i) free[i] = problem.is_free(i);
  auto sub = make_linear_sub_surface_problem<Family, Nodes, Q>(p, problem.surface(), problem.coordinates(),
                                                              problem.elements(), free, ideals, problem.measure());
  sub.set_threads(problem.threads());
  sub.set_regularization_alpha(problem.regularization_alpha());
  if (sub.status(sub.coordinates()).all_valid()) return std::nullopt;
  SolverOptions o = options;
  o.stage = "linear sub-mesh";
  SolverResult r = solver.solve(sub, o);
  problem.coordinates() = sub.coordinates();
  return r;
}

}  // namespace hom
