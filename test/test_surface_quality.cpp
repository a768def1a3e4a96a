// Property tests of the surface measures (chapter 5, include/hom/surface/)
// and of the analytic surfaces they are tested on (hyperbolic paraboloid,
// ParametricSurface, the thesis's parameterizations of section 5.5.1.2):
//   - consistency with the planar measure on z = 0 (section 5.5.1.1);
//   - invariance under rigid motions;
//   - independence of the parameterization (proposition 5.1, remark 5.3);
//   - the congruent straight-sided element scores 1 (remark 5.4);
//   - folded / inverted elements score 0;
//   - finite-difference checks of every derivative (J-bar, eta and eta_E in B,
//     X and the nodes' parameters; the surfaces' first and second derivatives).
#include <doctest/doctest.h>

#include <cmath>
#include <numbers>
#include <random>

#include <Eigen/Dense>

#include "hom/geometry/cylinder.hpp"
#include "hom/geometry/hyperbolic_paraboloid.hpp"
#include "hom/geometry/parametric_surface.hpp"
#include "hom/geometry/sphere.hpp"
#include "hom/geometry/thesis_parameterizations.hpp"
#include "hom/measure/oddy_measure.hpp"
#include "hom/measure/shape_measure.hpp"
#include "hom/mesh/elevate.hpp"
#include "hom/mesh/structured.hpp"
#include "hom/nodes/gauss_lobatto.hpp"
#include "hom/nodes/warp_blend.hpp"
#include "hom/quadrature/quadrature_policy.hpp"
#include "hom/quality/element_quality.hpp"
#include "hom/quality/mesh_quality.hpp"
#include "hom/surface/surface_distortion.hpp"
#include "hom/surface/surface_element_quality.hpp"
#include "hom/surface/surface_jacobian.hpp"
#include "hom/surface/surface_mesh_quality.hpp"

using namespace hom;

namespace {

template <class F, class N>
struct Case {
  using Family = F;
  using Nodes = N;
};

#define HOM_SURFACE_CASES Case<Simplex<2>, WarpBlend>, Case<Cube<2>, GaussLobatto>

using Mat32 = Eigen::Matrix<double, 3, 2>;
using UVs = Eigen::Matrix<double, 2, Eigen::Dynamic>;

template <class F, class N>
const Tabulation<F>& tab(int p) {
  return tabulation<F, N>(p, quadrature_for<F, DefaultExactness>(p));
}

template <class F, class N>
ElementNodes<2> reference_nodes(int p) {
  const auto pts = N::template points<F>(p);
  ElementNodes<2> X(2, pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) X.col(i) = pts[i];
  return X;
}

Eigen::Matrix3d random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> g;
  Eigen::Matrix3d A;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) A(i, j) = g(rng);
  Eigen::Matrix3d Q = Eigen::HouseholderQR<Eigen::Matrix3d>(A).householderQ();
  if (Q.determinant() < 0) Q.col(0) *= -1;
  return Q;
}

template <class M>
M random_matrix(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  M m;
  for (Eigen::Index i = 0; i < m.size(); ++i) m.data()[i] = u(rng);
  return m;
}

// A smooth curving of a 2D node set (as in test_quality.cpp).
ElementNodes<2> curve(const ElementNodes<2>& X, double eps) {
  ElementNodes<2> Y = X;
  for (int i = 0; i < X.cols(); ++i)
    for (int k = 0; k < 2; ++k) Y(k, i) += eps * std::sin(1.3 * X((k + 1) % 2, i) + 0.7 * k) * (0.5 + X(k, i) * X(k, i));
  return Y;
}

ElementNodes<3> embed(const ElementNodes<2>& X) {
  ElementNodes<3> Y = ElementNodes<3>::Zero(3, X.cols());
  Y.topRows<2>() = X;
  return Y;
}

// Nodes of an element in parameter space: the reference nodes scaled by `size`
// around `center` (an element of diameter about 2 size), curved by eps.
template <class F, class N>
UVs parameter_element(int p, const Eigen::Vector2d& center, double size, double eps) {
  ElementNodes<2> X = curve(reference_nodes<F, N>(p), eps);
  if constexpr (F::is_simplex) X.array() -= 1.0 / 3.0;
  return (size * X).colwise() + center;
}

bool same_distortion(double a, double b, double tol) {
  if (!std::isfinite(a) || !std::isfinite(b)) return std::isfinite(a) == std::isfinite(b);
  return std::abs(a - b) <= tol * std::abs(a);
}

const Eigen::Vector3d e3 = Eigen::Vector3d::UnitZ();

}  // namespace

// ---------------------------------------------------------------------------
// Surfaces.

