// Certification as the optimizer's final acceptance test (issue 8,
// include/hom/optimize/certified.hpp): meshes that the quadrature-point check
// calls valid after optimization but that fold at an element corner are
// repaired until certified; a mesh that certifies valid is left bitwise
// unchanged; the result's counts and element list are hom::certify_mesh's on
// the result mesh. Folds are checked independently of the Bernstein
// certificate through the Lagrange basis (Mesh::jacobian).
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "hom/basis/lagrange.hpp"
#include "hom/io/certification_report.hpp"
#include "hom/mesh/elevate.hpp"
#include "hom/mesh/structured.hpp"
#include "hom/nodes/warp_blend.hpp"
#include "hom/optimize/certified.hpp"
#include "hom/optimize/optimize.hpp"
#include "hom/quality/certify.hpp"
#include "test_meshes.hpp"

using namespace hom;

namespace {

using testing::box_mesh;
using testing::mesh_state;
using testing::TestMesh;

/// A curved boundary that folds an element at a corner: the fixed high-order
/// node of the face y = 0 nearest to (1/n + 1/(2 n p), 0[, 1/(2n)]) moves by
/// (-shift, +height) / n, so the boundary edge's tangent at its end vertex
/// turns into the element. Returns the mesh and its straight-sided ideal
/// (from the unmoved mesh).
template <class F>
std::pair<TestMesh<F>, IdealMesh<F>> folded_mesh(int n, int p, double shift, double height) {
  auto mesh = box_mesh<F>(n, p);
  const auto ideal = make_ideal_mesh(mesh, IdealKind::straight_sided);
  typename F::Point target = F::Point::Zero();
  target[0] = 1.0 / n + 0.5 / (n * p);
  if constexpr (F::dim == 3) target[2] = 0.5 / n;
  int best = -1;
  double distance = 1e300;
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    if (mesh.node_class(i).kind == NodeKind::free || std::abs(mesh.node(i)[1]) > 1e-12) continue;
    const double d = (mesh.node(i) - target).norm();
    if (d < distance) {
      distance = d;
      best = i;
    }
  }
  REQUIRE(best >= 0);
  mesh.nodes()(0, best) -= shift / n;
  mesh.nodes()(1, best) += height / n;
  return {std::move(mesh), ideal};
}

/// The result's certification against certify_mesh on the result mesh.
template <class MeshT>
void check_counts(const OptimizeResult& r, const MeshT& mesh, int depth) {
  REQUIRE(r.certification.has_value());
  const auto& c = *r.certification;
  CertifyOptions co;
  co.max_depth = depth;
  const auto cert = certify_mesh(mesh, co);
  CHECK(c.valid == cert.valid);
  CHECK(c.invalid == cert.invalid);
  CHECK(c.undecided == cert.undecided);
  CHECK(c.min_scaled_jacobian == cert.min_scaled_jacobian);
  std::vector<int> uncertified;
  for (int e = 0; e < mesh.num_elements(); ++e)
    if (cert.elements[e].status != Certificate::certified_valid) uncertified.push_back(e);
  CHECK(c.uncertified == uncertified);
  CHECK(c.certified() == (cert.valid == mesh.num_elements()));
  CHECK(r.certified() == c.certified());
  CHECK(c.valid + c.invalid + c.undecided == mesh.num_elements());
  CHECK(c.initial_valid + c.initial_invalid + c.initial_undecided == mesh.num_elements());
}

template <class F, int P>
struct FoldCase {
  using Family = F;
  static constexpr int degree = P;
};

/// (cells per axis, shift, height) of folded_mesh, from mild to severe.
/// Whether plain optimization leaves a fold is checked per configuration (the
/// premise); the larger shifts turn the boundary tangent back by more than
/// 90 degrees, which the free nodes cannot always undo.
template <class F>
std::vector<std::array<double, 3>> fold_configurations() {
  const int n = F::dim == 2 ? 3 : 2;
  std::vector<std::array<double, 3>> c;
  for (double shift : {0.3, 0.6})
    for (double height : {0.2, 0.4, 0.6, 0.8}) c.push_back({double(n), shift, height});
  return c;
}

/// One thread: the optimizer's result does not depend on the thread count in
/// exact arithmetic, but whether a corner fold survives is decided by small
/// differences, so every run of a comparison uses the same setting.
OptimizeOptions one_thread() {
  OptimizeOptions o;
  o.threads = 1;
  return o;
}

}  // namespace

