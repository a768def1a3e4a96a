// The surface certificate's polynomial g(xi) = (x_xi x x_eta) . sum_i N_i nu_i
// in Bernstein form (include/hom/surface/normal_jacobian_bernstein.hpp) and
// the unit nodal normals it is built from (include/hom/surface/unit_normal.hpp):
//   - the Bernstein expansion reproduces g, computed independently through
//     the Lagrange basis, at random points to 1e-12 relative, for curved
//     triangles and quadrilaterals on a torus at p = 1..10;
//   - at a pole of the sphere's parameterization the normal is the limit
//     from inside the element, so an element with a vertex at the pole is
//     certified valid, while a zero normal there would make it invalid;
//   - at a cone's apex, where the normal turns with the angle around the
//     axis, a fan element's normals (at the apex node and at the quadrature
//     points) are the cone's along the element, whatever angle the apex node
//     itself carries, and the element certifies valid.
#include <doctest/doctest.h>

#include <Eigen/Dense>
#include <cmath>
#include <numbers>
#include <random>

#include "hom/basis/lagrange.hpp"
#include "hom/element/cube.hpp"
#include "hom/element/simplex.hpp"
#include "hom/geometry/parametric_surface.hpp"
#include "hom/geometry/sphere.hpp"
#include "hom/geometry/torus.hpp"
#include "hom/nodes/gauss_lobatto.hpp"
#include "hom/nodes/warp_blend.hpp"
#include "hom/quadrature/quadrature_policy.hpp"
#include "hom/quality/certify.hpp"
#include "hom/surface/certified_surface.hpp"
#include "hom/surface/normal_jacobian_bernstein.hpp"
#include "hom/surface/surface_element_quality.hpp"
#include "hom/surface/unit_normal.hpp"

using namespace hom;

namespace {

/// Parameters of the nodes of a reference element of Family mapped affinely
/// to a patch of size h at (u0, v0), each moved by a random amount up to
/// `jitter` h (so the element is curved in R^3 by the surface and by the jitter).
template <ElementFamily Family, NodeSet Nodes>
Eigen::Matrix2Xd element_parameters(int p, double u0, double v0, double h, double jitter, std::mt19937& rng) {
  const auto& nodes = lagrange_basis<Family, Nodes>(p).nodes();
  std::uniform_real_distribution<double> d(-jitter * h, jitter * h);
  Eigen::Matrix2Xd UV(2, Eigen::Index(nodes.size()));
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const Eigen::Vector2d r =
        Family::is_simplex ? Eigen::Vector2d(nodes[i]) : Eigen::Vector2d((nodes[i].array() + 1.0) / 2.0);
    UV.col(Eigen::Index(i)) = Eigen::Vector2d(u0, v0) + h * r + Eigen::Vector2d(d(rng), d(rng));
  }
  return UV;
}

/// g at xi through the Lagrange basis, with the coordinates relative to the
/// first node (at p = 10 the Lagrange gradients sum to hundreds in magnitude:
/// an offset would cost the reference digits, not the expansion).
template <ElementFamily Family, NodeSet Nodes>
double lagrange_g(int p, const Eigen::Matrix3Xd& X, const Eigen::Matrix3Xd& nu, const typename Family::Point& xi) {
  const auto& basis = lagrange_basis<Family, Nodes>(p);
  const Eigen::Matrix3Xd Xc = X.colwise() - X.col(0);
  const Eigen::Matrix<double, 3, 2> J = Xc * basis.gradient(xi);
  return J.col(0).cross(J.col(1)).dot(nu * basis.value(xi));
}

template <ElementFamily Family>
typename Family::Point random_point(std::mt19937& rng) {
  std::uniform_real_distribution<double> d(0.0, 1.0);
  for (;;) {
    const Eigen::Vector2d x(d(rng), d(rng));
    if constexpr (Family::is_simplex) {
      if (x.sum() <= 1.0) return x;
    } else {
      return 2.0 * x - Eigen::Vector2d::Ones();
    }
  }
}