namespace {

struct NamedSurface {
  const char* name;
  ParametricSurface surface;
};

std::vector<NamedSurface> thesis_surfaces() {
  return {{"phi_Sigma1", thesis_sigma1(0)}, {"phi1_Sigma1", thesis_sigma1(1)}, {"phi2_Sigma1", thesis_sigma1(2)},
          {"phi_Sigma2", thesis_sigma2(0)}, {"phi1_Sigma2", thesis_sigma2(1)}, {"phi2_Sigma2", thesis_sigma2(2)}};
}

template <class G>
void check_surface_derivatives(const G& g, const Eigen::Vector2d& uv) {
  const double h = 1e-5;
  const Mat32 d = g.derivatives(uv);
  const auto s = g.second_derivatives(uv);
  for (int k = 0; k < 2; ++k) {
    const Eigen::Vector2d e = Eigen::Vector2d::Unit(k) * h;
    const Eigen::Vector3d fd = (g.evaluate(uv + e) - g.evaluate(uv - e)) / (2 * h);
    CHECK((fd - d.col(k)).norm() <= 1e-8 * (1 + d.col(k).norm()));
    const Mat32 dd = (g.derivatives(uv + e) - g.derivatives(uv - e)) / (2 * h);
    const Eigen::Vector3d exact0 = k == 0 ? s.uu : s.uv, exact1 = k == 0 ? s.uv : s.vv;
    CHECK((dd.col(0) - exact0).norm() <= 1e-6 * (1 + exact0.norm()));
    CHECK((dd.col(1) - exact1).norm() <= 1e-6 * (1 + exact1.norm()));
  }
}

}  // namespace

TEST_CASE("hyperbolic paraboloid: derivatives, projection, saddle") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (int t = 0; t < 10; ++t) {
    const Eigen::Vector3d o = random_matrix<Eigen::Vector3d>(rng);
    const HyperbolicParaboloid g(o, random_matrix<Eigen::Vector3d>(rng), 0.7 + 0.1 * t, 1.3, random_matrix<Eigen::Vector3d>(rng));
    const Eigen::Vector2d uv(u(rng), u(rng));
    check_surface_derivatives(g, uv);
    const Eigen::Vector3d x = g.evaluate(uv);
    CHECK((g.project(x) - uv).norm() < 1e-10);
    // Off the surface: first-order optimality of the projection.
    const Eigen::Vector3d y = x + 0.2 * random_matrix<Eigen::Vector3d>(rng);
    const Eigen::Vector2d a = g.project(y);
    const Mat32 d = g.derivatives(a);
    CHECK(std::abs((g.evaluate(a) - y).dot(d.col(0))) < 1e-10);
    CHECK(std::abs((g.evaluate(a) - y).dot(d.col(1))) < 1e-10);
    // z = u^2/a^2 - v^2/b^2 over the (e1, e2) plane: a saddle at the origin.
    CHECK((g.evaluate(Eigen::Vector2d::Zero()) - o).norm() < 1e-14);
    const double up = (g.evaluate(Eigen::Vector2d(0.5, 0)) - o).dot(g.axis());
    const double down = (g.evaluate(Eigen::Vector2d(0, 0.5)) - o).dot(g.axis());
    CHECK(up == doctest::Approx(0.25 / ((0.7 + 0.1 * t) * (0.7 + 0.1 * t))));
    CHECK(down == doctest::Approx(-0.25 / (1.3 * 1.3)));
  }
}

TEST_CASE("thesis parameterizations (section 5.5.1.2): formulas, derivatives, projection") {
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> u(-0.95, 0.95);
  const auto surfaces = thesis_surfaces();
  for (int t = 0; t < 20; ++t) {
    const Eigen::Vector2d uv(u(rng), u(rng));
    const double e = thesis_epsilon(uv[0], uv[1]);
    CHECK(e == doctest::Approx(std::exp(-2 * (1 - uv[0] * uv[0]) * (1 - uv[1] * uv[1]))));
    // eqs 5.29, 5.30 and the Sigma_2 analogues, written out.
    const Eigen::Vector2d p1(uv[0], uv[1] * e), p2(uv[0] * e, uv[1] * e);
    auto wave = [](const Eigen::Vector2d& p) {
      // Sigma_2's height as table 5.2 was computed (thesis_parameterizations.hpp).
      return std::sin(std::numbers::pi / 2 * p[0]) * std::cos(std::numbers::pi / 2 * p[1]);
    };
    CHECK((thesis_sigma1(1).evaluate(uv) - Eigen::Vector3d(p1[0], p1[1], 0)).norm() < 1e-15);
    CHECK((thesis_sigma1(2).evaluate(uv) - Eigen::Vector3d(p2[0], p2[1], 0)).norm() < 1e-15);
    CHECK((thesis_sigma2(0).evaluate(uv) - Eigen::Vector3d(uv[0], uv[1], wave(uv))).norm() < 1e-15);
    CHECK((thesis_sigma2(1).evaluate(uv) - Eigen::Vector3d(p1[0], p1[1], wave(p1))).norm() < 1e-15);
    CHECK((thesis_sigma2(2).evaluate(uv) - Eigen::Vector3d(p2[0], p2[1], wave(p2))).norm() < 1e-15);
    for (const auto& s : surfaces) {
      CAPTURE(s.name);
      check_surface_derivatives(s.surface, uv);
      // Orientation-preserving: the normal has a positive z component.
      const Mat32 d = s.surface.derivatives(uv);
      CHECK(d.col(0).cross(d.col(1))[2] > 0.0);
      const Eigen::Vector2d back = s.surface.project(s.surface.evaluate(uv));
      CHECK((back - uv).norm() < 1e-9);
    }
  }
  // The reparameterizations map the square onto itself (boundary to boundary).
  for (int k = 1; k <= 2; ++k) {
    const auto g = thesis_sigma1(k);
    CHECK((g.evaluate(Eigen::Vector2d(1, 0.3)) - Eigen::Vector3d(1, 0.3, 0)).norm() < 1e-15);
    CHECK((g.evaluate(Eigen::Vector2d(-0.4, -1)) - Eigen::Vector3d(-0.4, -1, 0)).norm() < 1e-15);
  }
}

