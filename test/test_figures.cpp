// The thesis's claims behind figures 3.4-3.6, 4.5 and D.3 (sections 3.3.1,
// 4.2.2, appendix D.2), checked on coarse grids; bench/bench_measures
// reproduces the figures themselves.
//
// Validity is cross-checked independently of the quadrature-based quality:
// an element the measures call tangled must have det D phi_P < 0 somewhere
// on a fine sample of the reference element.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <type_traits>
#include <vector>

#include <Eigen/Dense>

#include "hom/basis/lagrange.hpp"
#include "hom/measure/oddy_measure.hpp"
#include "hom/measure/regularization.hpp"
#include "hom/measure/shape_measure.hpp"
#include "hom/nodes/equispaced.hpp"
#include "hom/nodes/gauss_lobatto.hpp"
#include "hom/nodes/warp_blend.hpp"
#include "hom/quadrature/quadrature_policy.hpp"
#include "hom/quality/element_quality.hpp"
#include "hom/quality/ideal.hpp"

using namespace hom;

namespace {

constexpr double sqrt3 = std::numbers::sqrt3;

/// A planar element of the studies: the node set mapped onto the straight-sided
/// element with the given vertices, which is also its ideal.
template <class F, class N>
struct Study {
  using Family = F;
  int p;
  IdealVertices<F> ideal;
  ElementNodes<2> X0;
  const Tabulation<F>& tab;

  Study(int degree, const IdealVertices<F>& v)
      : p(degree), ideal(v), tab(tabulation<F, N>(degree, quadrature_for<F, ThesisExactness>(degree))) {
    const auto ref = N::template points<F>(p);
    X0.resize(2, static_cast<Eigen::Index>(ref.size()));
    for (std::size_t i = 0; i < ref.size(); ++i) {
      // Straight-sided map: affine on the triangle, bilinear on the square.
      Eigen::Vector2d x = Eigen::Vector2d::Zero();
      if constexpr (F::is_simplex) {
        x = v.col(0) + (v.col(1) - v.col(0)) * ref[i][0] + (v.col(2) - v.col(0)) * ref[i][1];
      } else {
        const double a = ref[i][0], b = ref[i][1];
        x = 0.25 * ((1 - a) * (1 - b) * v.col(0) + (1 + a) * (1 - b) * v.col(1) + (1 + a) * (1 + b) * v.col(2) +
                    (1 - a) * (1 + b) * v.col(3));
      }
      X0.col(i) = x;
    }
  }

  double q_shape(const ElementNodes<2>& X) const { return element_quality<F>(tab, X, ideal, ShapeMeasure{}).quality; }
  double q_oddy(const ElementNodes<2>& X) const { return element_quality<F>(tab, X, ideal, OddyMeasure{}).quality; }

  /// Smallest det D phi_P over a fine lattice of reference points (boundary included).
  double min_sampled_det(const ElementNodes<2>& X, int m = 60) const {
    std::vector<typename F::Point> pts;
    for (int j = 0; j <= m; ++j)
      for (int i = 0; i <= m; ++i) {
        typename F::Point xi;
        if constexpr (F::is_simplex) {
          if (i + j > m) continue;
          xi << double(i) / m, double(j) / m;
        } else {
          xi << -1.0 + 2.0 * i / m, -1.0 + 2.0 * j / m;
        }
        pts.push_back(xi);
      }
    const auto g = lagrange_basis<F, N>(p).gradients(pts);
    double d = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < pts.size(); ++k) {
      Eigen::Matrix2d J;
      J.col(0) = X * g[0].row(k).transpose();
      J.col(1) = X * g[1].row(k).transpose();
      d = std::min(d, J.determinant());
    }
    return d;
  }
};

IdealVertices<Simplex<2>> equilateral() { return regular_ideal_vertices<Simplex<2>>(); }

IdealVertices<Cube<2>> square() {
  IdealVertices<Cube<2>> v;
  for (int i = 0; i < 4; ++i) v.col(i) = Cube<2>::vertex(i);
  return v;
}

struct Window {
  double x0, x1, y0, y1;
};