TEST_CASE_TEMPLATE("certify: a corner fold that plain optimization leaves is repaired until certified", C,
                   FoldCase<Simplex<2>, 3>, FoldCase<Simplex<3>, 2>) {
  using F = typename C::Family;
  const int p = C::degree;
  int folds = 0, repaired_folds = 0;
  for (const auto& [n, shift, height] : fold_configurations<F>()) {
    CAPTURE(shift);
    CAPTURE(height);
    auto [plain, ideal] = folded_mesh<F>(int(n), p, shift, height);
    auto repaired = plain;
    OptimizeOptions o = one_thread();

    // The premise: plain optimization succeeds at the quadrature points...
    const auto r0 = optimize(plain, ideal, o);
    CHECK_FALSE(r0.certification.has_value());
    CHECK_FALSE(r0.certified());
    if (r0.result.inverted > 0) continue;
    REQUIRE(mesh_state(plain, ideal).inverted == 0);
    // ... and certification rejects an element, with a point where the
    // Lagrange Jacobian confirms det <= 0.
    const auto before = certify_mesh(plain);
    if (before.invalid == 0) continue;
    ++folds;
    std::vector<int> failing;
    for (int e = 0; e < plain.num_elements(); ++e)
      if (before.elements[e].status == Certificate::certified_invalid) {
        failing.push_back(e);
        REQUIRE(before.elements[e].invalid_point.has_value());
        CHECK(plain.jacobian(e, *before.elements[e].invalid_point).determinant() <= 1e-12);
      }

    o.certify = true;
    const auto r = optimize(repaired, ideal, o);
    REQUIRE(r.certification.has_value());
    const auto& c = *r.certification;
    CHECK(c.initial_valid == before.valid);
    CHECK(c.initial_invalid == before.invalid);
    CHECK(c.initial_undecided == before.undecided);
    CHECK(c.rounds >= 1);
    CHECK(c.rounds <= o.certify_rounds);
    CHECK(int(c.repairs.size()) == c.rounds);
    check_counts(r, repaired, o.certify_depth);
    if (!r.certified()) {
      // Not repaired: the result says which, and the mesh is better
      // certified than the plain result or is the plain result.
      CHECK(c.reason != RepairStop::certified);
      CHECK_FALSE(c.uncertified.empty());
      if (c.restored) CHECK(repaired.nodes() == plain.nodes());
      CHECK((c.invalid + c.undecided < before.invalid + before.undecided || repaired.nodes() == plain.nodes()));
      continue;
    }
    ++repaired_folds;
    CHECK(c.reason == RepairStop::certified);
    CHECK_FALSE(c.restored);
    // Still valid at the quadrature points, and the result says so.
    const auto state = mesh_state(repaired, ideal);
    CHECK(state.inverted == 0);
    CHECK(r.result.inverted == 0);
    CHECK(r.result.min_quality == doctest::Approx(state.min_quality).epsilon(1e-12));
    // Independently: det > 0 at the old failing points and at every vertex.
    for (int e : failing) {
      CHECK(repaired.jacobian(e, *before.elements[e].invalid_point).determinant() > 0.0);
      for (int v = 0; v < F::num_vertices; ++v) CHECK(repaired.jacobian(e, F::vertex(v)).determinant() > 0.0);
    }
    // Local: with one round, only nodes of elements sharing a node with a
    // failing element move (the normal stage is the same run), or, when the
    // round pulled its patch back towards the stage's start, of elements
    // within pull_back_rings such rings.
    if (c.rounds == 1) {
      std::set<int> ring_nodes;
      for (int e : failing)
        for (int i = 0; i < plain.nodes_per_element(); ++i) ring_nodes.insert(plain.elements()(i, e));
      const int rings = c.pull_backs > 0 ? CertifyRepairOptions{}.pull_back_rings : 1;
      for (int r = 0; r < rings; ++r) {
        std::set<int> grown = ring_nodes;
        for (int e = 0; e < plain.num_elements(); ++e) {
          bool ring = false;
          for (int i = 0; i < plain.nodes_per_element(); ++i) ring = ring || ring_nodes.count(plain.elements()(i, e));
          if (ring)
            for (int i = 0; i < plain.nodes_per_element(); ++i) grown.insert(plain.elements()(i, e));
        }
        ring_nodes = std::move(grown);
      }
      int moved = 0;
      for (int i = 0; i < plain.num_nodes(); ++i)
        if (plain.node(i) != repaired.node(i)) {
          ++moved;
          CHECK(ring_nodes.count(i) == 1);
          CHECK(plain.node_class(i).kind == NodeKind::free);
        }
      CHECK(moved > 0);
    }
  }
  CHECK(folds >= 4);  // the construction produced the case under test
  CHECK(repaired_folds >= 3);
  MESSAGE(repaired_folds << " of " << folds << " folds repaired");
}