// ---------------------------------------------------------------------------
// J-bar (eq 5.5).

TEST_CASE("J-bar: oriented Gram-Schmidt basis and closed form (section 5.2.1)") {
  std::mt19937 rng(21);
  for (int t = 0; t < 50; ++t) {
    const Mat32 T = random_matrix<Mat32>(rng);
    const Eigen::Vector3d n = random_matrix<Eigen::Vector3d>(rng);
    const Mat32 Q = oriented_orthonormal_basis(T, n);
    const Eigen::Matrix2d R = tangent_plane_coordinates(T, n);
    CHECK((Q.transpose() * Q - Eigen::Matrix2d::Identity()).norm() < 1e-12);
    CHECK((Q.transpose() * T - R).norm() < 1e-12);  // R = T~^T T
    CHECK((Q * R - T).norm() < 1e-12);              // T lies in span(T~)
    CHECK(R(1, 0) == 0.0);
    CHECK(R(0, 0) > 0.0);
    // gamma: (t~1, t~2) is counter-clockwise seen from n.
    CHECK(Q.col(0).cross(Q.col(1)).dot(n) > 0.0);
    CHECK(R.determinant() == doctest::Approx(tangent_orientation(T, n) * T.col(0).cross(T.col(1)).norm()));
    // Rigid motions of T (and its normal) leave T~^T T unchanged.
    const Eigen::Matrix3d Rot = random_rotation(rng);
    CHECK((tangent_plane_coordinates(Rot * T, Rot * n) - R).norm() < 1e-12);
    // J-bar maps the ideal's planar coordinates to the physical's: J-bar A-bar = B-bar.
    const Mat32 B = random_matrix<Mat32>(rng);
    const Eigen::Matrix2d J = surface_jacobian(T, n, B, n);
    CHECK((J * R - tangent_plane_coordinates(B, n)).norm() < 1e-10 * (1 + J.norm() * R.norm()));
  }
  // In the plane z = 0 with n = e3, J-bar is the planar Jacobian up to rotations:
  // same singular values and same determinant sign.
  for (int t = 0; t < 50; ++t) {
    const Eigen::Matrix2d A2 = random_matrix<Eigen::Matrix2d>(rng), B2 = random_matrix<Eigen::Matrix2d>(rng);
    Mat32 A = Mat32::Zero(), B = Mat32::Zero();
    A.topRows<2>() = A2;
    B.topRows<2>() = B2;
    // The ideal oriented by its own normal (det A-bar > 0), the physical by e3.
    const Eigen::Matrix2d J = surface_jacobian(A, e3 * (A2.determinant() > 0 ? 1 : -1), B, e3);
    const Eigen::Vector2d sj = Eigen::JacobiSVD<Eigen::Matrix2d>(J).singularValues();
    const Eigen::Vector2d sp = Eigen::JacobiSVD<Eigen::Matrix2d>(B2 * A2.inverse()).singularValues();
    CHECK((sj - sp).norm() < 1e-9 * (1 + sp.norm()));
    CHECK(J.determinant() == doctest::Approx(B2.determinant() / std::abs(A2.determinant())));
  }
}

TEST_CASE("J-bar: first and second derivatives in B match finite differences") {
  std::mt19937 rng(22);
  const double h = 1e-6;
  for (int t = 0; t < 40; ++t) {
    const Mat32 B = random_matrix<Mat32>(rng);
    // Both orientations: n on either side of the plane of B.
    const Eigen::Vector3d c = B.col(0).cross(B.col(1));
    const Eigen::Vector3d n = (t % 2 ? 1.0 : -1.0) * c + 0.3 * random_matrix<Eigen::Vector3d>(rng).cross(c);
    const Eigen::Matrix2d K = random_matrix<Eigen::Matrix2d>(rng) + 2.0 * Eigen::Matrix2d::Identity();
    const SurfaceJacobianJet jet = surface_jacobian_jet(K, B, n);
    CHECK((jet.value - tangent_plane_coordinates(B, n) * K).norm() < 1e-14);
    for (int j = 0; j < 6; ++j) {
      Mat32 Bp = B, Bm = B;
      Bp.data()[j] += h;
      Bm.data()[j] -= h;
      const Eigen::Matrix2d fd = (surface_jacobian_jet(K, Bp, n).value - surface_jacobian_jet(K, Bm, n).value) / (2 * h);
      const double scale = 1 + jet.first.cwiseAbs().maxCoeff();
      CHECK((Eigen::Map<const Eigen::Vector4d>(fd.data()) - jet.first.col(j)).norm() < 1e-7 * scale);
      const Eigen::Matrix<double, 4, 6> dfd =
          (surface_jacobian_jet(K, Bp, n).first - surface_jacobian_jet(K, Bm, n).first) / (2 * h);
      for (int i = 0; i < 4; ++i) {
        const double s2 = 1 + jet.second[i].cwiseAbs().maxCoeff();
        CHECK((dfd.row(i).transpose() - jet.second[i].col(j)).norm() < 1e-6 * s2);
      }
    }
    for (int i = 0; i < 4; ++i) CHECK((jet.second[i] - jet.second[i].transpose()).norm() < 1e-12 * (1 + jet.second[i].norm()));
  }
}

