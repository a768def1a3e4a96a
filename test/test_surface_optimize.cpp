// Tests of the surface optimizer of chapter 5 (include/hom/surface/
// surface_problem.hpp, optimize_surface.hpp):
//   - gradient and Hessian in the nodes' parameters against central finite
//     differences on curved surfaces (sphere, the thesis's Sigma_2 through a
//     non-trivial parameterization), triangles and quadrilaterals p = 1..3,
//     unregularized and regularized (delta > 0);
//   - the projected and Gauss-Newton Hessians are positive semi-definite;
//   - on the plane z = 0 with the identity parameterization the objective,
//     gradient, exact Hessian and validity are the planar problem's (eq 4.10);
//   - consistency (section 5.5.1.1): the planar and the surface optimizers
//     take a tangled curved-boundary mesh to the same mesh (E of eq 5.28);
//   - an invalid start on a sphere becomes valid, fixed nodes stay put and
//     the nodes stay on the surface;
//   - independence of the parameterization (proposition 5.2): Sigma_1 and
//     Sigma_2 through phi^1 and phi^2 optimize to the same physical mesh.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <Eigen/Dense>

#include "../bench/ring_mesh.hpp"
#include "hom/geometry/plane.hpp"
#include "hom/geometry/sphere.hpp"
#include "hom/geometry/thesis_parameterizations.hpp"
#include "hom/measure/shape_measure.hpp"
#include "hom/mesh/elevate.hpp"
#include "hom/mesh/structured.hpp"
#include "hom/nodes/gauss_lobatto.hpp"
#include "hom/nodes/warp_blend.hpp"
#include "hom/optimize/mesh_problem.hpp"
#include "hom/optimize/newton.hpp"
#include "hom/quadrature/quadrature_policy.hpp"
#include "hom/surface/optimize_boundary_face.hpp"
#include "hom/surface/optimize_surface.hpp"
#include "hom/surface/surface_mesh_quality.hpp"
#include "hom/surface/surface_problem.hpp"

using namespace hom;

