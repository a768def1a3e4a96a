// The optimizer of chapter 4 and appendices B-C (include/hom/optimize/):
// global derivatives against finite differences, the three solvers on
// perturbed meshes of every family, agreement between solvers, independence of
// the thread count, consistency (valid elements stay valid), p-continuation
// and curved boundaries.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include <Eigen/Dense>

#include "hom/mesh/elevate.hpp"
#include "hom/mesh/structured.hpp"
#include "hom/optimize/continuation.hpp"
#include "hom/optimize/gauss_seidel.hpp"
#include "hom/optimize/matrix_free_newton.hpp"
#include "hom/optimize/mesh_problem.hpp"
#include "hom/optimize/newton.hpp"
#include "hom/optimize/optimize.hpp"
#include "test_meshes.hpp"

using namespace hom;

namespace {

using testing::box_mesh;
using testing::mesh_state;
using testing::TestMesh;

// Moves every free node by a uniform random vector of the given amplitude per coordinate.
template <class MeshT>
void perturb(MeshT& mesh, double amplitude, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-amplitude, amplitude);
  for (int i = 0; i < mesh.num_nodes(); ++i)
    if (mesh.node_class(i).kind == NodeKind::free)
      for (int a = 0; a < MeshT::space_dim; ++a) mesh.nodes()(a, i) += u(rng);
}

// Annulus r0 < r < r1 of triangles (nt sectors, nr layers), elevated to p,
// boundary nodes projected radially onto the two circles (fixed there).
TestMesh<Simplex<2>> ring_mesh(int nt, int nr, double r0, double r1, int p) {
  using M = TestMesh<Simplex<2>>;
  const int np = (nr + 1) * nt;
  M::Coordinates X(2, np);
  auto id = [&](int i, int j) { return i * nt + (j % nt); };
  for (int i = 0; i <= nr; ++i)
    for (int j = 0; j < nt; ++j) {
      const double r = r0 + (r1 - r0) * i / nr, t = 2 * std::numbers::pi * j / nt;
      X.col(id(i, j)) << r * std::cos(t), r * std::sin(t);
    }
  M::Connectivity conn(3, 2 * nr * nt);
  int e = 0;
  for (int i = 0; i < nr; ++i)
    for (int j = 0; j < nt; ++j) {
      const int a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      for (auto tri : {std::array<int, 3>{a, b, c}, std::array<int, 3>{a, c, d}}) {
        Eigen::Matrix2d J;
        J.col(0) = X.col(tri[1]) - X.col(tri[0]);
        J.col(1) = X.col(tri[2]) - X.col(tri[0]);
        if (J.determinant() < 0) std::swap(tri[1], tri[2]);
        for (int k = 0; k < 3; ++k) conn(k, e) = tri[k];
        ++e;
      }
    }
  M linear(1, X, conn);
  for (int i = 0; i < np; ++i)
    if (i < nt || i >= nr * nt) linear.node_class(i).kind = NodeKind::fixed;
  M mesh = elevate(linear, p);
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    if (mesh.node_class(i).kind == NodeKind::free) continue;
    const double r = mesh.node(i).norm();
    mesh.node(i) *= (r < 0.5 * (r0 + r1) ? r0 : r1) / r;
  }
  return mesh;
}

template <class F>
double max_node_distance(const TestMesh<F>& a, const TestMesh<F>& b) {
  return (a.nodes() - b.nodes()).colwise().norm().maxCoeff();
}

OptimizeOptions tight_options(SolverKind kind) {
  OptimizeOptions o;
  o.solver = kind;
  o.max_iterations = 400;
  o.gradient_tolerance = 1e-10;
  o.objective_tolerance = 1e-14;
  o.quality_tolerance = 1e-12;
  o.threads = 1;
  return o;
}

constexpr SolverKind all_solvers[] = {SolverKind::newton, SolverKind::matrix_free_newton, SolverKind::gauss_seidel};

}  // namespace