TEST_CASE_TEMPLATE("eta(J-bar) (eq 5.6): gradient and Hessian in B match finite differences", M, ShapeMeasure,
                   OddyMeasure) {
  std::mt19937 rng(23);
  const double h = 1e-6;
  const M measure;
  for (int t = 0; t < 40; ++t) {
    const Mat32 B = random_matrix<Mat32>(rng);
    const Eigen::Vector3d c = B.col(0).cross(B.col(1));
    // Valid (n along b1 x b2) and inverted (n opposite) points; the inverted
    // ones only under the regularized determinant (eq 3.4).
    const bool inverted = t % 3 == 0;
    const Eigen::Vector3d n = inverted ? Eigen::Vector3d(-c) : c;
    const Eigen::Matrix2d K = tangent_plane_coordinates(random_matrix<Mat32>(rng) + Mat32::Identity() * 2, e3).inverse();
    auto check = [&](const auto& reg) {
      Mat32 g;
      Eigen::Matrix<double, 6, 6> H;
      const double eta = surface_distortion_hessian(measure, K, B, n, reg, g, H);
      Mat32 g1;
      CHECK(surface_distortion_gradient(measure, K, B, n, reg, g1) == doctest::Approx(eta).epsilon(1e-14));
      CHECK(surface_distortion(measure, K, B, n, reg) == doctest::Approx(eta).epsilon(1e-14));
      CHECK((g1 - g).norm() <= 1e-12 * (1 + g.norm()));
      for (int j = 0; j < 6; ++j) {
        Mat32 Bp = B, Bm = B;
        Bp.data()[j] += h;
        Bm.data()[j] -= h;
        const double fd = (surface_distortion(measure, K, Bp, n, reg) - surface_distortion(measure, K, Bm, n, reg)) / (2 * h);
        CHECK(std::abs(fd - g.data()[j]) < 1e-6 * (1 + std::abs(eta)));
        Mat32 gp, gm;
        surface_distortion_gradient(measure, K, Bp, n, reg, gp);
        surface_distortion_gradient(measure, K, Bm, n, reg, gm);
        const Eigen::Matrix<double, 6, 1> col = Eigen::Map<const Eigen::Matrix<double, 6, 1>>(Mat32((gp - gm) / (2 * h)).data());
        CHECK((col - H.col(j)).norm() < 1e-5 * (1 + H.cwiseAbs().maxCoeff()));
      }
    };
    check(RegularizedDeterminant{0.05});
    if (!inverted) check(ClampedDeterminant{});
    else CHECK(std::isinf(surface_distortion(measure, K, B, n, ClampedDeterminant{})));
  }
}

// ---------------------------------------------------------------------------
// Element quality (definitions 5.1, 5.2).

TEST_CASE_TEMPLATE("consistency (section 5.5.1.1): an element in z = 0 scores exactly its planar quality", C,
                   HOM_SURFACE_CASES) {
  using F = typename C::Family;
  using N = typename C::Nodes;
  for (int p = 1; p <= 5; ++p) {
    const auto& t = tab<F, N>(p);
    const ElementNodes<2> X = reference_nodes<F, N>(p);
    const IdealVertices<F> own = X.leftCols(F::num_vertices);
    for (double eps : {0.0, 0.03, 0.1, 0.3, 0.8}) {
      CAPTURE(p);
      CAPTURE(eps);
      const ElementNodes<2> Y = curve(X, eps);
      for (const IdealVertices<F>& ideal : {own, regular_ideal_vertices<F>(), IdealVertices<F>(1.7 * own)}) {
        std::vector<double> pw_planar, pw_surface;
        const auto planar = element_quality<F>(t, Y, ideal, ShapeMeasure{}, &pw_planar);
        const auto surface = surface_element_quality<F>(t, embed(Y), embed_ideal<F>(ideal), SurfaceNormals::constant(e3),
                                                         ShapeMeasure{}, &pw_surface);
        CHECK(planar.valid == surface.valid);
        CHECK(same_distortion(planar.distortion, surface.distortion, 1e-12));
        CHECK(std::abs(planar.quality - surface.quality) <= 1e-12);
        CHECK(std::abs(planar.min_det - surface.min_det) <= 1e-12 * std::abs(planar.max_det));
        CHECK(std::abs(planar.volume - surface.volume) <= 1e-12 * std::abs(planar.volume));
        CHECK(std::abs(planar.ideal_volume - surface.ideal_volume) <= 1e-12 * std::abs(planar.ideal_volume));
        for (std::size_t q = 0; q < pw_planar.size(); ++q) CHECK(std::abs(pw_planar[q] - pw_surface[q]) <= 1e-12);
        const auto oddy_p = element_quality<F>(t, Y, ideal, OddyMeasure{});
        const auto oddy_s = surface_element_quality<F>(t, embed(Y), embed_ideal<F>(ideal), SurfaceNormals::constant(e3),
                                                       OddyMeasure{});
        CHECK(same_distortion(oddy_p.distortion, oddy_s.distortion, 1e-12));
        // The same with the element's own facet normal (no geometry), where
        // the straight-sided facet keeps the plane's orientation (a strongly
        // curved quadrilateral's vertices may not).
        if (facet_normal<F>(embed(Y)).dot(e3) > 0.0) {
          const auto facet = surface_element_quality<F>(t, embed(Y), embed_ideal<F>(ideal),
                                                        facet_normals<F>(embed(Y)), ShapeMeasure{});
          CHECK(same_distortion(planar.distortion, facet.distortion, 1e-12));
        }
      }
    }
  }
}