struct Region {
  double area_shape = 0, area_oddy = 0;
  int mismatch = 0, oddy_above_shape = 0, feasible = 0;
};

/// Feasible region (q > 0) of both measures when node `node` moves over an n x n grid.
template <class S>
Region feasible_region(const S& s, int node, Window w, int n) {
  Region r;
  ElementNodes<2> X = s.X0;
  const double dx = (w.x1 - w.x0) / (n - 1), dy = (w.y1 - w.y0) / (n - 1);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      X(0, node) = w.x0 + i * dx;
      X(1, node) = w.y0 + j * dy;
      const double qs = s.q_shape(X), qo = s.q_oddy(X);
      r.area_shape += (qs > 0) * dx * dy;
      r.area_oddy += (qo > 0) * dx * dy;
      r.feasible += qs > 0;
      r.mismatch += (qs > 0) != (qo > 0);
      r.oddy_above_shape += qo > qs * (1 + 1e-12);
    }
  return r;
}

// hom's cubic triangle: node 2 = vertex x3, node 3 = edge node x4 (edge (0,1), next
// to vertex 0), node 9 = face node x10.
constexpr int vertex_x3 = 2, edge_x4 = 3, face_x10 = 9;

}  // namespace

TEST_CASE("figures: hom's equispaced cubic triangle carries the thesis's nodes x1..x10") {
  const Study<Simplex<2>, Equispaced> s(3, equilateral());
  const double thesis[10][2] = {{0, 0},           {1, 0},           {0.5, sqrt3 / 2},     {1.0 / 3, 0},
                                {2.0 / 3, 0},     {5.0 / 6, sqrt3 / 6}, {2.0 / 3, sqrt3 / 3}, {1.0 / 3, sqrt3 / 3},
                                {1.0 / 6, sqrt3 / 6}, {0.5, sqrt3 / 6}};
  const int hom_node[10] = {0, 1, 2, 3, 4, 5, 6, 8, 7, 9};
  for (int k = 0; k < 10; ++k) {
    CAPTURE(k);
    CHECK((s.X0.col(hom_node[k]) - Eigen::Vector2d(thesis[k][0], thesis[k][1])).norm() < 1e-14);
  }
}

TEST_CASE_TEMPLATE("figures: table 3.1 location 2 is the ideal (q = 1 for shape and Oddy)", N, Equispaced,
                   WarpBlend) {
  const Study<Simplex<2>, N> s(3, equilateral());
  // Equispaced: the table's coordinates; warp & blend: the node's own position.
  const bool eq = std::is_same_v<N, Equispaced>;
  const Eigen::Vector2d loc2[3] = {eq ? Eigen::Vector2d(0.5, sqrt3 / 2) : Eigen::Vector2d(s.X0.col(vertex_x3)),
                                   eq ? Eigen::Vector2d(1.0 / 3, 0) : Eigen::Vector2d(s.X0.col(edge_x4)),
                                   eq ? Eigen::Vector2d(0.5, sqrt3 / 6) : Eigen::Vector2d(s.X0.col(face_x10))};
  const int nodes[3] = {vertex_x3, edge_x4, face_x10};
  for (int k = 0; k < 3; ++k) {
    ElementNodes<2> X = s.X0;
    X.col(nodes[k]) = loc2[k];
    CHECK(s.q_shape(X) == doctest::Approx(1.0).epsilon(1e-12));
    CHECK(s.q_oddy(X) == doctest::Approx(1.0).epsilon(1e-12));
    CHECK(std::abs(s.q_shape(X) - 1.0) <= 1e-12);
    CHECK(std::abs(s.q_oddy(X) - 1.0) <= 1e-12);
  }
}