TEST_CASE_TEMPLATE("global gradient, Hessian and Hessian-vector products agree with finite differences", F, Simplex<2>,
                   Cube<2>, Simplex<3>, Cube<3>) {
  constexpr int D = F::dim;
  // Perturbed so that some elements are inverted (regularized, delta > 0) and
  // the others valid (sigma_0).
  const int n = D == 2 ? 3 : 2;
  auto mesh = box_mesh<F>(n, 2);
  perturb(mesh, (F::is_simplex ? 0.45 : 0.5) / (2 * n), D == 2 ? 102 : 202);
  auto problem = make_problem(mesh, make_ideal_mesh(mesh, IdealKind::straight_sided));
  const MeshState state = problem.status(problem.coordinates());
  problem.update_regularization(state);
  INFO("inverted elements: ", state.inverted);
  CHECK(state.inverted > 0);
  CHECK(state.inverted < problem.num_elements());

  const auto X = problem.coordinates();
  Eigen::VectorXd g;
  const double f = problem.value_gradient(X, g);
  CHECK(f == doctest::Approx(problem.value(X)).epsilon(1e-14));
  const int nd = problem.num_dofs();
  REQUIRE(nd > 0);
  // Fourth-order central differences: nearly degenerate valid elements have
  // large third derivatives.
  const double h = 1e-5;
  auto derivative = [&](auto&& phi) { return (-phi(2 * h) + 8 * phi(h) - 8 * phi(-h) + phi(-2 * h)) / (12 * h); };
  Eigen::VectorXd fd(nd);
  for (int k = 0; k < nd; ++k) {
    const Eigen::VectorXd ek = Eigen::VectorXd::Unit(nd, k);
    fd[k] = derivative([&](double t) { return problem.value(problem.displaced(X, ek, t)); });
  }
  CHECK((fd - g).norm() <= 1e-7 * g.norm());

  // Exact Hessian: columns against finite differences of the gradient.
  Eigen::SparseMatrix<double> H;
  Eigen::VectorXd g2;
  problem.hessian(X, HessianForm::exact, g2, H);
  CHECK((g2 - g).norm() <= 1e-13 * g.norm());
  const Eigen::MatrixXd Hd = Eigen::MatrixXd(H);
  CHECK((Hd - Hd.transpose()).norm() <= 1e-12 * Hd.norm());
  auto gradient_derivative = [&](const Eigen::VectorXd& v) {
    Eigen::VectorXd out = Eigen::VectorXd::Zero(nd), gt;
    for (auto [t, w] : {std::pair{2 * h, -1.0}, {h, 8.0}, {-h, -8.0}, {-2 * h, 1.0}}) {
      problem.value_gradient(problem.displaced(X, v, t), gt);
      out += w * gt;
    }
    return Eigen::VectorXd(out / (12 * h));
  };
  for (int k = 0; k < nd; k += std::max(1, nd / 12))
    CHECK((gradient_derivative(Eigen::VectorXd::Unit(nd, k)) - Hd.col(k)).norm() <= 1e-6 * Hd.norm());

  // Hessian-vector products, every form, against the assembled matrix of the
  // same form; the exact one also against a directional difference of the gradient.
  std::mt19937 rng(5);
  std::normal_distribution<double> normal;
  Eigen::VectorXd v(nd);
  for (int k = 0; k < nd; ++k) v[k] = normal(rng);
  for (HessianForm form : {HessianForm::exact, HessianForm::projected, HessianForm::gauss_newton}) {
    Eigen::SparseMatrix<double> Hf;
    Eigen::VectorXd gf, hv;
    problem.hessian(X, form, gf, Hf);
    problem.hessian_vector_product(X, form, v, hv);
    const Eigen::VectorXd ref = Hf * v;
    CHECK((hv - ref).norm() <= 1e-12 * (ref.norm() + Eigen::MatrixXd(Hf).norm()));
    if (form != HessianForm::exact) {
      // Projected and Gauss-Newton Hessians are positive semi-definite.
      const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es{Eigen::MatrixXd(Hf)};
      CHECK(es.eigenvalues().minCoeff() >= -1e-10 * es.eigenvalues().cwiseAbs().maxCoeff());
    }
    // The operator's nodal diagonal means are the matrix's: trace of the
    // free node's Dim x Dim diagonal block over Dim.
    typename decltype(problem)::HessianOperator op;
    problem.hessian_operator(X, form, gf, op);
    double mean_error = 0.0;
    for (int k = 0; k < problem.num_free_nodes(); ++k)
      mean_error = std::max(mean_error, std::abs(op.diagonal_means()[k] - Eigen::MatrixXd(Hf).block(D * k, D * k, D, D).trace() / D));
    CHECK(mean_error <= 1e-12 * Eigen::MatrixXd(Hf).norm());
  }
  Eigen::VectorXd hv;
  problem.hessian_vector_product(X, HessianForm::exact, v, hv);
  CHECK((gradient_derivative(v) - hv).norm() <= 1e-6 * hv.norm());
}