TEST_CASE_TEMPLATE("certify: a mesh that certifies valid is left bitwise unchanged", F, Simplex<2>, Cube<2>, Simplex<3>,
                   Cube<3>) {
  const int p = F::dim == 2 ? 4 : 3;
  auto a = box_mesh<F>(2, p);
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-0.02, 0.02);
  for (int i = 0; i < a.num_nodes(); ++i)
    if (a.node_class(i).kind == NodeKind::free)
      for (int k = 0; k < F::dim; ++k) a.nodes()(k, i) += u(rng);
  auto b = a;
  OptimizeOptions o = one_thread();
  const auto ra = optimize(a, o);
  REQUIRE(certify_mesh(a).valid == a.num_elements());  // the premise
  o.certify = true;
  const auto rb = optimize(b, o);
  CHECK(a.nodes() == b.nodes());  // bitwise
  REQUIRE(rb.certification.has_value());
  const auto& c = *rb.certification;
  CHECK(c.rounds == 0);  // one certification, no repair
  CHECK(c.repairs.empty());
  CHECK(c.reason == RepairStop::certified);
  CHECK(c.initial_valid == a.num_elements());
  CHECK(rb.certified());
  CHECK(rb.result.iterations == ra.result.iterations);
  CHECK(rb.result.objective == ra.result.objective);
  CHECK(rb.result.min_quality == ra.result.min_quality);
  check_counts(rb, b, o.certify_depth);
}

TEST_CASE("certify: with no repair rounds the stage only reports, and names the folded elements") {
  auto [plain, ideal] = folded_mesh<Simplex<2>>(3, 3, 0.3, 0.4);
  auto reported = plain;
  OptimizeOptions o = one_thread();
  optimize(plain, ideal, o);
  REQUIRE(certify_mesh(plain).invalid > 0);  // the premise
  o.certify = true;
  o.certify_rounds = 0;
  const auto r = optimize(reported, ideal, o);
  CHECK(plain.nodes() == reported.nodes());
  REQUIRE(r.certification.has_value());
  const auto& c = *r.certification;
  CHECK(c.rounds == 0);
  CHECK(c.reason == RepairStop::round_limit);
  CHECK_FALSE(r.certified());
  CHECK(c.invalid == c.initial_invalid);
  CHECK_FALSE(c.uncertified.empty());
  check_counts(r, reported, o.certify_depth);
}

