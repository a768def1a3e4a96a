// Geometry concept models (plane, line, circle, sphere, cylinder, torus), the
// type-erased model and boundary curving: derivatives against finite
// differences, projection against brute-force closest points, round trips.

#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "hom/geometry/circle.hpp"
#include "hom/geometry/curve_boundary.hpp"
#include "hom/geometry/cylinder.hpp"
#include "hom/geometry/geometry_model.hpp"
#include "hom/geometry/line.hpp"
#include "hom/geometry/plane.hpp"
#include "hom/geometry/sphere.hpp"
#include "hom/geometry/torus.hpp"
#include "hom/mesh/elevate.hpp"
#include "hom/mesh/structured.hpp"

using namespace hom;

namespace {

constexpr double pi = std::numbers::pi;

std::mt19937& rng() {
  static std::mt19937 g(12345);
  return g;
}
double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng()); }
Eigen::Vector3d random_vector(double s = 1.0) { return {uniform(-s, s), uniform(-s, s), uniform(-s, s)}; }
Eigen::Vector3d random_axis() {
  Eigen::Vector3d a;
  do a = random_vector(); while (a.norm() < 0.2);
  return a;
}

// Random instances of each model, in general position.
struct PlaneMaker {
  static Plane make() { return Plane(random_vector(2), random_axis(), random_vector()); }
  static Eigen::Vector2d params() { return {uniform(-3, 3), uniform(-3, 3)}; }
  static Eigen::Vector3d center(const Plane& g) { return g.origin(); }
  static constexpr double scale = 3.0;
};
struct SphereMaker {
  static Sphere make() { return Sphere(random_vector(2), uniform(0.3, 2.0), random_axis(), random_vector()); }
  // Away from the poles, where the parameterization is singular.
  static Eigen::Vector2d params() { return {uniform(-pi, pi), uniform(-1.4, 1.4)}; }
  static Eigen::Vector3d center(const Sphere& g) { return g.center(); }
  static constexpr double scale = 2.0;
};
struct CylinderMaker {
  static Cylinder make() { return Cylinder(random_vector(2), random_axis(), uniform(0.3, 2.0), random_vector()); }
  static Eigen::Vector2d params() { return {uniform(-pi, pi), uniform(-2, 2)}; }
  static Eigen::Vector3d center(const Cylinder& g) { return g.axis_point(); }
  static constexpr double scale = 2.0;
};
struct TorusMaker {
  static Torus make() {
    const double r = uniform(0.2, 0.8);
    return Torus(random_vector(2), random_axis(), r + uniform(0.3, 1.5), r, random_vector());
  }
  static Eigen::Vector2d params() { return {uniform(-pi, pi), uniform(-pi, pi)}; }
  static Eigen::Vector3d center(const Torus& g) { return g.center(); }
  static constexpr double scale = 2.5;
};

template <int D>
struct LineMaker {
  using G = Line<D>;
  using P = typename G::Point;
  static G make() {
    P a = P::Random() * 2, b;
    do b = P::Random() * 2; while ((b - a).norm() < 0.2);
    return G(a, b);
  }
  static double param() { return uniform(-3, 3); }
  static P center(const G& g) { return g.origin(); }
};
template <int D>
struct CircleMaker {
  using G = Circle<D>;
  using P = typename G::Point;
  static G make() {
    if constexpr (D == 2)
      return G(P::Random() * 2, uniform(0.3, 2.0));
    else
      return G(P::Random() * 2, uniform(0.3, 2.0), random_axis(), random_vector());
  }
  static double param() { return uniform(-pi, pi); }
  static P center(const G& g) { return g.center(); }
};

// Closest sample of the surface to y over a fine parameter grid around the
// answer: for unbounded parameters a window of +-`window` about it.
template <class G>
double brute_force_distance(const G& g, const Eigen::Vector3d& y, const Eigen::Vector2d& around, double window) {
  double best = std::numeric_limits<double>::infinity();
  constexpr int n = 400;
  std::array<double, 2> lo{}, hi{};
  for (int k = 0; k < 2; ++k) {
    const auto r = g.range(k);
    lo[k] = r.bounded() ? r.lo : around[k] - window;
    hi[k] = r.bounded() ? r.hi : around[k] + window;
  }
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) {
      const Eigen::Vector2d uv(lo[0] + (hi[0] - lo[0]) * i / n, lo[1] + (hi[1] - lo[1]) * j / n);
      best = std::min(best, (g.evaluate(uv) - y).norm());
    }
  return best;
}

}  // namespace