namespace {

// Perturbs a degree-p box mesh until some elements are inverted, runs one
// solver and checks that it recovers the unperturbed (optimal, f = 0) mesh.
template <class F>
void check_untangles(int n, int p, double amplitude, SolverKind kind, unsigned seed) {
  CAPTURE(p);
  CAPTURE(to_string(kind));
  auto mesh = box_mesh<F>(n, p);
  const auto reference = mesh;
  perturb(mesh, amplitude / (n * p), seed);
  const MeshState before = mesh_state(mesh);
  CHECK(before.inverted > 0);
  OptimizeOptions o;
  o.solver = kind;
  o.threads = 1;
  // Converge the node positions, not only the minimum quality to two digits
  // (the defaults): Gauss-Seidel creeps towards the degenerate minimum.
  o.quality_tolerance = 1e-7;
  o.stagnation_window = 5;
  o.max_iterations = 400;
  const OptimizeResult r = optimize(mesh, o);
  CAPTURE(before.inverted);
  CAPTURE(r.result.iterations);
  CAPTURE(to_string(r.result.reason));
  CHECK(r.result.initial_inverted == before.inverted);
  CHECK(r.inverted() == 0);
  CHECK(r.converged());
  CHECK(r.min_quality() > 0.95);
  const MeshState after = mesh_state(mesh);
  CHECK(after.inverted == 0);
  CHECK(after.min_quality == doctest::Approx(r.min_quality()).epsilon(1e-12));
  // Near the optimum, the nodes are near their unperturbed positions.
  CHECK(max_node_distance<F>(mesh, reference) < 0.05 / (n * p));
}

}  // namespace

TEST_CASE_TEMPLATE("the assembled Newton counts its Hessian's entries and refuses a problem beyond its memory", F,
                   Simplex<2>, Cube<3>) {
  auto mesh = box_mesh<F>(2, 3);
  perturb(mesh, 0.3 / 6, 31);
  auto problem = make_problem(mesh, make_ideal_mesh(mesh, IdealKind::straight_sided));
  // The count made before the pattern exists is the assembled matrix's.
  const std::int64_t counted = problem.hessian_nonzeros();
  Eigen::VectorXd g;
  typename decltype(problem)::SparseMatrix H;
  problem.hessian(problem.coordinates(), HessianForm::projected, g, H);
  CHECK(counted == H.nonZeros());
  CHECK(problem.hessian_nonzeros() < std::int64_t(problem.num_dofs()) * problem.num_dofs());

  const auto start = problem.coordinates();
  NewtonSolver newton;
  const double needed = NewtonSolver::memory_needed_bytes(problem.hessian_nonzeros(), problem.hessian_pattern_extra_bytes());
  CHECK(needed > 36.0 * double(H.nonZeros()));
  newton.memory_limit_bytes = 0.5 * needed;
  SolverOptions options;
  options.max_iterations = 5;
  CHECK_THROWS_WITH_AS(newton.solve(problem, options), doctest::Contains("nonzeros over"), std::runtime_error);
  CHECK(problem.coordinates() == start);  // refused before any step
  newton.memory_limit_bytes = 2.0 * needed;
  CHECK_NOTHROW(newton.solve(problem, options));
  CHECK(problem.coordinates() != start);
}

TEST_CASE_TEMPLATE("every solver untangles a perturbed planar mesh and recovers its ideal", F, Simplex<2>, Cube<2>) {
  for (int p = 2; p <= 4; ++p)
    for (SolverKind kind : all_solvers) check_untangles<F>(3, p, 0.45, kind, 100 + p);
}

TEST_CASE_TEMPLATE("every solver untangles a perturbed volume mesh and recovers its ideal", F, Simplex<3>, Cube<3>) {
  for (SolverKind kind : all_solvers) {
    check_untangles<F>(2, 2, 0.5, kind, 202);
    check_untangles<F>(1, 3, 0.5, kind, 203);  // every hexahedron inverted, 5 of 6 tetrahedra
  }
}

