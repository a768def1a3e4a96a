#pragma once
/// @file certified_surface.hpp
/// Certification and repair of a curved surface mesh on a parameterized
/// surface (issues 6 and 8), the surface counterpart of
/// optimize/certified.hpp.
///
/// The certificate is of the element a solver reads: the degree-p polynomial
/// x(xi) through the nodes in R^3, oriented by the interpolated unit surface
/// normals of its nodes, g(xi) = (x_xi x x_eta) . sum_i N_i(xi) nu_i
/// (normal_jacobian_bernstein.hpp), certified as a planar element's det
/// (quality/certify.hpp). g has the sign the optimizer tests at its
/// quadrature points (surface_problem.hpp), so the certificate extends the
/// optimizer's validity to every point of the element, and a point where it
/// fails is one the optimizer can be shown. Certified valid means the
/// element's tangent plane never turns over against the surface's normal: no
/// fold, and no element inverted as a whole. (The facet's own normal would
/// not do: a strongly curved element can be valid while its vertices, joined
/// straight, turn the other way. One normal per element would not do either:
/// at a nearly degenerate corner it can disagree in sign with the
/// optimizer's interpolated normal, and a repair round then has no point to
/// work on. The map S o u of chapter 5 is not certified: at a pole, where
/// S_u = 0, one (u, v) per node folds it near the pole for any polynomial u,
/// although x(xi) is fine there; a node at a pole takes the normal's limit
/// from inside its element, unit_normal.hpp.)
///
/// The optimizer (eq 5.22) sees the surface Jacobian (eq 5.5) only at the
/// quadrature points, so an optimized surface element can fold at a corner
/// node unseen (measured: the degree-3 sphere of cli_optimize_cad rotated by
/// 0.02 rad, element 228, sampled scaled Jacobian -0.19 at a node, 0 inverted
/// at the quadrature points). `certify_and_repair_surface` mends such folds
/// in rounds, as certified.hpp does in the volume:
///
///   1. sentinel points (the reference vertices, and each failing element's
///      invalid and weakest points) appended to the quadrature rule with a
///      small weight, so that the objective, the validity test and the line
///      search's barrier of SurfaceOptimizationProblem see det there;
///   2. a local problem in (u, v): the free nodes of the failing elements and
///      of their node neighbours (pull_back_rings rings for a pull-back),
///      every element with a free node, the rest held; nodes on CAD curves
///      and on the patch's boundary stay held (surface_free_node_mask);
///   3. when a valid start is known (`valid_start`, e.g. the parameters the
///      face stage started from) and the failing elements certify valid
///      there, the patch is first pulled back towards it in (u, v) with the
///      weights w = 1 - ring / (rings + 1) until every element of the
///      problem certifies valid, and the solve's result is pulled back
///      towards the round's start in the same way, so such a round ends
///      certified;
///   4. acceptance: a round that leaves more elements invalid at the
///      quadrature points, or more uncertified, is undone and the stage stops.
/// A fold whose det depends on held nodes only is not attempted (held); if
/// the rounds end with no fewer uncertified elements than they started with,
/// the mesh is put back (restored).

#include <algorithm>
#include <chrono>
#include <numeric>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "hom/detail/parallel.hpp"
#include "hom/detail/repair_patch.hpp"
#include "hom/geometry/surface_geometry.hpp"
#include "hom/mesh/mesh.hpp"
#include "hom/optimize/certified.hpp"
#include "hom/optimize/newton.hpp"
#include "hom/quadrature/quadrature_policy.hpp"
#include "hom/quality/certify.hpp"
#include "hom/quality/tabulation.hpp"
#include "hom/surface/normal_jacobian_bernstein.hpp"
#include "hom/surface/optimize_surface.hpp"
#include "hom/surface/surface_problem.hpp"
#include "hom/surface/unit_normal.hpp"