TEST_CASE_TEMPLATE("rigid motions of the physical element or of the ideal leave the quality unchanged", C,
                   HOM_SURFACE_CASES) {
  using F = typename C::Family;
  using N = typename C::Nodes;
  std::mt19937 rng(31);
  const Cylinder cyl(Eigen::Vector3d(0.1, -0.2, 0.3), Eigen::Vector3d(0.2, 0.1, 1.0), 0.8);
  for (int p = 1; p <= 5; ++p) {
    const auto& t = tab<F, N>(p);
    const UVs U = parameter_element<F, N>(p, Eigen::Vector2d(0.4, 0.2), 0.35, 0.1);
    const ElementNodes<3> X = surface_points(cyl, U);
    const SurfaceNormals n = surface_normals(t, cyl, U);
    const SurfaceIdealVertices<F> ideal = embed_ideal<F>(regular_ideal_vertices<F>());
    const auto base = surface_element_quality<F>(t, X, ideal, n, ShapeMeasure{});
    CHECK(base.valid);
    CHECK(base.quality > 0.2);
    CHECK(base.quality < 1.0);
    // The geometry overload is the same computation.
    CHECK(surface_element_quality<F>(t, cyl, U, ideal, ShapeMeasure{}).distortion == base.distortion);
    for (int k = 0; k < 5; ++k) {
      const Eigen::Matrix3d R = random_rotation(rng);
      const Eigen::Vector3d s = random_matrix<Eigen::Vector3d>(rng) * 3.0;
      const ElementNodes<3> RX = (R * X).colwise() + s;
      SurfaceNormals Rn{R * n.points, R * n.nodes};
      const auto moved = surface_element_quality<F>(t, RX, ideal, Rn, ShapeMeasure{});
      CHECK(same_distortion(moved.distortion, base.distortion, 1e-12));
      // The ideal moved instead (it is oriented by its own facet normal).
      const SurfaceIdealVertices<F> Ri = (R * ideal).colwise() + s;
      CHECK(same_distortion(surface_element_quality<F>(t, X, Ri, n, ShapeMeasure{}).distortion, base.distortion, 1e-12));
      CHECK(same_distortion(surface_element_quality<F>(t, X, Ri, n, OddyMeasure{}).distortion,
                            surface_element_quality<F>(t, X, ideal, n, OddyMeasure{}).distortion, 1e-12));
    }
  }
}