TEST_CASE_TEMPLATE("the three solvers reach the same optimum", F, Simplex<2>, Cube<2>, Simplex<3>) {
  const int p = F::dim == 2 ? 3 : 2;
  auto start = box_mesh<F>(2, p);
  const auto reference = start;
  perturb(start, 0.45 / (2 * p), 7);
  std::vector<TestMesh<F>> results;
  std::vector<double> objectives;
  for (SolverKind kind : all_solvers) {
    auto mesh = start;
    const auto r = optimize(mesh, tight_options(kind));
    CAPTURE(to_string(kind));
    CAPTURE(to_string(r.result.reason));
    CHECK(r.converged());
    CHECK(r.inverted() == 0);
    objectives.push_back(r.result.objective);
    results.push_back(mesh);
  }
  // f* = 0 (the unperturbed mesh); the minimum is degenerate (f ~ |x - x*|^4),
  // so positions agree to about f^(1/4) (node spacing 1 / (2p)).
  const double spacing = 1.0 / (2 * p);
  for (double f : objectives) CHECK(f < 1e-12);
  for (std::size_t a = 0; a < results.size(); ++a) {
    CHECK(max_node_distance<F>(results[a], reference) < 5e-3 * spacing);
    for (std::size_t b = a + 1; b < results.size(); ++b)
      CHECK(max_node_distance<F>(results[a], results[b]) < 5e-3 * spacing);
  }
}

TEST_CASE("the three solvers reach the same optimum on a curved ring, where f* > 0") {
  // Curved boundary: the optimum is not the straight-sided mesh and is not
  // degenerate, so the solvers must agree closely in objective and positions.
  std::vector<TestMesh<Simplex<2>>> results;
  std::vector<double> objectives;
  for (SolverKind kind : all_solvers) {
    auto mesh = ring_mesh(6, 2, 1.0, 2.0, 4);
    auto o = tight_options(kind);
    o.max_iterations = 1000;
    o.stagnation_window = 10;
    const auto r = optimize(mesh, o);
    CAPTURE(to_string(kind));
    CAPTURE(to_string(r.result.reason));
    CHECK(r.converged());
    CHECK(r.inverted() == 0);
    objectives.push_back(r.result.objective);
    results.push_back(mesh);
  }
  CHECK(objectives[0] > 1e-4);
  for (std::size_t a = 0; a < results.size(); ++a)
    for (std::size_t b = a + 1; b < results.size(); ++b) {
      CHECK(objectives[a] == doctest::Approx(objectives[b]).epsilon(1e-9));
      CHECK(max_node_distance<Simplex<2>>(results[a], results[b]) < 1e-6);
    }
}

TEST_CASE_TEMPLATE("results do not depend on the number of threads", F, Simplex<2>, Cube<3>) {
  auto start = box_mesh<F>(F::dim == 2 ? 4 : 2, 2);
  perturb(start, 0.4 / (F::dim == 2 ? 8 : 4), 3);
  for (SolverKind kind : all_solvers) {
    CAPTURE(to_string(kind));
    auto one = start, two = start;
    auto o = tight_options(kind);
    o.max_iterations = 8;
    o.threads = 1;
    const auto r1 = optimize(one, o);
    o.threads = 2;
    const auto r2 = optimize(two, o);
    CHECK(r1.result.iterations == r2.result.iterations);
    CHECK(r1.result.objective == r2.result.objective);
    CHECK(max_node_distance<F>(one, two) == 0.0);
  }
}