namespace hom {

/// The certificate of one surface element with nodes X (3 x n, the element's
/// local layout) and unit nodal surface normals nu (3 x n): of g in the file
/// comment.
template <ElementFamily Family, NodeSet Nodes>
ElementCertificate<Family> certify_surface_element(int p, const Eigen::Ref<const Eigen::Matrix3Xd>& X,
                                                   const Eigen::Ref<const Eigen::Matrix3Xd>& nu, const CertifyOptions& o) {
  const BernsteinPolynomial<Family> g = normal_jacobian_bernstein<Family, Nodes>(p, X, nu);
  return certify_coefficients<Family>(*g.space, g.coefficients, o);
}

namespace detail {

/// Certificate of the element with connectivity column `nodes`, its nodes at
/// parameters U of `surface`.
template <ElementFamily Family, NodeSet Nodes, SurfaceGeometry Surface, class Column>
ElementCertificate<Family> certify_on_surface(int p, const Surface& surface, const Eigen::Matrix2Xd& U,
                                              const Column& nodes, const CertifyOptions& o) {
  const Eigen::Index n = nodes.size();
  Eigen::Matrix2Xd UV(2, n);
  Eigen::Matrix3Xd X(3, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    UV.col(i) = U.col(nodes(i));
    X.col(i) = surface.evaluate(UV.col(i));
  }
  return certify_surface_element<Family, Nodes>(p, X, element_unit_normals(surface, UV), o);
}

}  // namespace detail

/// The certificates of the given elements (all when `elements` is null), in
/// that order, the mesh's nodes at parameters uv of `surface` (the elements
/// are those of x_i = S(u_i): mesh.nodes() is not read); threads as o.threads.
template <ElementFamily Family, NodeSet Nodes, SurfaceGeometry Surface>
std::vector<ElementCertificate<Family>> certify_surface_elements(const Mesh<Family, Nodes, 3>& mesh,
                                                                 const Surface& surface, const Eigen::Matrix2Xd& uv,
                                                                 const CertifyOptions& o,
                                                                 const std::vector<int>* elements = nullptr) {
  const int m = elements ? int(elements->size()) : mesh.num_elements();
  std::vector<ElementCertificate<Family>> out(m);
  const detail::SerialEigenScope serial;
  HOM_PARALLEL_FOR_DYNAMIC(detail::useful_threads(detail::resolve_threads(o.threads), m, 4))
  for (int b = 0; b < m; ++b)
    out[b] = detail::certify_on_surface<Family, Nodes>(mesh.degree(), surface, uv,
                                                       mesh.elements().col(elements ? (*elements)[b] : b), o);
  return out;
}

/// Certifies every element of the surface mesh whose node i lies at
/// parameters uv.col(i) of `surface`, and repairs the uncertified ones as the
/// file comment describes: free nodes move in uv, mesh.nodes() and their
/// classification's parameters. `ideals` are the elements' ideals (as given
/// to optimize_surface); `so`, `alpha` and `measure` the face stage's;
/// `valid_start`, when given, the parameters the face stage started from.
template <class Measure = ShapeMeasure, QuadraturePolicy Q = DefaultExactness, ElementFamily Family, NodeSet Nodes,
          SurfaceGeometry Surface>
CertificationOutcome certify_and_repair_surface(Mesh<Family, Nodes, 3>& mesh, const Surface& surface, Eigen::Matrix2Xd& uv,
                                                const std::vector<SurfaceIdealVertices<Family>>& ideals,
                                                SolverOptions so, const CertifyRepairOptions& o, int threads,
                                                double alpha = thesis_regularization_alpha, const Measure& measure = {},
                                                const Eigen::Matrix2Xd* valid_start = nullptr) {
  using Problem = SurfaceOptimizationProblem<Family, Measure, Surface>;
  const auto start = std::chrono::steady_clock::now();
  CertifyOptions co = o.certify;
  co.threads = threads;
  const int p = mesh.degree();
  const int nn = mesh.num_nodes();
  const auto& conn = mesh.elements();
  std::vector<ElementCertificate<Family>> cert = certify_surface_elements(mesh, surface, uv, co);
  CertificationOutcome out = certification_outcome(cert, RepairStop::certified);

  const QuadratureRule<2>& base_rule = quadrature_for<Family, Q>(p);
  const Tabulation<Family>& base_tab = tabulation<Family, Nodes>(p, base_rule);
  const double weight = o.sentinel_weight * std::accumulate(base_rule.weights.begin(), base_rule.weights.end(), 0.0) /
                        double(base_rule.size());
  const std::vector<bool> mesh_free = surface_free_node_mask(mesh);
  const detail::NodeElements by_node(conn, nn);
  detail::SentinelPoints<Family> sentinels;
  std::size_t solved_with = 0;
  const Eigen::Matrix2Xd uv_start = uv;
  const auto cert_start = cert;
  auto uncertified = [](const auto& c) {
    return std::count_if(c.begin(), c.end(), [](const auto& e) { return e.status != Certificate::certified_valid; });
  };
  // Puts node k at parameters u (its position and classification follow).
  auto place = [&](int k, const Eigen::Vector2d& u) {
    uv.col(k) = u;
    mesh.nodes().col(k) = surface.evaluate(u);
    NodeClass& c = mesh.node_class(k);
    if (c.num_params == 2 && c.entity && c.entity->dim == 2) c.params = {u(0), u(1)};
  };

  so.stage = "surface certify";
  so.target_quality = 0.0;  // the round's quality includes its sentinels; converge instead
  for (;;) {
    bool any = false;
    const std::vector<int> failing = detail::repairable_elements<Family, Nodes>(p, cert, conn, mesh_free, any);
    if (!any) {
      out.reason = RepairStop::certified;
      break;
    }
    if (failing.empty()) {
      out.reason = RepairStop::held;
      break;
    }
    if (out.rounds >= o.max_rounds) {
      out.reason = RepairStop::round_limit;
      break;
    }
    for (int e : failing) sentinels.add(cert[e]);
    if (sentinels.size() == solved_with) {
      out.reason = RepairStop::no_progress;
      break;
    }

    // The patch (step 2), wider for a pull-back (step 3).
    auto certified = [&](const std::vector<int>& elements, const Eigen::Matrix2Xd& U) {
      const detail::SerialEigenScope serial;
      std::vector<char> ok(elements.size());
      const int m = int(elements.size());
      HOM_PARALLEL_FOR_DYNAMIC(detail::useful_threads(detail::resolve_threads(threads), m, 4))
      for (int b = 0; b < m; ++b)
        ok[b] = detail::certify_on_surface<Family, Nodes>(p, surface, U, conn.col(elements[b]), o.certify).status ==
                Certificate::certified_valid;
      return std::all_of(ok.begin(), ok.end(), [](char v) { return v != 0; });
    };
    const bool pull_back = valid_start != nullptr && certified(failing, *valid_start);
    const int rings = pull_back ? std::max(1, o.pull_back_rings) : 1;
    const detail::RepairPatch patch = detail::repair_patch(conn, nn, by_node, failing, rings, mesh_free);
    if (patch.num_free == 0) {
      out.reason = RepairStop::no_free_nodes;
      break;
    }
    const std::vector<int>& elements = patch.elements;
    const std::vector<int>& nodes = patch.nodes;
    const std::vector<bool>& free = patch.free;
    Eigen::Matrix2Xd U(2, Eigen::Index(nodes.size()));
    for (std::size_t k = 0; k < nodes.size(); ++k) U.col(Eigen::Index(k)) = uv.col(nodes[k]);
    std::vector<SurfaceIdealVertices<Family>> patch_ideals;
    for (int e : elements) patch_ideals.push_back(ideals[e]);
    // The patch's parameters as a mesh-wide matrix, for `certified`.
    auto on_mesh = [&](const Eigen::Matrix2Xd& V) {
      Eigen::Matrix2Xd W = uv;
      for (std::size_t k = 0; k < nodes.size(); ++k) W.col(nodes[k]) = V.col(Eigen::Index(k));
      return W;
    };
    auto certified_along = [&](const Eigen::Matrix2Xd& from, const Eigen::Matrix2Xd& to,
                               double first) -> std::optional<Eigen::Matrix2Xd> {
      for (double t = first;; t = t > 1.0 / 4096 ? 0.5 * t : 0.0) {
        Eigen::Matrix2Xd V = from + t * (to - from);  // held nodes: from = to
        if (certified(elements, on_mesh(V))) return V;
        if (t == 0.0) return std::nullopt;
      }
    };
    Eigen::Matrix2Xd start_of_round = U;
    bool certified_start = false;
    if (pull_back) {
      Eigen::Matrix2Xd S = U;
      for (std::size_t k = 0; k < nodes.size(); ++k)
        if (free[k]) S.col(Eigen::Index(k)) += patch.weight[k] * (valid_start->col(nodes[k]) - U.col(Eigen::Index(k)));
      if (auto V = certified_along(S, U, 0.5)) {
        start_of_round = std::move(*V);
        certified_start = true;
        ++out.pull_backs;
      }
    }

    const Tabulation<Family> tab = sentinel_tabulation<Family, Nodes>(p, base_rule, sentinels.points(), weight);
    Problem problem(tab, surface, start_of_round, patch.connectivity, free, patch_ideals, measure);
    problem.set_threads(threads);
    problem.set_regularization_alpha(alpha);
    const Problem at_quadrature(base_tab, surface, U, patch.connectivity, free, patch_ideals, measure);
    out.repairs.push_back(NewtonSolver{}.solve(problem, so));
    if (certified_start) problem.coordinates() = *certified_along(start_of_round, problem.coordinates(), 1.0);
    ++out.rounds;
    solved_with = sentinels.size();
    out.sentinel_points = int(sentinels.size());

    // Step 4: keep the round unless it made things worse.
    const int invalid_before = at_quadrature.status(U).inverted;
    const int invalid_after = at_quadrature.status(problem.coordinates()).inverted;
    for (std::size_t k = 0; k < nodes.size(); ++k)
      if (free[k]) place(nodes[k], problem.coordinates().col(Eigen::Index(k)));
    std::vector<ElementCertificate<Family>> recert = certify_surface_elements(mesh, surface, uv, co, &elements);
    int uncertified_before = 0, uncertified_after = 0;
    for (std::size_t b = 0; b < elements.size(); ++b) {
      uncertified_before += cert[elements[b]].status != Certificate::certified_valid;
      uncertified_after += recert[b].status != Certificate::certified_valid;
    }
    if (invalid_after > invalid_before || uncertified_after > uncertified_before) {
      for (std::size_t k = 0; k < nodes.size(); ++k)
        if (free[k]) place(nodes[k], U.col(Eigen::Index(k)));
      out.reason = RepairStop::worse;
      break;
    }
    for (std::size_t b = 0; b < elements.size(); ++b) cert[elements[b]] = std::move(recert[b]);
  }

  if (out.rounds > 0 && uncertified(cert) >= uncertified(cert_start)) {
    for (int k = 0; k < nn; ++k)
      if (mesh_free[k]) place(k, uv_start.col(k));
    cert = cert_start;
    out.restored = true;
  }
  out.set_final(certification_outcome(cert, out.reason));
  out.on_surface = true;
  out.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace hom