TEST_CASE_TEMPLATE("independence of the parameterization (proposition 5.1): phi^1 and phi^2 give the same quality", C,
                   HOM_SURFACE_CASES) {
  using F = typename C::Family;
  using N = typename C::Nodes;
  for (int surface = 1; surface <= 2; ++surface) {
    const ParametricSurface phi0 = surface == 1 ? thesis_sigma1(0) : thesis_sigma2(0);
    const ParametricSurface phi1 = surface == 1 ? thesis_sigma1(1) : thesis_sigma2(1);
    const ParametricSurface phi2 = surface == 1 ? thesis_sigma1(2) : thesis_sigma2(2);
    for (int p = 1; p <= 5; ++p) {
      CAPTURE(surface);
      CAPTURE(p);
      const auto& t = tab<F, N>(p);
      // An element given by its nodes' phi^1 parameters (curved in U^1),
      // the same physical nodes through phi^2 and phi (projection).
      const UVs U1 = parameter_element<F, N>(p, Eigen::Vector2d(0.15, -0.1), 0.3, 0.1);
      const ElementNodes<3> X = surface_points(phi1, U1);
      UVs U2(2, U1.cols()), U0(2, U1.cols());
      for (Eigen::Index i = 0; i < U1.cols(); ++i) {
        U2.col(i) = phi2.project(X.col(i));
        U0.col(i) = phi0.project(X.col(i));
      }
      REQUIRE((surface_points(phi2, U2) - X).norm() < 1e-12);
      REQUIRE((surface_points(phi0, U0) - X).norm() < 1e-12);
      CHECK((U2 - U1).norm() > 0.05);  // genuinely different parameters
      const SurfaceIdealVertices<F> ideal = embed_ideal<F>(0.4 * regular_ideal_vertices<F>());
      const auto q1 = surface_element_quality<F>(t, phi1, U1, ideal, ShapeMeasure{});
      const auto q2 = surface_element_quality<F>(t, phi2, U2, ideal, ShapeMeasure{});
      const auto q0 = surface_element_quality<F>(t, phi0, U0, ideal, ShapeMeasure{});
      CHECK(q1.valid);
      CHECK(same_distortion(q1.distortion, q2.distortion, 1e-11));
      CHECK(same_distortion(q1.distortion, q0.distortion, 1e-11));
      CHECK(same_distortion(surface_element_quality<F>(t, phi1, U1, ideal, OddyMeasure{}).distortion,
                            surface_element_quality<F>(t, phi2, U2, ideal, OddyMeasure{}).distortion, 1e-11));
      // On the plane it is also the planar quality of the (x, y) nodes.
      if (surface == 1) {
        const auto planar = element_quality<F>(t, ElementNodes<2>(X.topRows<2>()), IdealVertices<F>(ideal.template topRows<2>()),
                                               ShapeMeasure{});
        CHECK(same_distortion(planar.distortion, q1.distortion, 1e-11));
      }
      // The gradients in the nodes' parameters differ, but both are the pull
      // back of one gradient in the physical coordinates: grad_u^k = D phi^k^T grad_x.
      const SurfaceIdealAtPoints id = surface_ideal_at_points<F>(t, ideal);
      ElementNodes<3> g1(3, X.cols()), g2(3, X.cols());
      surface_element_distortion_gradient<F>(t, X, id, surface_normals(t, phi1, U1), ShapeMeasure{}, ClampedDeterminant{}, g1);
      surface_element_distortion_gradient<F>(t, X, id, surface_normals(t, phi2, U2), ShapeMeasure{}, ClampedDeterminant{}, g2);
      CHECK((g1 - g2).norm() <= 1e-12 * g1.norm());
      const UVs p1 = parameter_gradient(phi1, U1, g1), p2 = parameter_gradient(phi2, U2, g2);
      for (Eigen::Index i = 0; i < X.cols(); ++i) {
        // Tangential part of grad_x recovered from either: D phi (D phi^T D phi)^{-1} grad_u.
        const Mat32 d1 = phi1.derivatives(U1.col(i)), d2 = phi2.derivatives(U2.col(i));
        const Eigen::Vector3d t1 = d1 * (d1.transpose() * d1).inverse() * p1.col(i);
        const Eigen::Vector3d t2 = d2 * (d2.transpose() * d2).inverse() * p2.col(i);
        CHECK((t1 - t2).norm() <= 1e-9 * (1 + g1.norm()));
      }
    }
  }
}

TEST_CASE_TEMPLATE("a straight-sided element congruent to its ideal scores q = 1 (remark 5.4)", C, HOM_SURFACE_CASES) {
  using F = typename C::Family;
  using N = typename C::Nodes;
  std::mt19937 rng(41);
  for (int p = 1; p <= 5; ++p) {
    const auto& t = tab<F, N>(p);
    for (int k = 0; k < 4; ++k) {
      // A random affine image of the reference element, placed in a random plane.
      Eigen::Matrix2d A = random_matrix<Eigen::Matrix2d>(rng) + 1.5 * Eigen::Matrix2d::Identity();
      if (A.determinant() < 0) A.col(0) *= -1;
      const ElementNodes<2> Y = A * reference_nodes<F, N>(p);
      const Eigen::Matrix3d R = random_rotation(rng);
      const Eigen::Vector3d s = random_matrix<Eigen::Vector3d>(rng);
      const ElementNodes<3> X = (R * embed(Y)).colwise() + s;
      // Congruent ideal: the planar element itself, elsewhere.
      const SurfaceIdealVertices<F> ideal = embed_ideal<F>(IdealVertices<F>(Y.leftCols(F::num_vertices)));
      for (const SurfaceNormals& n : {SurfaceNormals::constant(R * e3), facet_normals<F>(X)}) {
        const auto q = surface_element_quality<F>(t, X, ideal, n, ShapeMeasure{});
        CHECK(q.valid);
        CHECK(q.quality == doctest::Approx(1.0).epsilon(1e-12));
        CHECK(surface_element_quality<F>(t, X, ideal, n, OddyMeasure{}).quality == doctest::Approx(1.0).epsilon(1e-12));
        // Its own straight-sided counterpart as ideal (relative quality).
        const SurfaceIdealVertices<F> own = X.leftCols(F::num_vertices);
        CHECK(surface_element_quality<F>(t, X, own, n, ShapeMeasure{}).quality == doctest::Approx(1.0).epsilon(1e-12));
      }
    }
  }
}