TEST_CASE("elements valid at the start stay valid; the number of invalid elements never increases") {
  for (SolverKind kind : all_solvers) {
    for (int iterations : {1, 3, 100}) {
      CAPTURE(to_string(kind));
      CAPTURE(iterations);
      auto mesh = box_mesh<Simplex<2>>(3, 3);
      perturb(mesh, 0.45 / 9, 17);
      const MeshState before = mesh_state(mesh);
      REQUIRE(before.inverted > 0);
      REQUIRE(before.inverted < mesh.num_elements());
      OptimizeOptions o;
      o.solver = kind;
      o.threads = 1;
      o.max_iterations = iterations;
      int last = before.inverted;
      bool monotone = true;
      o.on_iteration = [&](const IterationInfo& it) {
        monotone = monotone && it.inverted <= last;
        last = it.inverted;
      };
      const auto r = optimize(mesh, o);
      CHECK(monotone);
      const MeshState after = mesh_state(mesh);
      CHECK(after.inverted == r.inverted());
      CHECK(after.inverted <= before.inverted);
      for (int e = 0; e < mesh.num_elements(); ++e)
        if (before.valid[e]) CHECK(after.valid[e]);
    }
  }
}

TEST_CASE("a curved ring whose elevated mesh is invalid after curving is repaired by every solver") {
  const auto curved = ring_mesh(6, 1, 1.0, 1.6, 3);
  const MeshState before = mesh_state(curved);
  CAPTURE(before.inverted);
  REQUIRE(before.inverted > 0);
  for (SolverKind kind : all_solvers) {
    CAPTURE(to_string(kind));
    auto mesh = curved;
    OptimizeOptions o;
    o.solver = kind;
    o.threads = 1;
    const auto r = optimize(mesh, o);
    CHECK(r.inverted() == 0);
    CHECK(r.min_quality() > 0.2);
    // Fixed (boundary) nodes did not move; they are on the circles.
    for (int i = 0; i < mesh.num_nodes(); ++i)
      if (mesh.node_class(i).kind != NodeKind::free) {
        CHECK((mesh.node(i) - curved.node(i)).norm() == 0.0);
        const double r0 = mesh.node(i).norm();
        CHECK(std::min(std::abs(r0 - 1.0), std::abs(r0 - 1.6)) < 1e-12);
      }
  }
}

TEST_CASE_TEMPLATE("Gauss-Seidel with vertex culling reaches the optimum, whatever the number of threads", F, Simplex<2>,
                   Simplex<3>) {
  // A local tangle in an otherwise optimal mesh: the node nearest the centre
  // moved by 1.5 node spacings, so culling has settled nodes to skip.
  const int n = F::dim == 2 ? 6 : 4, p = 2;
  const auto reference = box_mesh<F>(n, p);
  auto start = reference;
  int centre = 0;
  for (int i = 0; i < start.num_nodes(); ++i)
    if ((start.node(i).array() - 0.5).matrix().norm() < (start.node(centre).array() - 0.5).matrix().norm()) centre = i;
  start.node(centre)(0) += 1.5 / (n * p);
  const auto ideal = make_ideal_mesh(reference, IdealKind::straight_sided);  // f* = 0 at the reference
  GaussSeidel culled;
  culled.culling_tolerance = 0.05;
  culled.max_culled_passes = 10;
  SolverOptions o;
  o.max_iterations = 400;
  o.gradient_tolerance = 1e-10;
  o.objective_tolerance = 1e-14;
  o.quality_tolerance = 1e-12;
  std::vector<Eigen::MatrixXd> positions;
  for (int threads : {1, 2}) {
    CAPTURE(threads);
    auto problem = make_problem(start, ideal);
    REQUIRE(problem.status(problem.coordinates()).inverted > 0);
    problem.set_threads(threads);
    double smallest_fraction = 1.0;  // of the free nodes moved by one outer iteration
    o.on_iteration = [&](const IterationInfo& it) { smallest_fraction = std::min(smallest_fraction, it.step); };
    const SolverResult r = culled.solve(problem, o);
    CAPTURE(to_string(r.reason));
    CHECK(r.inverted == 0);
    CHECK(r.converged);
    CHECK(r.objective < 1e-12);      // f* = 0
    CHECK(smallest_fraction < 0.5);  // some sweeps skipped settled nodes
    positions.push_back(problem.coordinates());
  }
  CHECK((positions[0] - positions[1]).norm() == 0.0);
  // Settled nodes are revisited once nothing moves, so the sweeps reach the
  // optimum; the minimum is degenerate (f ~ |x - x*|^4), so positions agree to
  // about f^(1/4), as in "the three solvers reach the same optimum".
  const double spacing = 1.0 / (n * p);
  CHECK((positions[0] - reference.nodes()).colwise().norm().maxCoeff() < 1e-2 * spacing);
}