namespace {

template <class F, class N>
struct Case {
  using Family = F;
  using Nodes = N;
};

#define HOM_SURFACE_CASES Case<Simplex<2>, WarpBlend>, Case<Cube<2>, GaussLobatto>

using UVs = Eigen::Matrix<double, 2, Eigen::Dynamic>;

template <class F, class N>
const Tabulation<F>& tab(int p) {
  return tabulation<F, N>(p, quadrature_for<F, DefaultExactness>(p));
}

/// Degree-p structured mesh of the box [lo, hi]^2 with `cells` cells per side.
template <class F, class N>
Mesh<F, N> box_mesh(int cells, int p, double lo, double hi) {
  return elevate(structured_mesh<F, N>({cells, cells}, Eigen::Vector2d::Constant(lo), Eigen::Vector2d::Constant(hi)), p);
}

/// The box mesh's elements' vertices in z = 0 (isosceles right triangles, squares).
template <class F, class N>
std::vector<SurfaceIdealVertices<F>> embedded_ideals(const Mesh<F, N>& m) {
  std::vector<SurfaceIdealVertices<F>> v(m.num_elements());
  for (int e = 0; e < m.num_elements(); ++e) v[e] = embed_ideal<F>(m.ideal_vertices(e));
  return v;
}

/// Interior nodes free, the others fixed (the planar classification).
template <class M>
std::vector<bool> interior_mask(const M& m) {
  return free_node_mask(m);
}

/// Moves the free columns of U by uniform noise of size amplitude.
void perturb(UVs& U, const std::vector<bool>& free, double amplitude, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> d(-amplitude, amplitude);
  for (Eigen::Index i = 0; i < U.cols(); ++i)
    if (free[i]) U.col(i) += Eigen::Vector2d(d(rng), d(rng));
}

/// box_mesh on [0, 2]^2 with its free nodes moved by uniform noise of size amplitude.
template <class F, class N>
Mesh<F, N> perturbed_box(int cells, int p, double amplitude, unsigned seed) {
  auto mesh = box_mesh<F, N>(cells, p, 0.0, 2.0);
  UVs U = mesh.nodes();
  perturb(U, free_node_mask(mesh), amplitude, seed);
  mesh.nodes() = U;
  return mesh;
}

/// Central-difference gradient and Hessian checks of a surface problem at its
/// current coordinates, for the current deltas.
template <class P>
void check_derivatives(const P& problem, double tol_g, double tol_h) {
  const UVs U = problem.coordinates();
  Eigen::VectorXd g;
  const double f = problem.value_gradient(U, g);
  REQUIRE(std::isfinite(f));
  CHECK(problem.value(U) == doctest::Approx(f).epsilon(1e-13));
  const int n = problem.num_dofs();
  REQUIRE(n > 0);
  const double h = 1e-6;
  Eigen::VectorXd fd(n);
  for (int k = 0; k < n; ++k) {
    Eigen::VectorXd v = Eigen::VectorXd::Zero(n);
    v[k] = 1.0;
    fd[k] = (problem.value(problem.displaced(U, v, h)) - problem.value(problem.displaced(U, v, -h))) / (2 * h);
  }
  CHECK((fd - g).norm() <= tol_g * std::max(1.0, g.norm()));

  Eigen::SparseMatrix<double> H;
  Eigen::VectorXd g2;
  const double f2 = problem.hessian(U, HessianForm::exact, g2, H);
  CHECK(f2 == doctest::Approx(f).epsilon(1e-13));
  CHECK((g2 - g).norm() <= 1e-12 * std::max(1.0, g.norm()));
  const Eigen::MatrixXd Hd(H);
  Eigen::MatrixXd Hfd(n, n);
  for (int k = 0; k < n; ++k) {
    Eigen::VectorXd v = Eigen::VectorXd::Zero(n);
    v[k] = 1.0;
    Eigen::VectorXd gp, gm;
    problem.value_gradient(problem.displaced(U, v, h), gp);
    problem.value_gradient(problem.displaced(U, v, -h), gm);
    Hfd.col(k) = (gp - gm) / (2 * h);
  }
  CHECK((Hd - Hfd).norm() <= tol_h * std::max(1.0, Hd.norm()));
  CHECK((Hd - Hd.transpose()).norm() <= 1e-10 * std::max(1.0, Hd.norm()));

  for (HessianForm form : {HessianForm::projected, HessianForm::gauss_newton}) {
    Eigen::SparseMatrix<double> Hp;
    Eigen::VectorXd gp;
    problem.hessian(U, form, gp, Hp);
    CHECK((gp - g).norm() <= 1e-12 * std::max(1.0, g.norm()));
    const Eigen::MatrixXd M(Hp);
    CHECK((M - M.transpose()).norm() <= 1e-10 * std::max(1.0, M.norm()));
    const Eigen::VectorXd lambda = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(0.5 * (M + M.transpose())).eigenvalues();
    CHECK(lambda.minCoeff() >= -1e-10 * std::max(1.0, lambda.cwiseAbs().maxCoeff()));
  }
}

/// E of eq 5.28: max over the free nodes of |x1 - x2| / L, L the shortest
/// straight-sided edge of mesh 1's elements.
template <ElementFamily F>
double relative_distance(const Eigen::Matrix3Xd& X1, const Eigen::Matrix3Xd& X2, const std::vector<bool>& free,
                         const Eigen::MatrixXi& elements) {
  double L = std::numeric_limits<double>::infinity();
  for (Eigen::Index e = 0; e < elements.cols(); ++e)
    for (const auto& edge : F::edges()) L = std::min(L, (X1.col(elements(edge[0], e)) - X1.col(elements(edge[1], e))).norm());
  double E = 0.0;
  for (Eigen::Index i = 0; i < X1.cols(); ++i)
    if (free[i]) E = std::max(E, (X1.col(i) - X2.col(i)).norm() / L);
  return E;
}

SolverOptions tight_options() {
  SolverOptions o;
  o.max_iterations = 200;
  o.gradient_tolerance = 1e-10;
  o.objective_tolerance = 1e-12;
  o.stagnation_window = 0;  // the quality criterion stops a degenerate (quartic) minimum too early
  return o;
}

}  // namespace

