#pragma once
/// @file certified.hpp
/// Certification as the optimizer's final acceptance test (issue 8).
///
/// The objective (eq 4.10) and the validity test of the line search and of the
/// regularization (section 4.2.2) see det D phi_P only at the quadrature
/// points, so an optimized element can be valid there and still fold between
/// them (proposition 3.1 says no more); the known real case is a fold at a
/// corner node, which no interior quadrature point sees. `certify_and_repair`
/// certifies every element (quality/certify.hpp) and, while some element is
/// certified invalid or undecided, runs repair rounds:
///
///   1. Sentinel points. The reference points where certification found
///      det <= 0 (invalid_point) or came closest to it (weakest_point), with
///      the reference vertices from the first round on, are appended to the
///      quadrature rule with a small weight (sentinel_weight times the mean
///      weight). The points are reference coordinates, shared by every element
///      of the round's problem: one tabulation, as in the normal stage.
///      Through the rule a sentinel enters everything that reads quadrature
///      points: the objective (its (eta - 1)^2 term), the validity test
///      (MeshState, so an element with det <= 0 at a sentinel is regularized
///      as invalid, eqs 4.12-4.14, until det > 0 there) and the line search's
///      barrier (sigma_0 returns +inf at a sentinel too, so no accepted step
///      folds a valid element at its sentinels).
///   2. A local problem. Free: the free nodes of the failing elements and of
///      the elements sharing a node with them (a corner fold is often fixed by
///      an edge node of the neighbour). Problem: every element that has a free
///      node, everything else held.
///   3. A valid start for it, when one is known (`valid_start`: the normal
///      stage's starting configuration, e.g. a straight-sided mesh, in which
///      the failing elements certify valid; counted in pull_backs): the patch
///      then reaches pull_back_rings rings out, and its free nodes are pulled
///      back towards their positions there, the failing elements' all the
///      way and the others by less the farther out they are (w = 1 - ring /
///      (rings + 1)), so that no element mixes the start with the stage's
///      result: x(t) = x + (1 - t) w (x_start - x), t = 1/2, 1/4, ..., 2^-12,
///      0, to the first t at which every element of the problem is certified
///      valid. The
///      round then starts with no element invalid anywhere, so no element is
///      regularized and the barrier guards every point, sentinels included:
///      the solve improves the patch without folding it at those points
///      again; should it fold them elsewhere, between its points, the solve's
///      result is pulled back in the same way towards the round's start, so
///      a round that starts certified ends certified. Without it the failing
///      elements start invalid at their
///      sentinels and are regularized (delta > 0), and a regularized element
///      is free to fold anywhere: with an ideal the mesh cannot attain (the
///      equilateral tetrahedron of table 4.4 on a graded mesh) the regularized
///      optimum can keep the fold (measured: table 4.4 at p = 2, 2 elements
///      folded at a vertex stayed folded after 200 iterations and became
///      invalid at their quadrature points too).
///      Solved by the normal stage's solver.
///   4. Acceptance. The round's elements are certified again. A round that
///      leaves more elements invalid at the quadrature points, or more
///      elements uncertified, than before it is undone, and the stage stops.
///
/// Elements that cannot be repaired are left out: det at a point depends only
/// on the nodes whose shape functions have a non-zero gradient there, so an
/// element certified invalid at a point where all of those nodes are held
/// (boundary nodes: a sliver whose nodes all lie on the curved boundary)
/// keeps det <= 0 there whatever the free nodes do.
///
/// It stops when every element is certified valid, after max_rounds rounds,
/// when a round would learn no new sentinel point (the same problem again),
/// when the failing elements are all held or have no free node nearby, or on
/// an undone round (RepairStop). If the rounds end with no fewer uncertified
/// elements than they started with, the mesh is restored to the normal
/// stage's result: the stage never trades quality for nothing. Elements certified valid at the start of a round are the
/// only ones the barrier protects at their sentinels; a neighbour that
/// becomes uncertified between its points is caught by the next
/// certification. On a mesh that certifies valid the stage costs one
/// certification and moves nothing. The normal stage's kernels are not
/// touched: the extra points exist only in the small local problems.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <string_view>
#include <vector>