TEST_CASE("p-continuation untangles the linear sub-mesh first and ends valid on a curved ring") {
  // Figure C.2's setting: a degree-4 ring of 24 triangles whose boundary
  // edges were curved onto the circles, tangled near the inner circle.
  const auto curved = ring_mesh(6, 2, 1.0, 2.0, 4);
  REQUIRE(mesh_state(curved).inverted > 0);
  {
    const auto sub = make_linear_sub_problem(curved, make_ideal_mesh(curved, IdealKind::straight_sided));
    REQUIRE(sub.num_elements() == 16 * curved.num_elements());
    REQUIRE(sub.status(sub.coordinates()).inverted > 0);
  }
  for (SolverKind kind : all_solvers) {
    CAPTURE(to_string(kind));
    auto with = curved, without = curved;
    OptimizeOptions o;
    o.solver = kind;
    o.threads = 1;
    o.p_continuation = true;
    const auto r = optimize(with, o);
    REQUIRE(r.continuation.has_value());
    CHECK(r.continuation->initial_inverted > 0);
    CHECK(r.continuation->inverted == 0);
    CHECK(r.inverted() == 0);
    CHECK(r.min_quality() > 0.9);
    o.p_continuation = false;
    const auto s = optimize(without, o);
    CHECK(!s.continuation.has_value());
    CHECK(s.inverted() == 0);
    MESSAGE(to_string(kind), ": with p-continuation ", r.continuation->iterations, " linear + ", r.result.iterations,
            " high-order iterations (", r.time_s, " s); without ", s.result.iterations, " (", s.time_s, " s)");
  }
}

TEST_CASE("the linear stage stops once its sub-mesh has stayed valid for the requested iterations") {
  const auto curved = ring_mesh(6, 2, 1.0, 2.0, 4);
  for (int after : {0, 2}) {
    CAPTURE(after);
    auto mesh = curved;
    OptimizeOptions o;
    o.threads = 1;
    o.p_continuation = true;
    o.continuation_iterations_after_valid = after;
    const auto r = optimize(mesh, o);
    REQUIRE(r.continuation.has_value());
    CHECK(r.continuation->reason == StopReason::valid);
    CHECK(r.continuation->inverted == 0);
    CHECK(r.continuation->converged);
    CHECK(r.inverted() == 0);
  }
  // Run to convergence instead: another criterion stops it, later.
  auto a = curved, b = curved;
  OptimizeOptions o;
  o.threads = 1;
  o.p_continuation = true;
  o.continuation_iterations_after_valid = 0;
  const auto early = optimize(a, o);
  o.continuation_iterations_after_valid = -1;
  const auto full = optimize(b, o);
  CHECK(full.continuation->reason != StopReason::valid);
  CHECK(full.continuation->iterations > early.continuation->iterations);
}

TEST_CASE("p-continuation does nothing when the linear sub-mesh is valid") {
  auto mesh = box_mesh<Cube<2>>(2, 3);
  OptimizeOptions o;
  o.p_continuation = true;
  const auto r = optimize(mesh, o);
  CHECK(!r.continuation.has_value());
  CHECK(r.inverted() == 0);
  CHECK(r.min_quality() == doctest::Approx(1.0).epsilon(1e-9));
}

TEST_CASE("the whole-mesh scope regularizes every element while one is invalid, and none once all are valid") {
  auto mesh = box_mesh<Simplex<2>>(4, 2);
  const auto valid = mesh;
  perturb(mesh, 0.3, 7);
  auto problem = make_problem(mesh, make_ideal_mesh(mesh, IdealKind::straight_sided));
  const MeshState tangled = problem.status(problem.coordinates());
  REQUIRE(tangled.inverted > 0);
  REQUIRE(tangled.inverted < problem.num_elements());
  problem.set_regularization({thesis_regularization_alpha, RegularizationScope::invalid_elements});
  CHECK(problem.update_regularization(tangled) == tangled.inverted);
  for (int e = 0; e < problem.num_elements(); ++e) CHECK((problem.deltas()[e] > 0.0) == !tangled.valid[e]);
  problem.set_regularization({thesis_regularization_alpha, RegularizationScope::whole_mesh});
  CHECK(problem.update_regularization(tangled) == problem.num_elements());
  for (double d : problem.deltas()) CHECK(d > 0.0);
  const MeshState all_valid = problem.status(valid.nodes());
  REQUIRE(all_valid.all_valid());
  CHECK(problem.update_regularization(all_valid) == 0);
  for (double d : problem.deltas()) CHECK(d == 0.0);
}