TEST_CASE_TEMPLATE("surface objective: gradient and Hessian in (u, v) match finite differences on a sphere", C,
                   HOM_SURFACE_CASES) {
  using F = typename C::Family;
  using N = typename C::Nodes;
  const Sphere sphere(Eigen::Vector3d(0.1, -0.2, 0.3), 1.3);
  for (int p = 1; p <= 3; ++p) {
    CAPTURE(p);
    const auto param = box_mesh<F, N>(3, p, -0.6, 0.6);
    UVs U = param.nodes();
    const auto free = interior_mask(param);
    perturb(U, free, 0.08 / p, 7 + p);
    // Regular ideal: the residuals eta - 1 are far from zero (a strict test).
    std::vector<SurfaceIdealVertices<F>> ideals(param.num_elements(), embed_ideal<F>(regular_ideal_vertices<F>()));
    auto problem = make_surface_problem(tab<F, N>(p), sphere, U, param.elements(), free, ideals);
    REQUIRE(problem.status(U).all_valid());
    SUBCASE("unregularized") { check_derivatives(problem, 1e-6, 1e-5); }
    SUBCASE("regularized") {
      problem.set_deltas(std::vector<double>(param.num_elements(), 0.05));
      check_derivatives(problem, 1e-6, 1e-5);
    }
  }
}

TEST_CASE_TEMPLATE("surface objective: derivatives on Sigma_2 through phi^2 (second derivatives of phi matter)", C,
                   HOM_SURFACE_CASES) {
  using F = typename C::Family;
  using N = typename C::Nodes;
  const ParametricSurface sigma2 = thesis_sigma2(2);
  for (int p = 1; p <= 3; ++p) {
    CAPTURE(p);
    const auto param = box_mesh<F, N>(3, p, -0.45, 0.45);
    UVs U = param.nodes();
    const auto free = interior_mask(param);
    perturb(U, free, 0.05 / p, 11 + p);
    auto problem = make_surface_problem(tab<F, N>(p), sigma2, U, param.elements(), free, embedded_ideals(param));
    check_derivatives(problem, 1e-6, 1e-5);
  }
}

TEST_CASE_TEMPLATE("plane z = 0 with the identity parameterization: exactly the planar problem", C, HOM_SURFACE_CASES) {
  using F = typename C::Family;
  using N = typename C::Nodes;
  const Plane plane(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX());
  for (int p = 1; p <= 3; ++p) {
    CAPTURE(p);
    const auto mesh = perturbed_box<F, N>(3, p, 0.25 / p, 3 + p);
    const auto free = free_node_mask(mesh);
    const UVs U = mesh.nodes();
    const IdealMesh<F> ideal = IdealMesh<F>::regular(mesh.num_elements());
    auto planar = make_problem(mesh, ideal);
    std::vector<SurfaceIdealVertices<F>> ideals(mesh.num_elements(), embed_ideal<F>(regular_ideal_vertices<F>()));
    auto surface = make_surface_problem(planar.tabulation(), plane, U, mesh.elements(), free, ideals);
    REQUIRE(surface.num_dofs() == planar.num_dofs());

    const MeshState s1 = planar.status(U), s2 = surface.status(U);
    CHECK(s1.valid == s2.valid);
    for (int e = 0; e < mesh.num_elements(); ++e) CHECK(s2.quality[e] == doctest::Approx(s1.quality[e]).epsilon(1e-12));
    // With every element regularized, and with the validity-driven deltas.
    for (int round = 0; round < 2; ++round) {
      if (round == 0) {
        planar.set_deltas(std::vector<double>(mesh.num_elements(), 0.1));
        surface.set_deltas(std::vector<double>(mesh.num_elements(), 0.1));
      } else {
        planar.update_regularization(s1);
        surface.update_regularization(s2);
      }
      Eigen::VectorXd g1, g2;
      const double f1 = planar.value_gradient(U, g1), f2 = surface.value_gradient(U, g2);
      CHECK(f2 == doctest::Approx(f1).epsilon(1e-12));
      CHECK((g1 - g2).norm() <= 1e-11 * std::max(1.0, g1.norm()));
      Eigen::SparseMatrix<double> H1, H2;
      planar.hessian(U, HessianForm::exact, g1, H1);
      surface.hessian(U, HessianForm::exact, g2, H2);
      // (Computed by different chain rules: J-bar's through the Gram matrix of B.)
      CHECK((Eigen::MatrixXd(H1) - Eigen::MatrixXd(H2)).norm() <= 1e-7 * std::max(1.0, Eigen::MatrixXd(H1).norm()));
      CHECK(surface.scaled_gradient_norm(g2) == doctest::Approx(planar.scaled_gradient_norm(g1)).epsilon(1e-10));
    }
  }
}