template <ElementFamily Family, NodeSet Nodes>
void check_reproduces_g() {
  const Torus torus(Eigen::Vector3d(0.3, -0.2, 0.1), Eigen::Vector3d(0.0, 0.6, 0.8), 2.0, 0.7);
  std::mt19937 rng(7);
  for (int p = 1; p <= 10; ++p) {
    CAPTURE(p);
    const Eigen::Matrix2Xd UV = element_parameters<Family, Nodes>(p, 0.4, 1.1, 0.5, 0.02, rng);
    Eigen::Matrix3Xd X(3, UV.cols());
    for (Eigen::Index i = 0; i < UV.cols(); ++i) X.col(i) = torus.evaluate(UV.col(i));
    const Eigen::Matrix3Xd nu = element_unit_normals(torus, UV);
    const BernsteinPolynomial<Family> g = normal_jacobian_bernstein<Family, Nodes>(p, X, nu);
    CHECK(g.space->degree() == normal_jacobian_degree<Family>(p));
    CHECK(g.coefficients.size() == g.space->size());
    // Relative to the largest coefficient, as for the planar det (test_certify).
    const double scale = g.coefficients.cwiseAbs().maxCoeff();
    double error = 0.0;
    for (int k = 0; k < 40; ++k) {
      const auto xi = random_point<Family>(rng);
      error =
          std::max(error, std::abs(g.space->evaluate(g.coefficients, xi) - lagrange_g<Family, Nodes>(p, X, nu, xi)));
    }
    CHECK(scale > 0.0);
    CHECK(error <= 1e-12 * scale);
    for (int v = 0; v < Family::num_vertices; ++v)  // the corner coefficients are values
      CHECK(std::abs(g.coefficients[g.space->corners()[v]] - lagrange_g<Family, Nodes>(p, X, nu, Family::vertex(v))) <=
            1e-12 * scale);
  }
}

}  // namespace

TEST_CASE("normal jacobian: the Bernstein expansion of g reproduces g on curved triangles, p = 1..10") {
  check_reproduces_g<Simplex<2>, WarpBlend>();
}

TEST_CASE("normal jacobian: the Bernstein expansion of g reproduces g on curved quadrilaterals, p = 1..10") {
  check_reproduces_g<Cube<2>, GaussLobatto>();
}

TEST_CASE("unit normal: at a pole the normal is the limit from inside the element, and the element certifies valid") {
  using F = Simplex<2>;
  using N = WarpBlend;
  const Sphere sphere(Eigen::Vector3d::Zero(), 1.5);
  const double pole = std::numbers::pi / 2, h = 0.3;
  const Eigen::Vector2d at_pole(0.2, pole);
  CHECK(unit_normal(sphere, at_pole).norm() == 0.0);  // S_u vanishes there: no direction
  const Eigen::Vector3d limit = unit_normal_from(sphere, at_pole, Eigen::Vector2d(0.2, pole - h));
  CHECK((limit - Eigen::Vector3d::UnitZ()).norm() < 1e-5);  // the outward normal at the pole

  // A degree-4 triangle with a vertex at the pole: the straight triangle
  // (S(0, pole - h), S(1, pole - h), pole) with its nodes projected radially
  // onto the sphere, the nodes' parameters from the sphere's projection.
  const int p = 4;
  const auto& nodes = lagrange_basis<F, N>(p).nodes();
  const Eigen::Vector3d a = sphere.evaluate(Eigen::Vector2d(0.0, pole - h)),
                        b = sphere.evaluate(Eigen::Vector2d(1.0, pole - h));
  const Eigen::Vector3d c = sphere.evaluate(at_pole);
  Eigen::Matrix2Xd UV(2, Eigen::Index(nodes.size()));
  Eigen::Matrix3Xd X(3, UV.cols());
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const Eigen::Vector2d xi = nodes[i];
    const Eigen::Vector3d straight = a + xi[0] * (b - a) + xi[1] * (c - a);
    UV.col(Eigen::Index(i)) = sphere.project(straight);
    X.col(Eigen::Index(i)) = sphere.evaluate(UV.col(Eigen::Index(i)));
  }
  CHECK(UV(1, 2) == doctest::Approx(pole));  // vertex 2 is at the pole
  const Eigen::Matrix3Xd nu = element_unit_normals(sphere, UV);
  for (Eigen::Index i = 0; i < nu.cols(); ++i) CHECK(nu.col(i).norm() == doctest::Approx(1.0));
  const auto valid = certify_surface_element<F, N>(p, X, nu, CertifyOptions{});
  CHECK(valid.status == Certificate::certified_valid);
  // With no normal at the pole vertex (vertex 2), g vanishes there.
  Eigen::Matrix3Xd without = nu;
  without.col(2).setZero();
  const auto invalid = certify_surface_element<F, N>(p, X, without, CertifyOptions{});
  CHECK(invalid.status == Certificate::certified_invalid);
  REQUIRE(invalid.invalid_point.has_value());
  CHECK((*invalid.invalid_point - F::vertex(2)).norm() < 1e-12);
}

TEST_CASE("unit normal: an element straddling a periodic seam has its mean parameters inside it") {
  const Sphere sphere(Eigen::Vector3d::Zero(), 1.0);
  const ParameterRange longitude = sphere.range(0);
  REQUIRE(longitude.periodic);
  // Three nodes near the seam of the longitude, on both of its sides.
  Eigen::Matrix2Xd UV(2, 3);
  UV << longitude.hi - 0.05, longitude.lo + 0.05, longitude.hi - 0.02,  //
      0.1, 0.1, 0.2;
  const Eigen::Vector2d mean = mean_parameters(sphere, UV);
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (int i = 0; i < 3; ++i) centroid += sphere.evaluate(UV.col(i)) / 3.0;
  // The plain mean of the longitudes lies half a turn away, on the far side.
  CHECK((sphere.evaluate(Eigen::Vector2d(UV.rowwise().mean())) - centroid).norm() > 1.0);
  CHECK((sphere.evaluate(mean) - centroid).norm() < 0.05);
}