TEST_CASE_TEMPLATE("elements folded or inverted with respect to the surface score q = 0", C, HOM_SURFACE_CASES) {
  using F = typename C::Family;
  using N = typename C::Nodes;
  const Cylinder cyl(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), 1.0);
  const HyperbolicParaboloid hyp;
  for (int p = 1; p <= 5; ++p) {
    CAPTURE(p);
    const auto& t = tab<F, N>(p);
    const auto& layout = node_layout<F>(p);
    const SurfaceIdealVertices<F> ideal = embed_ideal<F>(0.5 * regular_ideal_vertices<F>());
    auto on_both = [&](const UVs& U, auto&& check) {
      check(surface_element_quality<F>(t, cyl, U, ideal, ShapeMeasure{}));
      check(surface_element_quality<F>(t, cyl, U, ideal, OddyMeasure{}));
      check(surface_element_quality<F>(t, hyp, U, ideal, ShapeMeasure{}));
      check(surface_element_quality<F>(t, hyp, U, ideal, OddyMeasure{}));
    };
    const UVs U = parameter_element<F, N>(p, Eigen::Vector2d(0.2, 0.1), 0.3, 0.05);
    on_both(U, [](const ElementQuality& q) {
      CHECK(q.valid);
      CHECK(q.quality > 0.0);
    });
    // Inverted: the parameter element mirrored without renumbering (clockwise
    // with respect to S_u x S_v).
    UVs M = U;
    M.row(0) = 0.4 - M.row(0).array();
    on_both(M, [](const ElementQuality& q) {
      CHECK_FALSE(q.valid);
      CHECK(q.quality == 0.0);
      CHECK(q.max_det < 0.0);
    });
    // The valid element against the opposite orientation.
    const ElementNodes<3> X = surface_points(cyl, U);
    SurfaceNormals n = surface_normals(t, cyl, U);
    n.points *= -1.0;
    n.nodes *= -1.0;
    CHECK(surface_element_quality<F>(t, X, ideal, n, ShapeMeasure{}).quality == 0.0);
    // Folded: an edge node pulled through the element past the opposite side.
    if (p >= 2) {
      const int edge_node = layout.edge_nodes(0).front();
      const auto e = F::edges()[0];
      Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
      for (int v = 0; v < F::num_vertices; ++v) centroid += U.col(v);
      centroid /= F::num_vertices;
      UVs Z = U;
      Z.col(edge_node) += 2.5 * (centroid - 0.5 * (U.col(e[0]) + U.col(e[1])));
      on_both(Z, [](const ElementQuality& q) {
        CHECK_FALSE(q.valid);
        CHECK(q.quality == 0.0);
        CHECK(q.scaled_jacobian() < 0.0);
      });
    }
  }
}

TEST_CASE_TEMPLATE("eta_E: gradient in the node coordinates and in the nodes' (u, v) matches finite differences", C,
                   HOM_SURFACE_CASES) {
  using F = typename C::Family;
  using N = typename C::Nodes;
  const double h = 1e-6;
  const Cylinder cyl(Eigen::Vector3d::Zero(), Eigen::Vector3d(0.3, 0.0, 1.0), 0.9);
  const HyperbolicParaboloid hyp(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), 0.8, 1.1);
  const ParametricSurface wave = thesis_sigma2(2);
  auto run = [&](const auto& g, const UVs& U, const SurfaceIdealVertices<F>& ideal, const Tabulation<F>& t,
                 const auto& measure, const auto& reg) {
    const SurfaceIdealAtPoints id = surface_ideal_at_points<F>(t, ideal);
    const SurfaceNormals n = surface_normals(t, g, U);  // fixed: it only orients
    auto eta_of = [&](const UVs& V) {
      ElementNodes<3> G(3, V.cols());
      return surface_element_distortion_gradient<F>(t, surface_points(g, V), id, n, measure, reg, G);
    };
    ElementNodes<3> gx(3, U.cols());
    const double eta = surface_element_distortion_gradient<F>(t, surface_points(g, U), id, n, measure, reg, gx);
    const UVs gu = parameter_gradient(g, U, gx);
    for (Eigen::Index i = 0; i < U.cols(); ++i)
      for (int k = 0; k < 2; ++k) {
        UVs Up = U, Um = U;
        Up(k, i) += h;
        Um(k, i) -= h;
        const double fd = (eta_of(Up) - eta_of(Um)) / (2 * h);
        CHECK(std::abs(fd - gu(k, i)) <= 1e-6 * (1 + eta) * (1 + gu.cwiseAbs().maxCoeff()));
      }
    return eta;
  };
  for (int p = 1; p <= 5; ++p) {
    CAPTURE(p);
    const auto& t = tab<F, N>(p);
    const SurfaceIdealVertices<F> ideal = embed_ideal<F>(0.6 * regular_ideal_vertices<F>());
    const UVs U = parameter_element<F, N>(p, Eigen::Vector2d(0.2, -0.1), 0.3, 0.1);
    run(cyl, U, ideal, t, ShapeMeasure{}, ClampedDeterminant{});
    run(hyp, U, ideal, t, OddyMeasure{}, ClampedDeterminant{});
    run(wave, U, ideal, t, ShapeMeasure{}, ClampedDeterminant{});
    // A tangled element under the regularized determinant (eq 3.4).
    UVs M = U;
    M.row(0) = 0.4 - M.row(0).array();
    const double eta = run(hyp, M, ideal, t, ShapeMeasure{}, element_regularization());
    CHECK(std::isfinite(eta));
  }
}

