#pragma once
/// @file continuation.hpp
/// p-continuation (appendix C): a better starting configuration for the
/// high-order optimization when the mesh is badly tangled.
///
/// Policies (concept: `name` and `run<Quadrature>(mesh, ideal, options, threads, measure, regularization)`
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
///          fixed nodes and the policy's solver (`solver`, Gauss-Seidel with
///          vertex culling by default) (one quadrature point per
///          simplex, whose Jacobian is constant). Otherwise do nothing: "we only
///          apply our procedure when this necessary condition is not hold".
///       3. The high-order mesh takes the optimized node positions (the
///          sub-mesh's nodes are the high-order nodes; nothing is interpolated).
///     The high-order optimization then starts from the recovered positions
///     (the sub-mesh being valid is necessary, not sufficient, for validity).
///   - VertexMeshContinuation: continuation in the degree from p = 1, for
///     tangles that the vertices themselves carry (a boundary that moved by
///     several element sizes, table 4.2), which the linear sub-mesh of appendix
///     C inherits p^Dim-fold:
///       1. the degree-1 mesh of the element vertices (same free/fixed
///          classification, ideal = the ideal elements' vertices) is optimized
///          with the policy's solver, only when it has inverted elements;
///       2. every free node that is not a vertex is placed at the image of its
///          reference point under its element's (now valid) straight-sided
///          map; held nodes keep their curved positions;
///       3. then, optionally, the linear sub-mesh stage of appendix C.
///     Step 2 moves free nodes of elements that were valid too (they lose
///     their curvature), so this policy is for tangles of the vertices, not
///     for a curved mesh that is nearly valid.
///     Step 1 falls back on a homotopy of the held vertices from the mesh's
///     valid snapshot when the direct solve stalls with inverted elements
///     (VertexMeshContinuation::untangle).
///     On table 4.2's moved cavity the degree-1 problem (357 nodes) untangles
///     179 inverted tetrahedra in a few seconds, where the degree-5 problem
///     started from the moved mesh stalls (bench_smooth).

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
                                  const Measure&, const Regularization& = {}) const {
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
  /// Vertex culling when that solver is Gauss-Seidel (GaussSeidel::culling_tolerance,
  /// max_culled_passes). bench_untangle --p 10 --pcont, 2 threads: the linear
  /// stage took 27 full sweeps and 35 s and left its sub-mesh at min quality
  /// 0.10; with culling 14 sweeps and 12 s, and the high-order mesh it hands
  /// on is valid with min quality 0.99 (table 4.1 in 29 s instead of 140 s).
  double culling_tolerance = 0.05;
  int max_culled_passes = 10;

  template <QuadraturePolicy Q, class Measure, ElementFamily Family, NodeSet Nodes, int SpaceDim>
  std::optional<SolverResult> run(Mesh<Family, Nodes, SpaceDim>& mesh, const IdealMesh<Family>& ideal,
                                  const SolverOptions& options, int threads, const Measure& measure,
                                  const Regularization& regularization = {}) const {
    if (mesh.degree() == 1) return std::nullopt;
    auto sub = make_linear_sub_problem<Measure, Q>(mesh, ideal, measure);
    sub.set_threads(threads);
    sub.set_regularization(regularization);
    if (sub.status(sub.coordinates()).all_valid()) return std::nullopt;
    SolverResult r = solver == SolverKind::gauss_seidel
                         ? GaussSeidel{.culling_tolerance = culling_tolerance, .max_culled_passes = max_culled_passes}.solve(sub, options)
                         : solve_with(solver, sub, options);
    mesh.nodes() = sub.coordinates();
    return r;
  }
};