// Figures 3.4(b), (c), (e), (f): pushing the edge node x4 to y = -3/2 or 3/2 and
// the face node x10 to y = -1 or 3/2 (table 3.1, locations 1 and 3) folds the
// element; both measures give q = 0 ("all the measures detect the same
// tangling positions, where the quality achieves the zero value").
TEST_CASE_TEMPLATE("figures: table 3.1 locations 1 and 3 of the edge and face nodes are tangled", N, Equispaced,
                   WarpBlend) {
  const Study<Simplex<2>, N> s(3, equilateral());
  const struct {
    int node;
    double y;
  } moves[4] = {{edge_x4, -1.5}, {edge_x4, 1.5}, {face_x10, -1.0}, {face_x10, 1.5}};
  for (const auto& m : moves) {
    CAPTURE(m.node);
    CAPTURE(m.y);
    ElementNodes<2> X = s.X0;
    X(1, m.node) = m.y;
    CHECK(s.q_shape(X) == 0.0);
    CHECK(s.q_oddy(X) == 0.0);
    CHECK(s.min_sampled_det(X) < 0.0);  // folded, independently of the quadrature
    CHECK_FALSE(element_quality<Simplex<2>>(s.tab, X, s.ideal, ShapeMeasure{}).valid);
  }
}

// Figure 3.4(a), (d): moving the equispaced vertex x3 along x is a shear
// (x, y) -> (x + d N_2(y), y) of the ideal element (N_2 depends on lambda_2
// only), so det D phi_P stays that of the ideal and the element stays valid:
// the quality decays but never reaches 0 on x3 in [-2, 3].
TEST_CASE("figures: the equispaced vertex sweep of figure 3.4 never tangles") {
  const Study<Simplex<2>, Equispaced> s(3, equilateral());
  const double det0 = s.min_sampled_det(s.X0);
  double previous = 1.0;
  for (int k = 0; k <= 20; ++k) {
    const double x = -2.0 + 0.25 * k;
    ElementNodes<2> X = s.X0;
    X(0, vertex_x3) = x;
    CAPTURE(x);
    CHECK(s.min_sampled_det(X) == doctest::Approx(det0).epsilon(1e-10));
    const double q = s.q_shape(X);
    CHECK(q > 0.0);
    if (x >= 0.5) {
      CHECK(q <= previous + 1e-14);  // decreasing away from the ideal
      previous = q;
    }
    CHECK(s.q_oddy(X) > 0.0);
    CHECK(s.q_oddy(X) <= q);  // Oddy is the stricter measure
  }
}

TEST_CASE_TEMPLATE("figures 3.5, 3.6: shape and Oddy share the feasible region; vertex > edge > face", N, Equispaced,
                   WarpBlend) {
  const Study<Simplex<2>, N> s(3, equilateral());
  // Windows containing the edge's and the face's whole regions (checked below);
  // the equispaced vertex region is an unbounded strip, whose part in the
  // window is already larger.
  const Region v = feasible_region(s, vertex_x3, {-5.0, 6.0, -0.5, 3.5}, 41);
  const Region e = feasible_region(s, edge_x4, {-0.5, 2.0, -3.0, 1.0}, 41);
  const Region f = feasible_region(s, face_x10, {0.1, 0.9, 0.0, 0.7}, 41);
  for (const Region* r : {&v, &e, &f}) {
    CHECK(r->mismatch == 0);
    CHECK(r->oddy_above_shape == 0);
    CHECK(r->feasible > 0);
    CHECK(r->area_shape == r->area_oddy);
  }
  CHECK(v.area_shape > e.area_shape);
  CHECK(e.area_shape > f.area_shape);

  // The edge and face regions are bounded by their windows: nothing feasible on the border.
  ElementNodes<2> X = s.X0;
  for (int k = 0; k <= 40; ++k) {
    const double t = k / 40.0;
    const Eigen::Vector2d border_e[4] = {{-0.5 + 2.5 * t, -3.0}, {-0.5 + 2.5 * t, 1.0}, {-0.5, -3.0 + 4 * t},
                                         {2.0, -3.0 + 4 * t}};
    const Eigen::Vector2d border_f[4] = {{0.1 + 0.8 * t, 0.0}, {0.1 + 0.8 * t, 0.7}, {0.1, 0.7 * t}, {0.9, 0.7 * t}};
    for (int b = 0; b < 4; ++b) {
      X = s.X0;
      X.col(edge_x4) = border_e[b];
      CHECK(s.q_shape(X) == 0.0);
      X = s.X0;
      X.col(face_x10) = border_f[b];
      CHECK(s.q_shape(X) == 0.0);
    }
  }
}