TEST_CASE("parameter range: normalize and unwrap") {
  const ParameterRange r{-pi, pi, true};
  for (int t = 0; t < 100; ++t) {
    const double u = uniform(-20, 20);
    const double n = r.normalize(u);
    CHECK(n >= -pi);
    CHECK(n < pi);
    CHECK(std::abs(std::remainder(n - u, 2 * pi)) < 1e-12);
    const double near = uniform(-10, 10);
    const double w = r.unwrap(u, near);
    CHECK(std::abs(w - near) <= pi + 1e-12);
    CHECK(std::abs(std::remainder(w - u, 2 * pi)) < 1e-12);
  }
  const ParameterRange b{0.0, 1.0, false};
  CHECK(b.normalize(1.5) == 1.0);
  CHECK(b.normalize(-0.5) == 0.0);
  CHECK(b.unwrap(7.0, 0.0) == 7.0);
  CHECK_FALSE(unbounded_range().bounded());
}

TEST_CASE_TEMPLATE("surface derivatives match finite differences", M, PlaneMaker, SphereMaker, CylinderMaker,
                   TorusMaker) {
  const double h = 1e-5;
  for (int t = 0; t < 20; ++t) {
    const auto g = M::make();
    const Eigen::Vector2d uv = M::params();
    const Eigen::Matrix<double, 3, 2> d = g.derivatives(uv);
    const auto s = g.second_derivatives(uv);
    for (int k = 0; k < 2; ++k) {
      const Eigen::Vector2d e = Eigen::Vector2d::Unit(k) * h;
      const Eigen::Vector3d fd = (g.evaluate(uv + e) - g.evaluate(uv - e)) / (2 * h);
      CHECK((fd - d.col(k)).norm() <= 1e-8 * (1 + d.col(k).norm()));
      const Eigen::Matrix<double, 3, 2> dd = (g.derivatives(uv + e) - g.derivatives(uv - e)) / (2 * h);
      const Eigen::Vector3d exact_k0 = k == 0 ? s.uu : s.uv;  // d/dk of S_u
      const Eigen::Vector3d exact_k1 = k == 0 ? s.uv : s.vv;  // d/dk of S_v
      CHECK((dd.col(0) - exact_k0).norm() <= 1e-7 * (1 + exact_k0.norm()));
      CHECK((dd.col(1) - exact_k1).norm() <= 1e-7 * (1 + exact_k1.norm()));
    }
  }
}

TEST_CASE_TEMPLATE("surface projection: round trip, idempotence, closest point", M, PlaneMaker, SphereMaker,
                   CylinderMaker, TorusMaker) {
  for (int t = 0; t < 20; ++t) {
    const auto g = M::make();
    // Points on the surface come back to themselves.
    const Eigen::Vector2d uv = M::params();
    const Eigen::Vector3d x = g.evaluate(uv);
    const Eigen::Vector2d back = g.project(x);
    CHECK((g.evaluate(back) - x).norm() <= 1e-12 * (1 + x.norm()));
    for (int k = 0; k < 2; ++k) {
      CHECK(g.range(k).contains(back[k]));
      const double expected = g.range(k).periodic ? g.range(k).unwrap(uv[k], back[k]) : uv[k];
      CHECK(back[k] == doctest::Approx(expected).epsilon(1e-10));
    }

    // Points off the surface: the projection is a fixed point and closest.
    const Eigen::Vector3d y = M::center(g) + random_vector(M::scale);
    const Eigen::Vector2d a = g.project(y);
    const Eigen::Vector3d px = g.evaluate(a);
    const Eigen::Vector2d a2 = g.project(px);
    CHECK((g.evaluate(a2) - px).norm() <= 1e-12 * (1 + px.norm()));
    const double dist = (px - y).norm();
    const double brute = brute_force_distance(g, y, a, 2 * M::scale);
    CHECK(dist <= brute + 1e-12);
    // The grid is fine enough to come within a few percent of the true
    // distance, so the projection is not just a local minimum.
    CHECK(brute - dist <= 0.05 * M::scale);
    // First-order optimality: the residual is normal to the surface.
    const Eigen::Matrix<double, 3, 2> d = g.derivatives(a);
    CHECK(std::abs((px - y).dot(d.col(0))) <= 1e-10 * (1 + d.col(0).norm()));
    CHECK(std::abs((px - y).dot(d.col(1))) <= 1e-10 * (1 + d.col(1).norm()));
  }
}