TEST_CASE("certify: sentinel points extend the rule; a fold at a sentinel makes the element invalid to the optimizer") {
  using F = Simplex<2>;
  const int p = 3;
  auto [mesh, ideal] = folded_mesh<F>(3, p, 0.3, 0.4);
  optimize(mesh, ideal, one_thread());
  const auto cert = certify_mesh(mesh);
  int e = -1;
  for (int k = 0; k < mesh.num_elements() && e < 0; ++k)
    if (cert.elements[k].status == Certificate::certified_invalid) e = k;
  REQUIRE(e >= 0);
  const auto x = *cert.elements[e].invalid_point;

  const auto& rule = quadrature_for<F, DefaultExactness>(p);
  const auto& base = tabulation<F, WarpBlend>(p, rule);
  const std::vector<F::Point> sentinels{F::vertex(0), x};
  const auto tab = sentinel_tabulation<F, WarpBlend>(p, rule, sentinels, 0.25);
  const int nq = rule.size();
  REQUIRE(tab.num_points() == nq + 2);
  CHECK((tab.shape_gradients.leftCols(2 * nq) - base.shape_gradients).norm() <= 1e-12 * base.shape_gradients.norm());
  CHECK(tab.rule.weights[nq] == 0.25);
  CHECK(tab.rule.weights[nq + 1] == 0.25);
  const auto& basis = lagrange_basis<F, WarpBlend>(p);
  for (int s = 0; s < 2; ++s) {
    const Eigen::MatrixXd g = basis.gradient(sentinels[s]);  // n x Dim
    CHECK((tab.shape_gradients.middleCols(2 * (nq + s), 2) - g).norm() <= 1e-12 * g.norm());
  }

  const auto conn = mesh.elements();
  std::vector<IdealAtPoints<2>> at_base, at_sentinels;
  for (int k = 0; k < mesh.num_elements(); ++k) {
    at_base.push_back(ideal_at_points<F>(base, ideal.vertices(k)));
    at_sentinels.push_back(ideal_at_points<F>(tab, ideal.vertices(k)));
  }
  const std::vector<bool> free = free_node_mask(mesh);
  const OptimizationProblem<F> plain(base, mesh.nodes(), conn, free, at_base);
  const OptimizationProblem<F> watched(tab, mesh.nodes(), conn, free, at_sentinels);
  CHECK(plain.status(plain.coordinates()).valid[e]);
  CHECK_FALSE(watched.status(watched.coordinates()).valid[e]);
  CHECK(watched.value(watched.coordinates()) == std::numeric_limits<double>::infinity());  // sigma_0's barrier
}

// det D phi_P = (xi_0 - c)^2 + delta: positive everywhere, close to 0 near
// xi_0 = c, undecided at a shallow depth. The certificate names where det came
// closest to 0 (the certify stage's sentinel for undecided elements).
TEST_CASE_TEMPLATE("certify: an undecided element names its weakest point", F, Simplex<2>, Cube<2>, Simplex<3>) {
  const int p = 3;
  const double c = 0.3, delta = 1e-3;
  const auto ref = WarpBlend::points<F>(p);
  Eigen::Matrix<double, F::dim, Eigen::Dynamic> X(F::dim, Eigen::Index(ref.size()));
  for (std::size_t j = 0; j < ref.size(); ++j) {
    typename F::Point y = ref[j];
    y[0] = std::pow(y[0] - c, 3) / 3.0 + delta * y[0];
    X.col(Eigen::Index(j)) = y;
  }
  CertifyOptions shallow;
  shallow.max_depth = 1;
  const auto cert = certify_element<F>(jacobian_bernstein<F, WarpBlend>(p), X, shallow);
  REQUIRE(cert.status == Certificate::undecided);
  CHECK_FALSE(cert.invalid_point.has_value());
  REQUIRE(cert.weakest_point.has_value());
  const auto& basis = lagrange_basis<F, WarpBlend>(p);
  auto det = [&](const typename F::Point& x) { return (X * basis.gradient(x)).determinant(); };
  double vertex_min = std::numeric_limits<double>::infinity();
  for (int v = 0; v < F::num_vertices; ++v) vertex_min = std::min(vertex_min, det(F::vertex(v)));
  CHECK(det(*cert.weakest_point) > 0.0);
  CHECK(det(*cert.weakest_point) < vertex_min);  // nearer the valley than any corner
  CertifyOptions deep;
  deep.max_depth = 10;
  const auto valid = certify_element<F>(jacobian_bernstein<F, WarpBlend>(p), X, deep);
  CHECK(valid.status == Certificate::certified_valid);
  CHECK_FALSE(valid.weakest_point.has_value());
}