#include "hom/detail/repair_patch.hpp"
#include "hom/mesh/mesh.hpp"
#include "hom/optimize/element_objective.hpp"
#include "hom/optimize/mesh_problem.hpp"
#include "hom/optimize/problem.hpp"
#include "hom/optimize/solver.hpp"
#include "hom/quadrature/quadrature_policy.hpp"
#include "hom/quality/certify.hpp"
#include "hom/quality/tabulation.hpp"

namespace hom {

/// Why the certify stage stopped.
enum class RepairStop {
  certified,      ///< every element certified valid
  round_limit,    ///< max_rounds repair rounds ran
  no_progress,    ///< no new sentinel point to add: another round would solve the same problem
  no_free_nodes,  ///< the uncertified elements have no free node within one element
  held,           ///< each uncertified element folds at a point where only held nodes determine det
  worse,          ///< the last round left more elements invalid or uncertified; it was undone
  not_repaired,   ///< certified only: no repair stage ran (CAD faces that are not optimized)
};

inline std::string_view to_string(RepairStop s) {
  switch (s) {
    case RepairStop::certified: return "certified";
    case RepairStop::round_limit: return "round limit";
    case RepairStop::no_progress: return "no new sentinel point";
    case RepairStop::no_free_nodes: return "no free nodes";
    case RepairStop::held: return "fold fixed by held nodes";
    case RepairStop::worse: return "round undone";
    case RepairStop::not_repaired: return "certified only, no repair stage";
  }
  return "?";
}

struct CertifyRepairOptions {
  CertifyOptions certify;        ///< subdivision depth, tolerance, threads
  int max_rounds = 4;            ///< repair rounds at most (0: certify only)
  int pull_back_rings = 3;       ///< node-neighbour rings around the failing elements that a pull-back moves
  double sentinel_weight = 0.1;  ///< a sentinel point's weight / the rule's mean weight
};

/// What the certify stage found and did.
struct CertificationOutcome {
  int initial_valid = 0, initial_invalid = 0, initial_undecided = 0;  ///< certificate before any repair
  int valid = 0, invalid = 0, undecided = 0;                          ///< final certificate
  double min_scaled_jacobian = std::numeric_limits<double>::infinity();  ///< final certified lower bound
  int rounds = 0;             ///< repair rounds kept or undone
  int pull_backs = 0;         ///< rounds that started from a patch pulled back towards the valid start
  int sentinel_points = 0;    ///< sentinel points of the last round
  RepairStop reason = RepairStop::certified;
  /// The rounds left no fewer uncertified elements than they started with,
  /// so the mesh was put back as the normal stage left it.
  bool restored = false;
  std::vector<int> uncertified;       ///< elements not certified valid at the end, ascending
  std::vector<SolverResult> repairs;  ///< each round's local solve
  double time_s = 0.0;                ///< certification and repair
  /// A surface mesh: each element's polynomial map in R^3 certified against
  /// its nodes' interpolated surface normals, g = (x_xi x x_eta) . n
  /// (surface/certified_surface.hpp). min_scaled_jacobian then bounds
  /// min g / max g, not the surface element's scaled Jacobian, and is not
  /// reported.
  bool on_surface = false;

  bool certified() const { return invalid == 0 && undecided == 0; }

  /// Takes the final state from `last` (the certificate at the end: counts,
  /// bound, uncertified elements); the initial counts, rounds and reason stay.
  void set_final(const CertificationOutcome& last) {
    valid = last.valid;
    invalid = last.invalid;
    undecided = last.undecided;
    min_scaled_jacobian = last.min_scaled_jacobian;
    uncertified = last.uncertified;
  }