TEST_CASE_TEMPLATE("curve derivatives, projection and round trip", M, LineMaker<2>, LineMaker<3>, CircleMaker<2>,
                   CircleMaker<3>) {
  using P = typename M::P;
  const double h = 1e-5;
  for (int t = 0; t < 20; ++t) {
    const auto g = M::make();
    const double u = M::param();
    const P fd = (g.evaluate(u + h) - g.evaluate(u - h)) / (2 * h);
    CHECK((fd - g.derivative(u)).norm() <= 1e-8 * (1 + fd.norm()));
    const P fd2 = (g.derivative(u + h) - g.derivative(u - h)) / (2 * h);
    CHECK((fd2 - g.second_derivative(u)).norm() <= 1e-7 * (1 + fd2.norm()));

    const P x = g.evaluate(u);
    const double back = g.project(x);
    CHECK((g.evaluate(back) - x).norm() <= 1e-12 * (1 + x.norm()));
    CHECK(g.range().contains(back));

    P y = M::center(g);
    for (int k = 0; k < P::RowsAtCompileTime; ++k) y[k] += uniform(-2, 2);
    const double a = g.project(y);
    const P px = g.evaluate(a);
    CHECK((g.evaluate(g.project(px)) - px).norm() <= 1e-12 * (1 + px.norm()));
    const double dist = (px - y).norm();
    const auto r = g.range();
    const double lo = r.bounded() ? r.lo : a - 6, hi = r.bounded() ? r.hi : a + 6;
    double brute = std::numeric_limits<double>::infinity();
    for (int i = 0; i <= 20000; ++i) brute = std::min(brute, (g.evaluate(lo + (hi - lo) * i / 20000.0) - y).norm());
    CHECK(dist <= brute + 1e-12);
    CHECK(brute - dist <= 1e-3);
    CHECK(std::abs((px - y).dot(g.derivative(a))) <= 1e-10 * (1 + g.derivative(a).norm()));
  }
}

TEST_CASE("analytic specifics") {
  const Sphere s({1, 2, 3}, 2.0);
  // Outward normal, radial projection, pole handling.
  const Eigen::Vector2d uv(0.3, 0.4);
  const Eigen::Matrix<double, 3, 2> d = s.derivatives(uv);
  CHECK(d.col(0).cross(d.col(1)).dot(s.evaluate(uv) - s.center()) > 0);
  CHECK(s.project({1, 2, 10})[1] == doctest::Approx(pi / 2));
  CHECK((s.evaluate(s.project({1, 2, 10})) - Eigen::Vector3d(1, 2, 5)).norm() < 1e-12);
  const Eigen::Vector3d y(4, -1, 7);
  CHECK((s.evaluate(s.project(y)) - (s.center() + 2.0 * (y - s.center()).normalized())).norm() < 1e-12);

  const Cylinder c({0, 0, 0}, {0, 0, 1}, 1.5);
  const Eigen::Matrix<double, 3, 2> dc = c.derivatives({1.0, 0.5});
  CHECK(dc.col(0).cross(dc.col(1)).dot(c.evaluate({1.0, 0.5}) - Eigen::Vector3d(0, 0, 0.5)) > 0);
  CHECK(c.project({3, 0, 2})[1] == doctest::Approx(2.0));

  const Plane p({0, 0, 1}, {0, 0, 2});
  const Eigen::Matrix<double, 3, 2> dp = p.derivatives({0, 0});
  CHECK((dp.col(0).cross(dp.col(1)) - Eigen::Vector3d::UnitZ()).norm() < 1e-14);
  CHECK((p.evaluate(p.project({3, 4, 5})) - Eigen::Vector3d(3, 4, 1)).norm() < 1e-14);

  CHECK_THROWS_AS(Sphere({0, 0, 0}, -1.0), std::invalid_argument);
  CHECK_THROWS_AS(Torus({0, 0, 0}, {0, 0, 1}, 1.0, 2.0), std::invalid_argument);
  CHECK_THROWS_AS(Line<2>(Eigen::Vector2d(1, 1), Eigen::Vector2d(1, 1)), std::invalid_argument);
}

TEST_CASE("type-erased geometry agrees with the model") {
  const Torus t({0.1, 0.2, 0.3}, {1, 1, 0}, 2.0, 0.5);
  const AnySurface any = t;
  const Circle<2> c({0.5, -0.5}, 1.2);
  const AnyCurve<2> anyc = c;
  for (int k = 0; k < 10; ++k) {
    const Eigen::Vector2d uv = TorusMaker::params();
    CHECK((any.evaluate(uv) - t.evaluate(uv)).norm() == 0.0);
    CHECK((any.derivatives(uv) - t.derivatives(uv)).norm() == 0.0);
    const Eigen::Vector3d y = random_vector(3);
    CHECK((any.project(y) - t.project(y)).norm() == 0.0);
    const double u = uniform(-pi, pi);
    CHECK((anyc.evaluate(u) - c.evaluate(u)).norm() == 0.0);
    CHECK(anyc.project(c.evaluate(u)) == c.project(c.evaluate(u)));
  }
  GeometryModel<3> model;
  model.add_surface(4, t);
  model.add_curve(2, Line<3>({0, 0, 0}, {1, 0, 0}));
  CHECK(model.has({2, 4}));
  CHECK(model.has({1, 2}));
  CHECK_FALSE(model.has({2, 2}));
  CHECK(model.surface(3) == nullptr);
}