namespace {

/// A planar mesh as a surface mesh in z = 0, ideal snapshot included.
template <class F, class N>
Mesh<F, N, 3> lift(const Mesh<F, N>& m) {
  Eigen::Matrix3Xd X = Eigen::Matrix3Xd::Zero(3, m.num_nodes()), I = X;
  X.topRows<2>() = m.nodes();
  I.topRows<2>() = m.ideal_coordinates();
  Mesh<F, N, 3> s(m.degree(), X, m.elements());
  s.node_classes() = m.node_classes();
  s.set_ideal_coordinates(I);
  return s;
}

/// Planar and surface optimization of the same tangled planar mesh: E (eq 5.28).
template <class F, class N>
double consistency_E(const Mesh<F, N>& start, int& inverted_before, int& inverted_after) {
  Mesh<F, N> planar_mesh = start;
  auto planar = make_problem(planar_mesh, planar_mesh.straight_sided_ideal());
  inverted_before = planar.status(planar.coordinates()).inverted;
  const SolverResult r1 = NewtonSolver{}.solve(planar, tight_options());

  Mesh<F, N, 3> surface_mesh = lift(start);
  UVs uv = start.nodes();
  OptimizeOptions o;
  o.gradient_tolerance = 1e-10;
  o.objective_tolerance = 1e-12;
  o.stagnation_window = 0;
  const Plane plane(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX());
  const SurfaceOptimizeResult r2 = optimize_surface(surface_mesh, plane, uv, o);
  inverted_after = std::max(r1.inverted, r2.inverted());
  CHECK(r1.converged);
  CHECK(r2.converged());
  Eigen::Matrix3Xd X1 = Eigen::Matrix3Xd::Zero(3, start.num_nodes());
  X1.topRows<2>() = planar.coordinates();
  // The same free nodes in both.
  CHECK(surface_free_node_mask(surface_mesh) == free_node_mask(start));
  return relative_distance<F>(X1, surface_mesh.nodes(), free_node_mask(start), start.elements());
}

}  // namespace

TEST_CASE("consistency (section 5.5.1.1): planar and surface optimizers agree on a tangled degree-3 ring") {
  // The ring of appendix C/D (bench/ring_mesh.hpp): the curved inner circle
  // tangles the elements along it.
  const auto start = bench::curved_ring(bench::ring_triangles(bench::thesis_ring_layout()), 3, 1.0, 2.0);
  int before = 0, after = 0;
  const double E = consistency_E(start, before, after);
  CHECK(before > 0);
  CHECK(after == 0);
  CHECK(E <= 1e-3);
  MESSAGE("triangle ring p = 3: " << before << " tangled at the start, E = " << E);
}

TEST_CASE("consistency (section 5.5.1.1): quadrilateral ring, p = 3, perturbed interior") {
  auto start = bench::curved_ring(bench::ring_quads(8, 2, 1.0, 2.0), 3, 1.0, 2.0);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> d(-0.08, 0.08);
  for (int i = 0; i < start.num_nodes(); ++i)
    if (start.node_class(i).kind == NodeKind::free) start.node(i) += Eigen::Vector2d(d(rng), d(rng));
  int before = 0, after = 0;
  const double E = consistency_E(start, before, after);
  CHECK(after == 0);
  CHECK(E <= 1e-3);
  MESSAGE("quadrilateral ring p = 3: " << before << " tangled at the start, E = " << E);
}

