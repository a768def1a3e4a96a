#pragma once
/// @file optimize_surface.hpp
/// Smoothing and untangling of a high-order surface mesh on a parameterized
/// surface (chapter 5, eq 5.22) in one call, the surface counterpart of
/// optimize/optimize.hpp:
///
///     hom::Mesh<hom::Simplex<2>, hom::WarpBlend, 3> mesh = ...;   // nodes on `sphere`
///     Eigen::Matrix2Xd uv = ...;                                   // their parameters
///     auto r = hom::optimize_surface(mesh, sphere, uv);            // ShapeMeasure, DefaultExactness
///
/// moves the free nodes' parameters (SurfaceOptimizationProblem, NewtonSolver)
/// and leaves the final parameters in `uv` and the final physical nodes
/// x_i = phi(u_i) in `mesh.nodes()`. Free nodes (surface_free_node_mask): the
/// nodes neither classified fixed nor on a curve or point entity, and not on
/// the mesh's topological boundary (the edges of the surface patch, whose
/// nodes the thesis holds at their positions on the boundary curves).
/// Options: hom::OptimizeOptions (solver must be newton; p_continuation runs
/// the linear sub-mesh stage of appendix C on the surface first,
/// surface_continuation.hpp; ideal straight_sided = each element's snapshot
/// vertices in R^3, Mesh::ideal_vertices, or regular = equilateral triangle /
/// unit square).

#include <chrono>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "hom/geometry/surface_geometry.hpp"
#include "hom/measure/shape_measure.hpp"
#include "hom/mesh/facet.hpp"
#include "hom/mesh/mesh.hpp"
#include "hom/mesh/topology.hpp"
#include "hom/optimize/newton.hpp"
#include "hom/optimize/optimize.hpp"
#include "hom/optimize/solver.hpp"
#include "hom/quadrature/quadrature_policy.hpp"
#include "hom/quality/tabulation.hpp"
#include "hom/surface/surface_continuation.hpp"
#include "hom/surface/surface_mesh_quality.hpp"
#include "hom/surface/surface_problem.hpp"

namespace hom {

/// Free-node mask of a surface mesh (see the file comment).
template <ElementFamily Family, NodeSet Nodes>
std::vector<bool> surface_free_node_mask(const Mesh<Family, Nodes, 3>& mesh) {
  std::vector<bool> free(mesh.num_nodes(), true);
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    const NodeClass& c = mesh.node_class(i);
    if (c.kind == NodeKind::fixed || (c.entity && c.entity->dim < 2)) free[i] = false;
  }
  const auto topology = make_topology(mesh);
  for (const FacetRef& f : topology.boundary_facets())
    for (int local : facet_nodes<Family>(mesh.degree(), f.local)) free[mesh.elements()(local, f.element)] = false;
  return free;
}

/// The ideal of every element of a surface mesh for `kind` (surface_ideal_for).
template <ElementFamily Family, NodeSet Nodes>
std::vector<SurfaceIdealVertices<Family>> surface_ideals(const Mesh<Family, Nodes, 3>& mesh, IdealKind kind) {
  std::vector<SurfaceIdealVertices<Family>> v(mesh.num_elements());
  for (int e = 0; e < mesh.num_elements(); ++e) v[e] = surface_ideal_for(mesh, e, kind);
  return v;
}

struct SurfaceOptimizeResult {
  SolverResult result;                      ///< the degree-p stage
  std::optional<SolverResult> continuation;  ///< the linear sub-mesh stage, when it ran
  double time_s = 0.0;                      ///< both stages

  bool converged() const { return result.converged; }
  int inverted() const { return result.inverted; }
  double min_quality() const { return result.min_quality; }
};

/// Optimizes the surface mesh whose node i lies at parameters uv.col(i) of
/// `surface` against the given ideals; uv and mesh.nodes() are updated.
template <class Measure = ShapeMeasure, QuadraturePolicy Q = DefaultExactness, ElementFamily Family, NodeSet Nodes,
          SurfaceGeometry Surface>
SurfaceOptimizeResult optimize_surface(Mesh<Family, Nodes, 3>& mesh, const Surface& surface, Eigen::Matrix2Xd& uv,
                                       const std::vector<SurfaceIdealVertices<Family>>& ideals,
                                       const OptimizeOptions& options = {}, const Measure& measure = {}) {
  if (options.solver != SolverKind::newton)
    throw std::invalid_argument("hom::optimize_surface: only the newton solver is available on surfaces");
  if (uv.cols() != mesh.num_nodes())
    throw std::invalid_argument("hom::optimize_surface: " + std::to_string(uv.cols()) + " node parameters for " +
                                std::to_string(mesh.num_nodes()) + " nodes");
  const auto start = std::chrono::steady_clock::now();
  const int p = mesh.degree();
  const Tabulation<Family>& tab = tabulation<Family, Nodes>(p, quadrature_for<Family, Q>(p));
  SurfaceOptimizationProblem<Family, Measure, Surface> problem(tab, surface, uv, mesh.elements(),
                                                               surface_free_node_mask(mesh), ideals, measure);
  problem.set_threads(options.threads);
  problem.set_regularization_alpha(options.regularization_alpha);
  SolverOptions so = options.solver_options();
  SurfaceOptimizeResult out;
  const NewtonSolver newton{.hessian = options.hessian};
  if (options.p_continuation) out.continuation = surface_linear_sub_mesh_continuation<Nodes, Q>(problem, ideals, so, newton);
  so.stage = "surface";
  out.result = newton.solve(problem, so);
  uv = problem.coordinates();
  mesh.nodes() = problem.physical_coordinates();
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    NodeClass& c = mesh.node_class(i);
    if (c.num_params == 2 && c.entity && c.entity->dim == 2) c.params = {uv(0, i), uv(1, i)};
  }
  out.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

/// The same against the ideal of options.ideal.
template <class Measure = ShapeMeasure, QuadraturePolicy Q = DefaultExactness, ElementFamily Family, NodeSet Nodes,
          SurfaceGeometry Surface>
SurfaceOptimizeResult optimize_surface(Mesh<Family, Nodes, 3>& mesh, const Surface& surface, Eigen::Matrix2Xd& uv,
                                       const OptimizeOptions& options = {}, const Measure& measure = {}) {
  return optimize_surface<Measure, Q>(mesh, surface, uv, surface_ideals(mesh, options.ideal), options, measure);
}

/// The same with the node parameters from the mesh: a node's own (u, v)
/// when it is classified on a surface with two parameters, the projection of
/// its position onto `surface` otherwise; the surface nodes' parameters are
/// written back to their classification.
template <class Measure = ShapeMeasure, QuadraturePolicy Q = DefaultExactness, ElementFamily Family, NodeSet Nodes,
          SurfaceGeometry Surface>
SurfaceOptimizeResult optimize_surface(Mesh<Family, Nodes, 3>& mesh, const Surface& surface,
                                       const OptimizeOptions& options = {}, const Measure& measure = {}) {
  Eigen::Matrix2Xd uv(2, mesh.num_nodes());
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    const NodeClass& c = mesh.node_class(i);
    if (c.num_params == 2 && c.entity && c.entity->dim == 2)
      uv.col(i) = Eigen::Vector2d(c.params[0], c.params[1]);
    else
      uv.col(i) = surface.project(mesh.node(i));
  }
  return optimize_surface<Measure, Q>(mesh, surface, uv, options, measure);
}

}  // namespace hom