TEST_CASE("curve_boundary: planar mesh onto a circle") {
  // The square [-1, 1]^2 with its four sides put on the circumscribed circle.
  const double R = std::sqrt(2.0);
  for (int p : {2, 3, 5}) {
    const auto linear = structured_mesh<Simplex<2>>({4, 4}, Eigen::Vector2d(-1, -1), Eigen::Vector2d(1, 1));
    auto mesh = elevate(linear, p);
    const auto before = mesh;
    GeometryModel<2> model;
    for (int tag = 1; tag <= 4; ++tag) model.add_curve(tag, Circle<2>({0, 0}, R));
    const auto report = curve_boundary(mesh, model);
    CHECK(report.curve_nodes > 0);
    CHECK(report.max_displacement > 0.1);
    std::vector<char> on_boundary(mesh.num_nodes(), 0);
    for (const auto& f : mesh.boundary_facets())
      for (int i : mesh.facet_node_ids(f)) on_boundary[i] = 1;
    for (int i = 0; i < mesh.num_nodes(); ++i) {
      const auto& c = mesh.node_class(i);
      if (c.kind == NodeKind::fixed) {
        CHECK((mesh.node(i) - before.node(i)).norm() == 0.0);  // corners stay
      } else if (on_boundary[i]) {
        CHECK(mesh.node(i).norm() == doctest::Approx(R).epsilon(1e-13));
        REQUIRE(c.num_params == 1);
        CHECK((model.curve(c.entity->tag)->evaluate(c.params[0]) - mesh.node(i)).norm() < 1e-13);
      } else {
        CHECK((mesh.node(i) - before.node(i)).norm() == 0.0);  // interior untouched
      }
    }
    // The ideal stays straight-sided.
    CHECK((mesh.ideal_coordinates() - before.ideal_coordinates()).norm() == 0.0);

    // Without vertex projection, boundary vertices stay where they were.
    auto mesh2 = elevate(linear, p);
    curve_boundary(mesh2, model, {.project_vertices = false});
    const auto vmask = mesh2.vertex_mask();
    for (int i = 0; i < mesh2.num_nodes(); ++i)
      if (vmask[i]) CHECK((mesh2.node(i) - before.node(i)).norm() == 0.0);
  }
}

TEST_CASE("curve_boundary: tetrahedral cube onto its planes and a sphere") {
  const auto linear = structured_mesh<Simplex<3>>({2, 2, 2});
  auto mesh = elevate(linear, 3);
  const auto before = mesh;
  // Face tags of structured.hpp: x = 0, x = 1, y = 0, y = 1, z = 0, z = 1.
  GeometryModel<3> planes;
  for (int a = 0; a < 3; ++a)
    for (int s = 0; s < 2; ++s) {
      Eigen::Vector3d o = Eigen::Vector3d::Zero();
      o[a] = s;
      planes.add_surface(1 + 2 * a + s, Plane(o, (s ? 1.0 : -1.0) * Eigen::Vector3d::Unit(a)));
    }
  const auto report = curve_boundary(mesh, planes);
  CHECK(report.surface_nodes > 0);
  CHECK(report.without_geometry > 0);  // nodes on the cube's edges (curves without geometry)
  CHECK(report.max_displacement < 1e-14);
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    const auto& c = mesh.node_class(i);
    if (c.kind == NodeKind::on_entity && c.entity->dim == 2) {
      REQUIRE(c.num_params == 2);
      CHECK((planes.surface(c.entity->tag)->evaluate({c.params[0], c.params[1]}) - mesh.node(i)).norm() < 1e-14);
    }
  }

  // Every face on the circumscribed sphere: face nodes move onto it, edge
  // nodes (curves without geometry) and interior nodes stay.
  auto curved = elevate(linear, 3);
  GeometryModel<3> sphere;
  const Sphere S({0.5, 0.5, 0.5}, std::sqrt(3.0) / 2.0);
  for (int tag = 1; tag <= 6; ++tag) sphere.add_surface(tag, S);
  curve_boundary(curved, sphere);
  for (int i = 0; i < curved.num_nodes(); ++i) {
    const auto& c = curved.node_class(i);
    if (c.kind == NodeKind::on_entity && c.entity->dim == 2)
      CHECK((curved.node(i) - S.center()).norm() == doctest::Approx(S.radius()).epsilon(1e-13));
    else
      CHECK((curved.node(i) - before.node(i)).norm() == 0.0);
  }
}