TEST_CASE_TEMPLATE("an invalid start on a sphere becomes valid; fixed nodes stay, nodes stay on the sphere", C,
                   HOM_SURFACE_CASES) {
  using F = typename C::Family;
  using N = typename C::Nodes;
  const Sphere sphere(Eigen::Vector3d::Zero(), 2.0);
  const int p = 3;
  const auto param = box_mesh<F, N>(3, p, -0.6, 0.6);
  UVs uv = param.nodes();
  Mesh<F, N, 3> mesh(p, surface_points(sphere, uv), param.elements());
  mesh.reset_ideal();  // straight-sided ideal: the initial vertices on the sphere
  // Fold one element: drag an interior vertex across its neighbours.
  const auto free = surface_free_node_mask(mesh);
  CHECK(free == free_node_mask(param));  // the patch's boundary is found topologically
  int moved = -1;
  for (int v = 0; v < mesh.num_nodes() && moved < 0; ++v)
    if (free[v] && mesh.vertex_mask()[v]) moved = v;
  REQUIRE(moved >= 0);
  uv.col(moved) += Eigen::Vector2d(0.55, 0.5);
  mesh.nodes() = surface_points(sphere, uv);
  const auto rule = quadrature_for<F, DefaultExactness>(p);
  const MeshQuality before = surface_mesh_quality(mesh, sphere, uv, ShapeMeasure{}, IdealKind::straight_sided, rule);
  int inverted = 0;
  for (const auto& q : before.elements) inverted += !q.valid;
  REQUIRE(inverted > 0);
  const UVs uv0 = uv;
  const SurfaceOptimizeResult r = optimize_surface(mesh, sphere, uv);
  CHECK(r.result.initial_inverted == inverted);
  CHECK(r.inverted() == 0);
  CHECK(r.min_quality() > 0.0);
  MESSAGE(F::name << ": " << r.result.initial_inverted << " inverted -> " << r.inverted() << ", min q "
                  << r.result.initial_min_quality << " -> " << r.min_quality() << " (" << to_string(r.result.reason)
                  << ", " << r.result.iterations << " iterations)");
  const MeshQuality after = surface_mesh_quality(mesh, sphere, uv, ShapeMeasure{}, IdealKind::straight_sided, rule);
  for (const auto& q : after.elements) CHECK(q.valid);
  CHECK(after.quality_statistics().min == doctest::Approx(r.min_quality()).epsilon(1e-10));
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    CHECK((mesh.node(i) - sphere.evaluate(uv.col(i))).norm() <= 1e-14);
    if (!free[i]) CHECK((uv.col(i) - uv0.col(i)).norm() == 0.0);
  }
}

TEST_CASE("a step out of a bounded parameter range is rejected (f = +inf)") {
  const ParametricSurface s = thesis_sigma1(0);  // the identity on [-1, 1]^2
  const auto param = box_mesh<Simplex<2>, WarpBlend>(2, 2, -1.0, 1.0);
  auto problem =
      make_surface_problem(tab<Simplex<2>, WarpBlend>(2), s, param.nodes(), param.elements(), free_node_mask(param),
                           embedded_ideals(param));
  const UVs U = problem.coordinates();
  CHECK(std::isfinite(problem.value(U)));
  Eigen::VectorXd v = Eigen::VectorXd::Zero(problem.num_dofs());
  v[0] = 5.0;  // far beyond u = 1
  CHECK(problem.value(problem.displaced(U, v, 1.0)) == std::numeric_limits<double>::infinity());
  CHECK(std::isfinite(problem.value(problem.displaced(U, v, 1e-3))));
}