/// The degree-1 mesh of `mesh`'s element vertices as an optimization problem
/// (nodes renumbered compactly; `vertex_nodes[k]` is vertex k's node in `mesh`).
template <class Measure = ShapeMeasure, QuadraturePolicy Q = DefaultExactness, ElementFamily Family, NodeSet Nodes, int SpaceDim>
OptimizationProblem<Family, Measure> make_vertex_problem(const Mesh<Family, Nodes, SpaceDim>& mesh, const IdealMesh<Family>& ideal,
                                                         std::vector<int>& vertex_nodes, const Measure& measure = {}) {
  static_assert(SpaceDim == Family::dim, "hom::make_vertex_problem: planar and volume meshes only");
  constexpr int nv = Family::num_vertices;
  std::vector<int> index(mesh.num_nodes(), -1);
  vertex_nodes.clear();
  Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic> conn(nv, mesh.num_elements());
  for (int e = 0; e < mesh.num_elements(); ++e)
    for (int k = 0; k < nv; ++k) {
      const int node = mesh.element(e)[k];  // local nodes 0..nv-1 are the vertices (NodeLayout)
      if (index[node] < 0) {
        index[node] = int(vertex_nodes.size());
        vertex_nodes.push_back(node);
      }
      conn(k, e) = index[node];
    }
  Eigen::Matrix<double, Family::dim, Eigen::Dynamic> x(Family::dim, Eigen::Index(vertex_nodes.size()));
  std::vector<bool> free(vertex_nodes.size());
  for (std::size_t k = 0; k < vertex_nodes.size(); ++k) {
    x.col(k) = mesh.node(vertex_nodes[k]);
    free[k] = mesh.node_class(vertex_nodes[k]).kind == NodeKind::free;
  }
  const QuadratureRule<Family::dim>& rule = Family::is_simplex ? cached_gauss_rule<Family>(1) : quadrature_for<Family, Q>(1);
  const Tabulation<Family>& tab = tabulation<Family, Nodes>(1, rule);
  std::vector<IdealAtPoints<Family::dim>> ideals(mesh.num_elements());
  for (int e = 0; e < mesh.num_elements(); ++e) ideals[e] = ideal_at_points<Family>(tab, ideal.vertices(e));
  return OptimizationProblem<Family, Measure>(tab, std::move(x), std::move(conn), std::move(free), std::move(ideals), measure);
}

/// Places every free non-vertex node of `mesh` at the image of its reference
/// point under its element's straight-sided map (vertices as they are now).
template <ElementFamily Family, NodeSet Nodes, int SpaceDim>
void place_free_nodes_straight(Mesh<Family, Nodes, SpaceDim>& mesh) {
  constexpr int nv = Family::num_vertices;
  const Eigen::MatrixXd& to_nodes = detail::vertex_shape_matrix<Family, Nodes>(mesh.degree());  // nv x n_p
  Eigen::Matrix<double, SpaceDim, nv> v;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const auto nodes = mesh.element(e);
    for (int k = 0; k < nv; ++k) v.col(k) = mesh.node(nodes[k]);
    for (int i = nv; i < int(to_nodes.cols()); ++i)
      if (mesh.node_class(nodes[i]).kind == NodeKind::free) mesh.node(nodes[i]) = v * to_nodes.col(i);
  }
}

struct VertexMeshContinuation {
  static constexpr std::string_view name = "vertex-mesh";
  SolverKind solver = SolverKind::newton;  ///< solver of the degree-1 stage (small problems)
  /// Boundary homotopy when the direct degree-1 solve leaves elements
  /// inverted: at most this many halvings of the homotopy step (0: none).
  int max_step_halvings = 6;
  /// Then the linear sub-mesh stage of appendix C (when its sub-mesh is tangled).
  std::optional<LinearSubMeshContinuation> sub_mesh = LinearSubMeshContinuation{};