TEST_CASE_TEMPLATE("certify: a fold between the quadrature points is pulled back towards the stage's valid start", F,
                   Simplex<2>, Simplex<3>) {
  // A straight-sided degree-2 mesh (certified valid) in which the node of an
  // interior edge slides towards one end, to 0.2 of the edge: the edge's
  // tangent at that vertex, 4 x_mid - 3 x_v - x_w, turns back, so every
  // element around the edge folds at the vertex, where no quadrature point is.
  const auto start = box_mesh<F>(3, 2);
  const auto ideal = make_ideal_mesh(start, IdealKind::straight_sided);
  auto mesh = start;
  int moved = -1;
  for (int e = 0; e < mesh.num_elements() && moved < 0; ++e)
    for (int j = 0; j < int(F::edges().size()) && moved < 0; ++j) {
      const auto nodes = mesh.element(e);
      const int v = nodes[F::edges()[j][0]], w = nodes[F::edges()[j][1]], mid = nodes[F::num_vertices + j];
      if (mesh.node_class(v).kind != NodeKind::free || mesh.node_class(w).kind != NodeKind::free) continue;
      mesh.node(mid) = mesh.node(v) + 0.2 * (mesh.node(w) - mesh.node(v));
      moved = mid;
    }
  REQUIRE(moved >= 0);
  REQUIRE(mesh_state(mesh, ideal).inverted == 0);  // valid at every quadrature point
  REQUIRE(certify_mesh(mesh).invalid > 0);         // and folded between them

  SolverOptions no_steps;  // the round's solve takes no step: only the pull-back can repair
  no_steps.max_iterations = 0;
  auto without = mesh;
  const auto a = certify_and_repair<ShapeMeasure, DefaultExactness>(without, ideal, NewtonSolver{}, no_steps,
                                                                     CertifyRepairOptions{}, 1, Regularization{});
  CHECK_FALSE(a.certified());
  const auto b = certify_and_repair<ShapeMeasure, DefaultExactness>(mesh, ideal, NewtonSolver{}, no_steps,
                                                                     CertifyRepairOptions{}, 1, Regularization{},
                                                                     ShapeMeasure{}, &start.nodes());
  CHECK(b.certified());
  CHECK(b.reason == RepairStop::certified);
  CHECK(b.rounds >= 1);
  CHECK(b.pull_backs >= 1);
  CHECK(a.pull_backs == 0);
  CHECK(certify_mesh(mesh).valid == mesh.num_elements());
  // The moved node went back along its segment, part of the way; the other
  // nodes of the patch were where the start has them and stay there.
  const auto x0 = start.node(moved), x = mesh.node(moved), folded = without.node(moved);
  const double t = (x - x0).dot(folded - x0) / (folded - x0).squaredNorm();
  CHECK((x - x0 - t * (folded - x0)).norm() <= 1e-12);
  CHECK(t > 0.0);
  CHECK(t < 1.0);
  for (int i = 0; i < mesh.num_nodes(); ++i)
    if (i != moved) CHECK(mesh.node(i) == start.node(i));
}

// The tools' certificate lines (io/certification_report.hpp), written to a
// temporary file: counts, the repair line, the first ten uncertified elements
// and the stop reason, and nothing about uncertified elements when all hold.
TEST_CASE("print_certification: the counts, the repair rounds and the first ten uncertified elements") {
  auto printed = [](const CertificationOutcome& c) {
    std::FILE* f = std::tmpfile();
    REQUIRE(f);
    hom::io::print_certification(c, 6, f);
    std::rewind(f);
    std::string text;
    for (int ch; (ch = std::fgetc(f)) != EOF;) text += char(ch);
    std::fclose(f);
    return text;
  };
  CertificationOutcome c;
  c.initial_valid = 88;
  c.initial_invalid = 12;
  c.valid = 88;
  c.invalid = 12;
  c.rounds = 2;
  c.reason = RepairStop::no_progress;
  for (int e = 0; e < 12; ++e) c.uncertified.push_back(3 * e);
  const std::string text = printed(c);
  CHECK(text.find("subdivision depth <= 6") != std::string::npos);
  CHECK(text.find("after optimization: 88 certified valid, 12 certified invalid, 0 undecided") != std::string::npos);
  CHECK(text.find("repair: 2 rounds") != std::string::npos);
  const std::string first_ten = "NOT CERTIFIED: elements 0 3 6 9 12 15 18 21 24 27 ... (no new sentinel point)";
  CHECK(text.find(first_ten) != std::string::npos);
  CHECK(text.find(" 30") == std::string::npos);  // the eleventh is left out

  CertificationOutcome ok;
  ok.initial_valid = ok.valid = 5;
  ok.min_scaled_jacobian = 0.25;
  const std::string fine = printed(ok);
  CHECK(fine.find("final: 5 certified valid, 0 certified invalid, 0 undecided") != std::string::npos);
  CHECK(fine.find("certified min scaled Jacobian >= 0.2500") != std::string::npos);
  CHECK(fine.find("NOT CERTIFIED") == std::string::npos);
  CHECK(fine.find("repair:") == std::string::npos);
}