TEST_CASE_TEMPLATE("independence of the parameterization (proposition 5.2): phi^1 and phi^2 give the same mesh", C,
                   HOM_SURFACE_CASES) {
  using F = typename C::Family;
  using N = typename C::Nodes;
  const int p = std::is_same_v<F, Simplex<2>> ? 3 : 2;
  const auto param = box_mesh<F, N>(4, p, -1.0, 1.0);
  const auto ideals = embedded_ideals(param);
  const auto free = free_node_mask(param);
  // Sigma_1 (the plane) and Sigma_2 (the wave of table 5.2, section 5.5.1.2.2).
  for (bool wave : {false, true}) {
    CAPTURE(wave);
    Eigen::Matrix3Xd X[2];
    for (int k = 1; k <= 2; ++k) {
      const ParametricSurface s = wave ? thesis_sigma2(k) : thesis_sigma1(k);
      auto problem = make_surface_problem(tab<F, N>(p), s, param.nodes(), param.elements(), free, ideals);
      const SolverResult r = NewtonSolver{}.solve(problem, tight_options());
      CHECK(r.converged);
      CHECK(r.inverted == 0);
      if (!wave) CHECK(r.min_quality > 0.999);  // the plane admits the ideal mesh itself
      X[k - 1] = problem.physical_coordinates();
    }
    const double E = relative_distance<F>(X[0], X[1], free, param.elements());
    MESSAGE((wave ? "Sigma_2" : "Sigma_1") << ", " << F::name << " p = " << p << ": E = " << E);
    CHECK(E <= 1e-3);
  }
}

TEST_CASE("optimize_boundary_face: a volume mesh's face folded in its plane is repaired on it (and certified), nothing else moves") {
  // The unit box of Kuhn tetrahedra at p = 3; its face z = 0 is entity
  // {2, 5} (structured.hpp). The nodes inside that face are moved in the
  // plane until some of its triangles fold; the face's optimum is the
  // unmoved mesh (f = 0), whichever way the plane's normal points (the
  // facets turn outward, -z: with +z they are mirrored for the optimizer).
  const int p = 3, n = 2;
  const auto start = elevate(structured_mesh<Simplex<3>, WarpBlend>({n, n, n}), p);
  const double spacing = 1.0 / (n * p);
  for (const Eigen::Vector3d& normal : {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0, 0, -1)}) {
    auto mesh = start;
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-0.6 * spacing, 0.6 * spacing);
    std::vector<int> moved;
    for (int i = 0; i < mesh.num_nodes(); ++i) {
      const auto& c = mesh.node_class(i);
      if (c.entity && c.entity->dim == 2 && c.entity->tag == 5) {
        mesh.node(i) += Eigen::Vector3d(u(rng), u(rng), 0.0);
        moved.push_back(i);
      }
    }
    REQUIRE(!moved.empty());
    OptimizeOptions o;
    o.max_iterations = 200;
    o.gradient_tolerance = 1e-10;
    o.objective_tolerance = 1e-14;
    o.quality_tolerance = 1e-12;
    o.threads = 1;
    o.certify = normal.z() < 0;  // once with the face certified after the optimization
    const auto r = optimize_boundary_face(mesh, 5, Plane(Eigen::Vector3d::Zero(), normal), o);
    REQUIRE(r);
    CHECK(r->optimization.result.initial_inverted > 0);
    CHECK(r->optimization.inverted() == 0);
    REQUIRE(bool(r->certification) == o.certify);
    if (o.certify) CHECK(r->certification->certified());
    double back = 0.0;
    for (int i : moved) {
      CHECK(std::abs(mesh.node(i).z()) < 1e-14);
      back = std::max(back, (mesh.node(i) - start.node(i)).norm());
    }
    CHECK(back < 1e-2 * spacing);  // the degenerate minimum: f ~ |x - x*|^4
    for (int i = 0; i < mesh.num_nodes(); ++i)
      if (std::find(moved.begin(), moved.end(), i) == moved.end()) CHECK(mesh.node(i) == start.node(i));
  }
  // A face without free nodes, or without facets, is left alone.
  auto mesh = start;
  CHECK_FALSE(optimize_boundary_face(mesh, 99, Plane(Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 1)), OptimizeOptions{}));
}