// ---------------------------------------------------------------------------
// Meshes.

TEST_CASE_TEMPLATE("surface mesh quality: a planar mesh in a tilted plane has its planar statistics", C,
                   HOM_SURFACE_CASES) {
  using F = typename C::Family;
  using N = typename C::Nodes;
  std::mt19937 rng(51);
  for (int p = 1; p <= 4; ++p) {
    auto planar = elevate(structured_mesh<F, N>({3, 2}), p);
    // Curve the interior nodes a little, keep the ideal (straight-sided snapshot).
    for (int i = 0; i < planar.num_nodes(); ++i) {
      auto x = planar.node(i);
      const double bump = 0.04 * std::sin(3.0 * x[0]) * std::sin(3.0 * x[1]);
      x[1] += bump;
    }
    const Eigen::Matrix3d R = random_rotation(rng);
    const Eigen::Vector3d s = random_matrix<Eigen::Vector3d>(rng);
    Eigen::Matrix3Xd X3 = (R * embed(planar.nodes())).colwise() + s;
    Eigen::Matrix3Xd I3 = (R * embed(planar.ideal_coordinates())).colwise() + s;
    Mesh<F, N, 3> surface(p, X3, planar.elements());
    surface.set_ideal_coordinates(I3);
    for (IdealKind kind : {IdealKind::straight_sided, IdealKind::regular}) {
      const MeshQuality a = mesh_quality(planar, ShapeMeasure{}, kind);
      const MeshQuality b = surface_mesh_quality(surface, ShapeMeasure{}, kind);
      REQUIRE(a.elements.size() == b.elements.size());
      for (std::size_t e = 0; e < a.elements.size(); ++e)
        CHECK(same_distortion(a.elements[e].distortion, b.elements[e].distortion, 1e-12));
      CHECK(std::abs(a.mesh_quality - b.mesh_quality) < 1e-12);
      const Statistics sa = a.quality_statistics(), sb = b.quality_statistics();
      CHECK(std::abs(sa.min - sb.min) < 1e-12);
      CHECK(std::abs(sa.mean - sb.mean) < 1e-12);
      CHECK(sa.inverted == sb.inverted);
      CHECK(std::abs(a.scaled_jacobian_statistics().min - b.scaled_jacobian_statistics().min) < 1e-12);
      // Point-wise nodal quality as well.
      const auto& rule = quadrature_for<F, DefaultExactness>(p);
      const auto na = nodal_mesh_quality(planar, ShapeMeasure{}, kind, rule);
      const auto nb = surface_nodal_mesh_quality(surface, ShapeMeasure{}, kind, rule);
      for (std::size_t i = 0; i < na.size(); ++i) CHECK(std::abs(na[i] - nb[i]) < 1e-12);
    }
  }
}

TEST_CASE_TEMPLATE("surface mesh quality on a cylinder: surface and facet orientations agree on valid meshes", C,
                   HOM_SURFACE_CASES) {
  using F = typename C::Family;
  using N = typename C::Nodes;
  const Cylinder cyl(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), 1.0);
  for (int p = 1; p <= 4; ++p) {
    // A parameter-space mesh of [-1, 1] x [0, 1] (angle, height) mapped onto the cylinder.
    const auto param = elevate(structured_mesh<F, N>({4, 2}, typename F::Point(-1.0, 0.0), typename F::Point(1.0, 1.0)), p);
    Eigen::Matrix3Xd X(3, param.num_nodes());
    for (int i = 0; i < param.num_nodes(); ++i) X.col(i) = cyl.evaluate(param.node(i));
    Mesh<F, N, 3> mesh(p, X, param.elements());
    const auto& rule = quadrature_for<F, DefaultExactness>(p);
    const MeshQuality facet = surface_mesh_quality(mesh, ShapeMeasure{}, IdealKind::straight_sided, rule);
    const MeshQuality geo = surface_mesh_quality(mesh, cyl, param.nodes(), ShapeMeasure{}, IdealKind::straight_sided, rule);
    CHECK(facet.inverted() == 0);
    CHECK(geo.inverted() == 0);
    for (std::size_t e = 0; e < facet.elements.size(); ++e) {
      CHECK(same_distortion(facet.elements[e].distortion, geo.elements[e].distortion, 1e-12));
      CHECK(facet.elements[e].quality <= 1.0 + 1e-14);
    }
    // p = 1: the straight-sided facets are their own ideals.
    if (p == 1) CHECK(facet.quality_statistics().min == doctest::Approx(1.0).epsilon(1e-12));
    else CHECK(facet.quality_statistics().min < 1.0);
  }
}