  template <QuadraturePolicy Q, class Measure, ElementFamily Family, NodeSet Nodes, int SpaceDim>
  std::optional<SolverResult> run(Mesh<Family, Nodes, SpaceDim>& mesh, const IdealMesh<Family>& ideal,
                                  const SolverOptions& options, int threads, const Measure& measure,
                                  const Regularization& regularization = {}) const {
    std::optional<SolverResult> result;
    std::vector<int> vertex_nodes;
    auto vertices = make_vertex_problem<Measure, Q>(mesh, ideal, vertex_nodes, measure);
    vertices.set_threads(threads);
    vertices.set_regularization(regularization);
    if (!vertices.status(vertices.coordinates()).all_valid()) {
      SolverOptions o = options;
      o.stage = "vertices";
      o.iterations_after_valid = -1;  // a converged degree-1 mesh: the best straight-sided start
      result = untangle(vertices, snapshot_positions(mesh, vertex_nodes), o);
      for (std::size_t k = 0; k < vertex_nodes.size(); ++k) mesh.node(vertex_nodes[k]) = vertices.coordinates().col(k);
      if (mesh.degree() > 1) place_free_nodes_straight(mesh);
    }
    if (!sub_mesh) return result;
    auto sub = sub_mesh->template run<Q>(mesh, ideal, options, threads, measure, regularization);
    if (!sub) return result;
    if (!result) return sub;
    result->iterations += sub->iterations;  // both stages in one record: iterations and time add up
    result->time_s += sub->time_s;
    result->solver += " + " + sub->solver;
    result->inverted = sub->inverted;
    result->min_quality = sub->min_quality;
    return result;
  }

 private:
  /// The vertices' positions in the mesh's snapshot (Mesh::ideal_coordinates:
  /// the straight-sided mesh before curving or moving its boundary).
  template <class MeshT>
  static Eigen::Matrix<double, MeshT::dim, Eigen::Dynamic> snapshot_positions(const MeshT& mesh, const std::vector<int>& nodes) {
    Eigen::Matrix<double, MeshT::dim, Eigen::Dynamic> x(MeshT::dim, Eigen::Index(nodes.size()));
    for (std::size_t k = 0; k < nodes.size(); ++k) x.col(k) = mesh.ideal_coordinates().col(nodes[k]);
    return x;
  }

  /// Untangles the degree-1 problem: first directly from its positions; if
  /// that leaves elements inverted (the regularized objective has local
  /// minima with inverted elements when the boundary moved by several element
  /// sizes), by a homotopy on the held vertices from the valid snapshot
  /// (held(t) = snapshot + t (target - snapshot), free vertices optimized at
  /// each t, the step in t halved when a stage ends invalid and doubled after
  /// a success). Returns the accumulated record of all solves.
  template <class Problem, class Positions>
  SolverResult untangle(Problem& problem, const Positions& snapshot, const SolverOptions& o) const {
    const Positions target = problem.coordinates();
    SolverResult total = solve_with(solver, problem, o);
    if (total.inverted == 0 || max_step_halvings <= 0) return total;
    if (!problem.status(snapshot).all_valid()) return total;  // no valid start for a homotopy: keep the direct result
    const auto accumulate = [&](const SolverResult& r) {
      total.iterations += r.iterations;
      total.time_s += r.time_s;
      total.inverted = r.inverted;
      total.min_quality = r.min_quality;
      total.objective = r.objective;
      total.converged = r.converged;
      total.reason = r.reason;
    };
    Positions valid = snapshot;  // the last configuration with every element valid, at parameter t
    double t = 0.0, dt = 0.5;
    int halvings = 0;
    while (t < 1.0) {
      const double next = std::min(1.0, t + dt);
      problem.coordinates() = valid;
      for (int k = 0; k < int(valid.cols()); ++k)
        if (!problem.is_free(k)) problem.coordinates().col(k) = snapshot.col(k) + next * (target.col(k) - snapshot.col(k));
      accumulate(solve_with(solver, problem, o));
      if (total.inverted == 0) {
        t = next;
        valid = problem.coordinates();
        dt *= 2.0;
      } else if (++halvings > max_step_halvings) {
        return total;  // the caller's next stage starts from this (invalid) configuration
      } else {
        dt *= 0.5;
      }
    }
    return total;
  }
};

}  // namespace hom