TEST_CASE("optimize_boundary_face: with element ideals, each facet is measured against its element's ideal's face") {
  // Linear Kuhn tetrahedra of the unit box, 3 cells a side: the face z = 0
  // (entity {2, 5}) has 4 inside nodes. The element ideals are the elements
  // of a second, conformal mesh whose inside face nodes sit at other points
  // q of the plane: the face's optimum is then every node at its q (f = 0),
  // whichever way the plane's normal points (with +z the facets, and their
  // ideals, are mirrored for the optimizer). Without the element ideals the
  // face is measured against its own straight-sided mesh and goes back there.
  const int n = 3;
  const double spacing = 1.0 / n;
  const auto start = structured_mesh<Simplex<3>, WarpBlend>({n, n, n});
  auto target = start;
  std::vector<int> inside;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.25 * spacing, 0.25 * spacing);
  for (int i = 0; i < start.num_nodes(); ++i) {
    const auto& c = start.node_class(i);
    if (c.entity && c.entity->dim == 2 && c.entity->tag == 5) {
      target.node(i) += Eigen::Vector3d(u(rng), u(rng), 0.0);
      inside.push_back(i);
    }
  }
  REQUIRE(inside.size() == 4);
  std::vector<IdealVertices<Simplex<3>>> v(start.num_elements());
  for (int e = 0; e < start.num_elements(); ++e)
    for (int k = 0; k < 4; ++k) v[e].col(k) = target.node(target.vertex(e, k));
  const IdealMesh<Simplex<3>> ideals(std::move(v));
  OptimizeOptions o;
  o.max_iterations = 200;
  o.gradient_tolerance = 1e-12;
  o.objective_tolerance = 1e-16;
  o.quality_tolerance = 1e-12;
  o.threads = 1;
  for (const Eigen::Vector3d& normal : {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0, 0, -1)}) {
    CAPTURE(normal.z());
    const Plane plane(Eigen::Vector3d::Zero(), normal);
    auto mesh = start;
    // Fold the face: one inside node over its neighbour, towards the middle.
    const Eigen::Vector3d over(start.node(inside[0]).x() < 0.5 ? 1.2 * spacing : -1.2 * spacing, 0.0, 0.0);
    mesh.node(inside[0]) += over;
    const auto r = optimize_boundary_face(mesh, 5, plane, o, ShapeMeasure{}, &ideals);
    REQUIRE(r);
    CHECK(r->optimization.result.initial_inverted > 0);
    CHECK(r->optimization.inverted() == 0);
    for (int i : inside) {
      CHECK(std::abs(mesh.node(i).z()) < 1e-14);
      CHECK((mesh.node(i) - target.node(i)).norm() < 1e-2 * spacing);
    }
    auto own = start;
    own.node(inside[0]) += over;
    REQUIRE(optimize_boundary_face(own, 5, plane, o));
    for (int i : inside) CHECK((own.node(i) - start.node(i)).norm() < 1e-2 * spacing);
  }
  // One ideal per element, or a clear error.
  auto mesh = start;
  const IdealMesh<Simplex<3>> short_ideals = IdealMesh<Simplex<3>>::regular(3);
  CHECK_THROWS_AS(optimize_boundary_face(mesh, 5, Plane(Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 1)), o,
                                         ShapeMeasure{}, &short_ideals),
                  std::invalid_argument);
}