TEST_CASE("unit normal: at a cone's apex the normals follow the element, whatever angle the apex node carries") {
  using F = Simplex<2>;
  using N = WarpBlend;
  // S(u, v) = ((1 - v) R cos u, (1 - v) R sin u, H v): the apex at v = 1,
  // where S_u vanishes; the outward normal is (H cos u, H sin u, R) / |.|.
  const double R = 1.0, H = 3.0;
  const ParametricSurface cone(
      [=](const Eigen::Vector2d& p) {
        return Eigen::Vector3d((1 - p[1]) * R * std::cos(p[0]), (1 - p[1]) * R * std::sin(p[0]), H * p[1]);
      },
      [=](const Eigen::Vector2d& p) {
        Eigen::Matrix<double, 3, 2> d;
        d << -(1 - p[1]) * R * std::sin(p[0]), -R * std::cos(p[0]),  //
            (1 - p[1]) * R * std::cos(p[0]), -R * std::sin(p[0]),    //
            0.0, H;
        return d;
      },
      [](const Eigen::Vector2d&) { return SurfaceSecondDerivatives{}; },
      {0.0, 2 * std::numbers::pi, true}, {0.0, 1.0, false});
  auto normal_at = [&](double u) { return Eigen::Vector3d(H * std::cos(u), H * std::sin(u), R).normalized(); };

  // A degree-3 fan triangle spanning the angles 1.7 to 2.3 (its middle 2.0),
  // its sides at the apex on the cone's lines (as hom curve places them):
  // u = 1.7 + 0.6 xi / (1 - eta), v = 0.6 + 0.4 eta. The apex node then
  // carries the angle 0 (and, through the seam, 2 pi), which names the same point.
  const int p = 3;
  const auto& nodes = lagrange_basis<F, N>(p).nodes();
  Eigen::Matrix2Xd UV(2, Eigen::Index(nodes.size()));
  Eigen::Matrix3Xd X(3, UV.cols());
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const Eigen::Vector2d xi = nodes[i];
    const double eta = xi[1];
    UV.col(Eigen::Index(i)) << (eta < 1 ? 1.7 + 0.6 * xi[0] / (1 - eta) : 2.0), 0.6 + 0.4 * eta;
    X.col(Eigen::Index(i)) = cone.evaluate(UV.col(Eigen::Index(i)));
  }
  const Eigen::Matrix2Xd along = UV;  // the parameters that follow the element
  REQUIRE(UV(1, 2) == 1.0);  // vertex 2 is the apex
  UV(0, 2) = 2 * std::numbers::pi - 0.1;
  CHECK((cone.evaluate(UV.col(2)) - X.col(2)).norm() < 1e-15);
  CHECK(unit_normal(cone, UV.col(2)).norm() == 0.0);

  // The apex node's normal: the cone's at the mean angle of the other nodes.
  const Eigen::Matrix3Xd nu = element_unit_normals(cone, UV);
  CHECK((nu.col(2) - normal_at(2.0)).norm() < 1e-5);
  for (Eigen::Index i = 0; i < nu.cols(); ++i)
    if (i != 2) CHECK((nu.col(i) - normal_at(UV(0, i))).norm() < 1e-12);
  // The apex's own angle would give the far side's normal (they differ by
  // more than 90 degrees), and the element would be certified folded.
  CHECK(normal_at(UV(0, 2)).dot(normal_at(2.0)) < 0.0);
  Eigen::Matrix3Xd far_side = nu;
  far_side.col(2) = normal_at(UV(0, 2));
  CHECK(certify_surface_element<F, N>(p, X, far_side, CertifyOptions{}).status == Certificate::certified_invalid);
  CHECK(certify_surface_element<F, N>(p, X, nu, CertifyOptions{}).status == Certificate::certified_valid);

  // The normals at the quadrature points: those at the parameters that
  // follow the element, not at ones interpolated from the apex's angle 0.
  const auto rule = quadrature_for<F, DefaultExactness>(p);
  const auto& tab = tabulation<F, N>(p, rule);
  const SurfaceNormals at = surface_normals(tab, cone, UV);
  const Eigen::Matrix2Xd uq = along * tab.shape_values.transpose();
  for (int q = 0; q < tab.num_points(); ++q) CHECK((at.points.col(q) - normal_at(uq(0, q))).norm() < 1e-9);
}