  /// Adds the outcome of another part of the mesh (a CAD face's stage, say):
  /// counts, rounds and times add up, the first part left uncertified gives
  /// the reason, and `element_of` maps part's element numbers to this one's.
  void add(const CertificationOutcome& part, const std::vector<int>& element_of) {
    initial_valid += part.initial_valid;
    initial_invalid += part.initial_invalid;
    initial_undecided += part.initial_undecided;
    valid += part.valid;
    invalid += part.invalid;
    undecided += part.undecided;
    min_scaled_jacobian = std::min(min_scaled_jacobian, part.min_scaled_jacobian);
    rounds += part.rounds;
    pull_backs += part.pull_backs;
    sentinel_points = std::max(sentinel_points, part.sentinel_points);
    if (reason == RepairStop::certified) reason = part.reason;
    restored = restored || part.restored;
    for (int e : part.uncertified) uncertified.push_back(element_of[e]);
    std::sort(uncertified.begin(), uncertified.end());
    repairs.insert(repairs.end(), part.repairs.begin(), part.repairs.end());
    time_s += part.time_s;
  }
};

/// The tabulation of `base` followed by `sentinels` (reference points), each
/// of weight `weight`. No sum factorization: the rule is no longer a
/// collapsed tensor rule.
template <ElementFamily Family, NodeSet Nodes>
Tabulation<Family> sentinel_tabulation(int p, const QuadratureRule<Family::dim>& base,
                                       const std::vector<typename Family::Point>& sentinels, double weight) {
  QuadratureRule<Family::dim> rule = base;
  for (const auto& x : sentinels) {
    rule.points.push_back(x);
    rule.weights.push_back(weight);
  }
  rule.name = base.name + " + " + std::to_string(sentinels.size()) + " sentinel points";
  Tabulation<Family> t = make_tabulation<Family, Nodes>(p, rule);
  t.sum_factorization.reset();
  return t;
}

namespace detail {

/// Whether every element of the patch (node coordinates X, connectivity C)
/// is certified valid.
template <ElementFamily Family, NodeSet Nodes, class Coordinates, class Connectivity>
bool patch_certified(int p, const Coordinates& X, const Connectivity& C, const CertifyOptions& o, int threads) {
  const detail::SerialEigenScope serial;
  const auto& jb = jacobian_bernstein<Family, Nodes>(p);
  const int m = int(C.cols());
  std::vector<char> valid(m);
  HOM_PARALLEL_FOR_DYNAMIC(detail::useful_threads(detail::resolve_threads(threads), m, 4))
  for (int b = 0; b < m; ++b) {
    Eigen::Matrix<double, Family::dim, Eigen::Dynamic> x(Family::dim, C.rows());
    for (Eigen::Index i = 0; i < C.rows(); ++i) x.col(i) = X.col(C(i, b));
    valid[b] = certify_element<Family>(jb, x, o).status == Certificate::certified_valid;
  }
  return std::all_of(valid.begin(), valid.end(), [](char v) { return v != 0; });
}

struct CertifyCounts {
  int valid = 0, invalid = 0, undecided = 0;
};

template <class Certificates>
CertifyCounts count_certificates(const Certificates& c) {
  CertifyCounts n;
  for (const auto& e : c) {
    n.valid += e.status == Certificate::certified_valid;
    n.invalid += e.status == Certificate::certified_invalid;
    n.undecided += e.status == Certificate::undecided;
  }
  return n;
}

}  // namespace detail

/// The outcome of a certification without repair: counts, bound and
/// uncertified elements of `elements` (one certificate per element, in
/// element order); `reason` is RepairStop::certified when every element is
/// certified valid, `if_uncertified` otherwise.
template <ElementFamily Family>
CertificationOutcome certification_outcome(const std::vector<ElementCertificate<Family>>& elements,
                                           RepairStop if_uncertified) {
  CertificationOutcome out;
  const auto n = detail::count_certificates(elements);
  out.initial_valid = out.valid = n.valid;
  out.initial_invalid = out.invalid = n.invalid;
  out.initial_undecided = out.undecided = n.undecided;
  for (std::size_t e = 0; e < elements.size(); ++e) {
    out.min_scaled_jacobian = std::min(out.min_scaled_jacobian, elements[e].min_scaled_jacobian);
    if (elements[e].status != Certificate::certified_valid) out.uncertified.push_back(int(e));
  }
  out.reason = out.certified() ? RepairStop::certified : if_uncertified;
  return out;
}

/// Certifies every element of `mesh` and repairs the uncertified ones as the
/// file comment describes, moving free nodes of `mesh` in place. `solver`,
/// `so`, `threads`, `regularization` and `measure` are the normal stage's;
/// `valid_start`, when given, the node coordinates the normal stage started
/// from (step 3 of the file comment; used where its elements certify valid).
template <class Measure, QuadraturePolicy Q, class Solver, ElementFamily Family, NodeSet Nodes>
CertificationOutcome certify_and_repair(Mesh<Family, Nodes, Family::dim>& mesh, const IdealMesh<Family>& ideal,
                                        const Solver& solver, SolverOptions so, const CertifyRepairOptions& o, int threads,
                                        const Regularization& regularization, const Measure& measure = {},
                                        const typename Mesh<Family, Nodes, Family::dim>::Coordinates* valid_start = nullptr) {
  using Problem = OptimizationProblem<Family, Measure>;
  const auto start = std::chrono::steady_clock::now();
  CertifyOptions co = o.certify;
  co.threads = threads;
  std::vector<ElementCertificate<Family>> cert = certify_mesh(mesh, co).elements;
  CertificationOutcome out;
  {
    const auto n = detail::count_certificates(cert);
    out.initial_valid = n.valid;
    out.initial_invalid = n.invalid;
    out.initial_undecided = n.undecided;
  }

  const int p = mesh.degree();
  const int nn = mesh.num_nodes(), npe = mesh.nodes_per_element();
  const auto& conn = mesh.elements();
  const QuadratureRule<Family::dim>& base_rule = quadrature_for<Family, Q>(p);
  const Tabulation<Family>& base_tab = tabulation<Family, Nodes>(p, base_rule);
  const double weight = o.sentinel_weight * std::accumulate(base_rule.weights.begin(), base_rule.weights.end(), 0.0) /
                        double(base_rule.size());
  const std::vector<bool> mesh_free = free_node_mask(mesh);
  std::optional<detail::NodeElements> by_node;  // built on the first round
  detail::SentinelPoints<Family> sentinels;
  std::size_t solved_with = 0;  // sentinels of the last round's problem
  // The normal stage's result, kept from the first round on.
  std::optional<typename Mesh<Family, Nodes, Family::dim>::Coordinates> start_nodes;
  std::vector<ElementCertificate<Family>> start_cert;

  so.stage = "certify";
  so.target_quality = 0.0;  // the round's quality includes its sentinels; converge instead
  out.reason = RepairStop::certified;
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
    if (!start_nodes) {
      start_nodes = mesh.nodes();
      start_cert = cert;
    }
    for (int e : failing) sentinels.add(cert[e]);
    if (sentinels.size() == solved_with) {
      out.reason = RepairStop::no_progress;
      break;
    }

    // The round's patch: free nodes of the failing elements and of the
    // elements within `rings` node-neighbour rings of them (one ring, or
    // pull_back_rings for a pull-back); the elements of those nodes.
    if (!by_node) by_node.emplace(conn, nn);
    // A pull-back needs the failing elements valid at the start.
    bool pull_back = valid_start != nullptr;
    if (pull_back) {
      typename Problem::Connectivity Cf(npe, Eigen::Index(failing.size()));
      for (std::size_t b = 0; b < failing.size(); ++b)
        for (int i = 0; i < npe; ++i) Cf(i, Eigen::Index(b)) = conn(i, failing[b]);
      pull_back = detail::patch_certified<Family, Nodes>(p, *valid_start, Cf, o.certify, threads);
    }
    const int rings = pull_back ? std::max(1, o.pull_back_rings) : 1;
    const detail::RepairPatch patch = detail::repair_patch(conn, nn, *by_node, failing, rings, mesh_free);
    if (patch.num_free == 0) {
      out.reason = RepairStop::no_free_nodes;
      break;
    }
    const std::vector<int>& elements = patch.elements;
    const std::vector<int>& nodes = patch.nodes;
    const std::vector<bool>& free = patch.free;
    const typename Problem::Connectivity& C = patch.connectivity;
    typename Problem::Coordinates X(Family::dim, Eigen::Index(nodes.size()));
    for (std::size_t k = 0; k < nodes.size(); ++k) X.col(Eigen::Index(k)) = mesh.node(nodes[k]);
    // Step 3: pull the patch back towards the stage's start until it certifies valid.
    const auto certified_along = [&](const typename Problem::Coordinates& from, const typename Problem::Coordinates& to,
                                     double first) -> std::optional<typename Problem::Coordinates> {
      for (double t = first;; t = t > 1.0 / 4096 ? 0.5 * t : 0.0) {
        typename Problem::Coordinates Y = from + t * (to - from);  // held nodes: from = to
        if (detail::patch_certified<Family, Nodes>(p, Y, C, o.certify, threads)) return Y;
        if (t == 0.0) return std::nullopt;
      }
    };
    typename Problem::Coordinates start_of_round = X;
    bool certified_start = false;
    if (pull_back) {
      // The pulled-back patch: each free node a fraction 1 - level / (rings +
      // 1) of the way to its start, all the way at the failing elements and
      // fading out towards the held nodes, so that no element mixes nodes at
      // the start with nodes where the stage left them.
      typename Problem::Coordinates S = X;
      for (std::size_t k = 0; k < nodes.size(); ++k)
        if (free[k]) S.col(Eigen::Index(k)) += patch.weight[k] * (valid_start->col(nodes[k]) - X.col(Eigen::Index(k)));
      if (auto Y = certified_along(S, X, 0.5)) {
        start_of_round = std::move(*Y);
        certified_start = true;
        ++out.pull_backs;
      }  // else the start is not valid here either: the round starts from X
    }

    const Tabulation<Family> tab = sentinel_tabulation<Family, Nodes>(p, base_rule, sentinels.points(), weight);
    std::vector<IdealAtPoints<Family::dim>> ideals, base_ideals;
    for (int e : elements) {
      ideals.push_back(ideal_at_points<Family>(tab, ideal.vertices(e)));
      base_ideals.push_back(ideal_at_points<Family>(base_tab, ideal.vertices(e)));
    }
    Problem problem(tab, start_of_round, C, free, std::move(ideals), measure);
    problem.set_threads(threads);
    problem.set_regularization(regularization);
    const Problem at_quadrature(base_tab, X, C, free, std::move(base_ideals), measure);  // validity as the normal stage sees it
    out.repairs.push_back(solver.solve(problem, so));
    // From a certified start the round keeps the patch certified: the solve's
    // step is shortened (towards the start of the round) until it is.
    if (certified_start) problem.coordinates() = *certified_along(start_of_round, problem.coordinates(), 1.0);
    ++out.rounds;
    solved_with = sentinels.size();
    out.sentinel_points = int(sentinels.size());

    // Accept the round unless it made things worse.
    const int invalid_before = at_quadrature.status(X).inverted;
    const int invalid_after = at_quadrature.status(problem.coordinates()).inverted;
    for (std::size_t k = 0; k < nodes.size(); ++k)
      if (free[k]) mesh.nodes().col(nodes[k]) = problem.coordinates().col(Eigen::Index(k));
    std::vector<ElementCertificate<Family>> recert(elements.size());
    {
      const detail::SerialEigenScope serial;
      const auto& jb = jacobian_bernstein<Family, Nodes>(p);
      const int m = int(elements.size());
      HOM_PARALLEL_FOR_DYNAMIC(detail::useful_threads(detail::resolve_threads(threads), m, 4))
      for (int b = 0; b < m; ++b) recert[b] = certify_element<Family>(jb, mesh.element_coordinates(elements[b]), o.certify);
    }
    int uncertified_before = 0, uncertified_after = 0;
    for (std::size_t b = 0; b < elements.size(); ++b) {
      uncertified_before += cert[elements[b]].status != Certificate::certified_valid;
      uncertified_after += recert[b].status != Certificate::certified_valid;
    }
    if (invalid_after > invalid_before || uncertified_after > uncertified_before) {
      for (std::size_t k = 0; k < nodes.size(); ++k)
        if (free[k]) mesh.nodes().col(nodes[k]) = X.col(Eigen::Index(k));
      out.reason = RepairStop::worse;
      break;
    }
    for (std::size_t b = 0; b < elements.size(); ++b) cert[elements[b]] = std::move(recert[b]);
  }

  auto uncertified = [](const auto& c) {
    return std::count_if(c.begin(), c.end(), [](const auto& e) { return e.status != Certificate::certified_valid; });
  };
  if (out.rounds > 0 && uncertified(cert) >= uncertified(start_cert)) {
    mesh.nodes() = *start_nodes;
    cert = std::move(start_cert);
    out.restored = true;
  }
  out.set_final(certification_outcome(cert, out.reason));
  out.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace hom