TEST_CASE_TEMPLATE("p-continuation on a surface: the linear sub-problem on z = 0 is the planar one", C, HOM_SURFACE_CASES) {
  using F = typename C::Family;
  using N = typename C::Nodes;
  const Plane plane(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX());
  for (int p = 2; p <= 4; ++p) {
    CAPTURE(p);
    // Up to 0.9 of the node spacing: some sub-elements tangle.
    const auto mesh = perturbed_box<F, N>(2, p, 0.9 / p, 11 + p);
    const auto free = free_node_mask(mesh);
    const UVs U = mesh.nodes();
    const IdealMesh<F> ideal = IdealMesh<F>::regular(mesh.num_elements());
    auto planar = make_linear_sub_problem(mesh, ideal);
    const std::vector<SurfaceIdealVertices<F>> ideals(mesh.num_elements(), embed_ideal<F>(regular_ideal_vertices<F>()));
    auto surface = make_linear_sub_surface_problem<F, N>(p, plane, U, mesh.elements(), free, ideals);
    REQUIRE(surface.num_elements() == planar.num_elements());
    CHECK(surface.num_elements() == mesh.num_elements() * p * p);
    CHECK(surface.nodes_per_element() == F::num_vertices);
    CHECK(surface.num_dofs() == planar.num_dofs());
    CHECK(surface.elements() == planar.elements());
    const MeshState s1 = planar.status(U), s2 = surface.status(U);
    CHECK(s1.valid == s2.valid);
    CHECK(s1.inverted > 0);  // the perturbation tangles some sub-elements
    planar.update_regularization(s1);
    surface.update_regularization(s2);
    Eigen::VectorXd g1, g2;
    const double f1 = planar.value_gradient(U, g1), f2 = surface.value_gradient(U, g2);
    CHECK(f2 == doctest::Approx(f1).epsilon(1e-12));
    CHECK((g1 - g2).norm() <= 1e-11 * std::max(1.0, g1.norm()));
  }
}

TEST_CASE_TEMPLATE("p-continuation on a surface: a scrambled patch on a sphere reaches the unperturbed start's optimum", C,
                   HOM_SURFACE_CASES) {
  using F = typename C::Family;
  using N = typename C::Nodes;
  const Sphere sphere(Eigen::Vector3d::Zero(), 2.0);
  const int p = 4;
  const auto param = box_mesh<F, N>(3, p, -0.6, 0.6);
  const std::vector<bool> free = free_node_mask(param);
  // Ideals: the straight-sided elements through the vertices on the sphere.
  Mesh<F, N, 3> straight(p, surface_points(sphere, param.nodes()), param.elements());
  straight.reset_ideal();
  const auto ideals = surface_ideals(straight, IdealKind::straight_sided);
  // Every interior node moved by up to 0.45 of the node spacing: most elements tangled.
  UVs scrambled = param.nodes();
  perturb(scrambled, free, 0.45 * 1.2 / (3 * p), 21);
  const auto& t = tab<F, N>(p);
  OptimizeOptions o;
  o.gradient_tolerance = 1e-10;
  o.objective_tolerance = 1e-12;
  o.stagnation_window = 0;

  auto optimized = [&](const UVs& start, bool pcont, SurfaceOptimizeResult& r) {
    Mesh<F, N, 3> mesh(p, surface_points(sphere, start), param.elements());
    UVs uv = start;
    OptimizeOptions oo = o;
    oo.p_continuation = pcont;
    r = optimize_surface(mesh, sphere, uv, ideals, oo);
    return Eigen::Matrix3Xd(mesh.nodes());
  };
  {
    auto before = make_surface_problem(t, sphere, scrambled, param.elements(), free, ideals);
    CHECK(2 * before.status(scrambled).inverted > param.num_elements());
  }
  SurfaceOptimizeResult from_straight, from_scrambled;
  const Eigen::Matrix3Xd x0 = optimized(param.nodes(), true, from_straight);
  const Eigen::Matrix3Xd x1 = optimized(scrambled, true, from_scrambled);
  CHECK_FALSE(from_straight.continuation.has_value());  // a valid sub-mesh: nothing to do
  REQUIRE(from_scrambled.continuation.has_value());
  CHECK(from_scrambled.continuation->inverted == 0);
  CHECK(from_scrambled.inverted() == 0);
  CHECK(from_scrambled.converged());
  const double E = relative_distance<F>(x0, x1, free, param.elements());
  CHECK(E <= 1e-6);
  MESSAGE(F::name << " p = " << p << ": scrambled start, linear stage " << from_scrambled.continuation->iterations
                  << " iterations, then " << from_scrambled.result.iterations << "; E = " << E);
}