TEST_CASE("figure D.3: quadrilateral of degree 2, same feasible regions, vertex > edge > face") {
  const Study<Cube<2>, GaussLobatto> s(2, square());
  CHECK(s.q_shape(s.X0) == doctest::Approx(1.0).epsilon(1e-12));
  CHECK(s.q_oddy(s.X0) == doctest::Approx(1.0).epsilon(1e-12));
  const Region v = feasible_region(s, 2, {-3.0, 6.0, -3.0, 6.0}, 41);  // vertex (1, 1)
  const Region e = feasible_region(s, 4, {-2.0, 2.0, -5.0, 0.5}, 41);  // edge node (0, -1)
  const Region f = feasible_region(s, 8, {-1.2, 1.2, -1.2, 1.2}, 41);  // centre
  for (const Region* r : {&v, &e, &f}) {
    CHECK(r->mismatch == 0);
    CHECK(r->oddy_above_shape == 0);
  }
  CHECK(v.area_shape > e.area_shape);
  CHECK(e.area_shape > f.area_shape);
  CHECK(f.area_shape > 0.0);
}

// Figure 4.5: x0 = (0, 0.5), x1 = (0, -0.5), x2 = (x, 0) as hom's vertices 0, 1, 2
// (counter-clockwise for x > 0: det [x1 - x0, x2 - x0] = x), equilateral ideal.
namespace {
Eigen::Matrix2d figure_4_5_jacobian(double x) {
  const auto I = regular_ideal_vertices<Simplex<2>>();
  Eigen::Matrix2d P, DI;
  P << 0.0, x, -1.0, -0.5;  // columns x1 - x0, x2 - x0
  DI.col(0) = I.col(1) - I.col(0);
  DI.col(1) = I.col(2) - I.col(0);
  return P * DI.inverse();
}
}  // namespace

TEST_CASE("figure 4.5: the regularized distortion has one minimum, near sqrt(3)/2, and no asymptote at 0") {
  const ShapeMeasure m;
  const RegularizedDeterminant reg{0.05};
  const int n = 2001;
  std::vector<double> xs(n), eta(n);
  for (int i = 0; i < n; ++i) {
    xs[i] = -5.0 + 10.0 * i / (n - 1);
    eta[i] = m.value(figure_4_5_jacobian(xs[i]), reg);
    REQUIRE(std::isfinite(eta[i]));
  }
  std::vector<double> minima;
  for (int i = 1; i + 1 < n; ++i)
    if (eta[i] < eta[i - 1] && eta[i] < eta[i + 1]) minima.push_back(xs[i]);
  REQUIRE(minima.size() == 1);
  CHECK(std::abs(minima[0] - sqrt3 / 2) < 0.05);

  CHECK(std::isfinite(m.value(figure_4_5_jacobian(0.0), reg)));
  for (int i = 0; i < n; ++i) {
    const double clamped = m.value(figure_4_5_jacobian(xs[i]), ClampedDeterminant{});
    CAPTURE(xs[i]);
    if (xs[i] <= 0.0)
      CHECK(std::isinf(clamped));
    else
      CHECK(std::isfinite(clamped));
  }
  // The printed eq 3.2 (|sigma|) has both minima eta = 1 at x = +-sqrt(3)/2.
  CHECK(m.value(figure_4_5_jacobian(sqrt3 / 2), AbsoluteDeterminant{}) == doctest::Approx(1.0).epsilon(1e-12));
  CHECK(m.value(figure_4_5_jacobian(-sqrt3 / 2), AbsoluteDeterminant{}) == doctest::Approx(1.0).epsilon(1e-12));
  // x > 0 is the valid (counter-clockwise) side.
  CHECK(figure_4_5_jacobian(0.3).determinant() > 0.0);
  CHECK(figure_4_5_jacobian(-0.3).determinant() < 0.0);
}