TEST_CASE("the vertex problem is the degree-1 mesh of the element vertices") {
  auto mesh = box_mesh<Simplex<3>>(2, 3);
  std::vector<int> vertex_nodes;
  const auto ideal = make_ideal_mesh(mesh, IdealKind::straight_sided);
  const auto vertices = make_vertex_problem(mesh, ideal, vertex_nodes);
  CHECK(vertices.num_nodes() == 27);  // (2 + 1)^3 grid points
  CHECK(vertices.num_elements() == mesh.num_elements());
  CHECK(vertices.num_free_nodes() == 1);  // the centre of the box
  // Reference: the same linear mesh built directly, as its own problem.
  const auto linear = structured_mesh<Simplex<3>, WarpBlend>({2, 2, 2});
  auto reference = make_problem(linear, make_ideal_mesh(linear, IdealKind::straight_sided));
  CHECK(vertices.value(vertices.coordinates()) == doctest::Approx(reference.value(reference.coordinates())));
  for (std::size_t k = 0; k < vertex_nodes.size(); ++k)
    CHECK((vertices.coordinates().col(k) - mesh.node(vertex_nodes[k])).norm() == 0.0);
}

TEST_CASE_TEMPLATE("free high-order nodes are placed on their elements' straight-sided maps", F, Simplex<2>, Cube<2>, Simplex<3>) {
  const auto straight = box_mesh<F>(2, 3);
  auto mesh = straight;
  // Move every free node that is not a vertex; the vertices stay.
  std::vector<bool> vertex(mesh.num_nodes(), false);
  for (int e = 0; e < mesh.num_elements(); ++e)
    for (int k = 0; k < F::num_vertices; ++k) vertex[mesh.element(e)[k]] = true;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.1, 0.1);
  for (int i = 0; i < mesh.num_nodes(); ++i)
    if (!vertex[i] && mesh.node_class(i).kind == NodeKind::free)
      for (int a = 0; a < F::dim; ++a) mesh.nodes()(a, i) += u(rng);
  REQUIRE(max_node_distance(mesh, straight) > 0.01);
  place_free_nodes_straight(mesh);
  CHECK(max_node_distance(mesh, straight) < 1e-12);
}

// A 2D analogue of table 4.2: a held square "cavity" in the middle of a
// triangle mesh translated by several element sizes.
TEST_CASE("the vertex-mesh continuation untangles a mesh whose held cavity moved by several elements") {
  auto mesh = box_mesh<Simplex<2>>(12, 3);
  const Eigen::Vector2d shift(0.25, 0.0);  // three cells
  std::vector<int> cavity;
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    const auto x = mesh.node(i);
    if (x.minCoeff() > 5.0 / 12 - 1e-12 && x.maxCoeff() < 7.0 / 12 + 1e-12) {
      mesh.node_class(i).kind = NodeKind::fixed;
      mesh.node(i) += shift;
      cavity.push_back(i);
    }
  }
  REQUIRE(cavity.size() == 7 * 7);  // a 2 x 2 cell block at degree 3
  const auto moved = mesh;
  REQUIRE(mesh_state(mesh).inverted > 10);
  OptimizeOptions o;
  o.solver = SolverKind::matrix_free_newton;
  o.threads = 1;
  o.vertex_continuation = true;
  o.regularization_scope = RegularizationScope::whole_mesh;
  const auto r = optimize(mesh, o);
  REQUIRE(r.continuation.has_value());
  CHECK(r.continuation_policy == "vertex-mesh");
  CHECK(r.continuation->inverted == 0);
  CHECK(r.inverted() == 0);
  CHECK(mesh_state(mesh).inverted == 0);
  CHECK(r.min_quality() > 0.2);
  for (int i = 0; i < mesh.num_nodes(); ++i)
    if (mesh.node_class(i).kind != NodeKind::free) CHECK((mesh.node(i) - moved.node(i)).norm() == 0.0);
}
