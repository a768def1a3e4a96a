// Property tests of the high-order element distortion and quality (chapter 3,
// include/hom/quality/): lemma 3.1, lemma 3.2 / corollary 3.1, proposition 3.2 /
// corollary 3.5, validity detection, scaled Jacobian and volume.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include <Eigen/Dense>

#include "hom/measure/oddy_measure.hpp"
#include "hom/measure/shape_measure.hpp"
#include "hom/nodes/equispaced.hpp"
#include "hom/nodes/warp_blend.hpp"
#include "hom/quadrature/quadrature_policy.hpp"
#include "hom/quality/element_quality.hpp"
#include "hom/quality/statistics.hpp"

using namespace hom;

namespace {

template <class F, class N>
struct Case {
  using Family = F;
  using Nodes = N;
};

#define HOM_CASES                                                                                         \
  Case<Simplex<2>, Equispaced>, Case<Simplex<2>, WarpBlend>, Case<Simplex<3>, Equispaced>,                \
      Case<Simplex<3>, WarpBlend>, Case<Cube<2>, Equispaced>, Case<Cube<2>, WarpBlend>, Case<Cube<3>, Equispaced>, \
      Case<Cube<3>, WarpBlend>

template <class F, class N>
const Tabulation<F>& tab(int p) {
  return tabulation<F, N>(p, quadrature_for<F, DefaultExactness>(p));
}

// Reference nodes of the node set as a Dim x n matrix.
template <class F, class N>
ElementNodes<F::dim> reference_nodes(int p) {
  const auto pts = N::template points<F>(p);
  ElementNodes<F::dim> X(F::dim, pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) X.col(i) = pts[i];
  return X;
}

template <int D>
Eigen::Matrix<double, D, D> random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> g;
  Eigen::Matrix<double, D, D> A;
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j) A(i, j) = g(rng);
  Eigen::HouseholderQR<Eigen::Matrix<double, D, D>> qr(A);
  Eigen::Matrix<double, D, D> Q = qr.householderQ();
  if (Q.determinant() < 0) Q.col(0) *= -1;
  return Q;
}

// A smooth curving of the reference element: x + eps * (sin, cos) mix.
template <int D>
ElementNodes<D> curve(const ElementNodes<D>& X, double eps) {
  ElementNodes<D> Y = X;
  for (int i = 0; i < X.cols(); ++i)
    for (int k = 0; k < D; ++k) Y(k, i) += eps * std::sin(1.3 * X((k + 1) % D, i) + 0.7 * k) * (0.5 + X(k, i) * X(k, i));
  return Y;
}

template <class F>
IdealVertices<F> vertices_of(const ElementNodes<F::dim>& X) {
  return X.template leftCols<F::num_vertices>();
}

}  // namespace

TEST_CASE_TEMPLATE("lemma 3.1: for p = 1 the element measure is the linear measure", C, Case<Simplex<2>, WarpBlend>,
                   Case<Simplex<3>, WarpBlend>) {
  using F = typename C::Family;
  constexpr int D = F::dim;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  const auto ideal = regular_ideal_vertices<F>();
  for (int trial = 0; trial < 50; ++trial) {
    ElementNodes<D> X = reference_nodes<F, typename C::Nodes>(1);
    for (int i = 0; i < X.cols(); ++i)
      for (int k = 0; k < D; ++k) X(k, i) += u(rng);
    // Affine map: D phi_E = D phi_P (D phi_I)^{-1} is constant.
    Eigen::Matrix<double, D, D> Jp, Ji;
    for (int k = 0; k < D; ++k) {
      Jp.col(k) = X.col(k + 1) - X.col(0);
      Ji.col(k) = ideal.col(k + 1) - ideal.col(0);
    }
    const Eigen::Matrix<double, D, D> J = Jp * Ji.inverse();
    for (int m = 0; m < 2; ++m) {
      const double linear = m == 0 ? ShapeMeasure{}.value(J, ClampedDeterminant{}) : OddyMeasure{}.value(J, ClampedDeterminant{});
      const auto r = m == 0 ? element_quality<F>(tab<F, typename C::Nodes>(1), X, ideal, ShapeMeasure{})
                            : element_quality<F>(tab<F, typename C::Nodes>(1), X, ideal, OddyMeasure{});
      if (std::isfinite(linear))
        CHECK(r.distortion == doctest::Approx(linear).epsilon(1e-12));
      else
        CHECK(r.quality == 0.0);
    }
  }
}

TEST_CASE_TEMPLATE("lemma 3.2 / corollary 3.1: the ideal scores exactly 1, others eta >= 1 and q in [0,1]", C, HOM_CASES) {
  using F = typename C::Family;
  using N = typename C::Nodes;
  const int pmax = F::dim == 3 ? 8 : 10;
  std::mt19937 rng(5);
  for (int p = 1; p <= pmax; ++p) {
    const auto& t = tab<F, N>(p);
    const ElementNodes<F::dim> X = reference_nodes<F, N>(p);
    // Ideal = the element itself (relative ideal of a straight-sided element),
    // also after a rotation and scaling of the physical element alone.
    const auto Q = random_rotation<F::dim>(rng);
    const ElementNodes<F::dim> Y = 2.5 * Q * X;
    for (const auto& Z : {X, Y}) {
      const auto shape = element_quality<F>(t, Z, vertices_of<F>(X), ShapeMeasure{});
      const auto oddy = element_quality<F>(t, Z, vertices_of<F>(X), OddyMeasure{});
      CHECK(shape.distortion == doctest::Approx(1.0).epsilon(1e-12));
      CHECK(oddy.distortion == doctest::Approx(1.0).epsilon(1e-12));
      CHECK(shape.valid);
      CHECK(shape.scaled_jacobian() == doctest::Approx(1.0).epsilon(1e-10));
    }
    // Curved elements.
    for (double eps : {0.02, 0.08, 0.3}) {
      const ElementNodes<F::dim> Z = curve<F::dim>(X, eps);
      for (int m = 0; m < 2; ++m) {
        const auto r = m == 0 ? element_quality<F>(t, Z, vertices_of<F>(X), ShapeMeasure{})
                              : element_quality<F>(t, Z, vertices_of<F>(X), OddyMeasure{});
        CHECK(r.quality >= 0.0);
        CHECK(r.quality <= 1.0);
        if (r.valid) CHECK(r.distortion >= 1.0 - 1e-14);
      }
    }
  }
}

TEST_CASE_TEMPLATE("proposition 3.2 / corollary 3.5: invariance under similarity transformations", C, HOM_CASES) {
  using F = typename C::Family;
  using N = typename C::Nodes;
  constexpr int D = F::dim;
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-3, 3);
  for (int p : {2, 3, 5}) {
    const auto& t = tab<F, N>(p);
    const ElementNodes<D> X = reference_nodes<F, N>(p);
    const ElementNodes<D> Z = curve<D>(X, 0.06);
    const auto ideal = regular_ideal_vertices<F>();
    const auto base_shape = element_quality<F>(t, Z, ideal, ShapeMeasure{});
    const auto base_oddy = element_quality<F>(t, Z, ideal, OddyMeasure{});
    REQUIRE(base_shape.valid);
    for (int trial = 0; trial < 5; ++trial) {
      const auto Q = random_rotation<D>(rng);
      const double scale = std::exp(u(rng));
      Eigen::Matrix<double, D, 1> shift;
      for (int k = 0; k < D; ++k) shift[k] = 10 * u(rng);
      const ElementNodes<D> W = ((scale * Q * Z).colwise() + shift).eval();
      CHECK(element_quality<F>(t, W, ideal, ShapeMeasure{}).distortion ==
            doctest::Approx(base_shape.distortion).epsilon(1e-10));
      CHECK(element_quality<F>(t, W, ideal, OddyMeasure{}).distortion ==
            doctest::Approx(base_oddy.distortion).epsilon(1e-10));
      // A reflection: mirror the physical element and renumber its nodes by
      // the matching symmetry S of the reference element so it keeps its
      // orientation; its relative ideal follows. Then D phi_E' = R D phi_E(S xi) R^T
      // and eta_E is unchanged up to the quadrature's lack of symmetry under S,
      // made negligible with a high-degree rule.
      const auto& layout = node_layout<F>(p);
      Eigen::Matrix<double, D, D> R = Q;
      R.col(0) *= -1;
      if (R.determinant() > 0) R.col(1) *= -1;
      ElementNodes<D> V(D, X.cols());
      for (int i = 0; i < layout.size(); ++i) {
        auto l = layout.lattice(i);
        if constexpr (F::is_simplex)
          std::swap(l[0], l[1]);
        else
          l[0] = p - l[0];
        V.col(i) = R * Z.col(layout.index_of(l));
      }
      const auto& fine = tabulation<F, N>(p, quadrature_for<F, ThesisExactness>(8));
      const auto reflected = element_quality<F>(fine, V, vertices_of<F>(V), ShapeMeasure{});
      const auto original = element_quality<F>(fine, Z, vertices_of<F>(Z), ShapeMeasure{});
      CHECK(reflected.valid);
      CHECK(reflected.distortion == doctest::Approx(original.distortion).epsilon(1e-10));
    }
  }
}

TEST_CASE_TEMPLATE("folded elements get q = 0, slightly curved ones 0 < q < 1", C, HOM_CASES) {
  using F = typename C::Family;
  using N = typename C::Nodes;
  constexpr int D = F::dim;
  for (int p = 2; p <= 6; ++p) {
    const auto& t = tab<F, N>(p);
    const auto& layout = node_layout<F>(p);
    const ElementNodes<D> X = reference_nodes<F, N>(p);
    const auto ideal = vertices_of<F>(X);
    // Slightly curved: move one interior-of-edge node a little inwards.
    const int edge_node = layout.edge_nodes(0).front();
    const auto e = F::edges()[0];
    typename F::Point centroid = F::Point::Zero();
    for (int v = 0; v < F::num_vertices; ++v) centroid += F::vertex(v);
    centroid /= F::num_vertices;
    const typename F::Point inwards = centroid - 0.5 * (F::vertex(e[0]) + F::vertex(e[1]));
    ElementNodes<D> Y = X;
    Y.col(edge_node) += 0.02 * inwards / p;
    const auto slight = element_quality<F>(t, Y, ideal, ShapeMeasure{});
    CHECK(slight.valid);
    CHECK(slight.quality > 0.0);
    CHECK(slight.quality < 1.0);
    // Folded: move the same node across the element, past the opposite side
    // (figure 3.4(b): an edge node pulled through the element tangles it).
    ElementNodes<D> Z = X;
    Z.col(edge_node) += 2.5 * inwards;
    const auto folded = element_quality<F>(t, Z, ideal, ShapeMeasure{});
    CHECK_FALSE(folded.valid);
    CHECK(folded.quality == 0.0);
    CHECK(element_quality<F>(t, Z, ideal, OddyMeasure{}).quality == 0.0);
    CHECK(folded.scaled_jacobian() < 0.0);
    // A straight-sided but inverted element (mirrored without renumbering) is
    // invalid even against its own, equally inverted, relative ideal.
    ElementNodes<D> M = X;
    M.row(0) *= -1.0;
    const auto mirrored = element_quality<F>(t, M, vertices_of<F>(M), ShapeMeasure{});
    CHECK_FALSE(mirrored.valid);
    CHECK(mirrored.quality == 0.0);
  }
}

TEST_CASE_TEMPLATE("volume of a curved element is the exact integral of det D phi_P", C, HOM_CASES) {
  using F = typename C::Family;
  using N = typename C::Nodes;
  constexpr int D = F::dim;
  // The map x -> A x + b is reproduced exactly at any degree, so the volume is
  // |det A| times the reference volume; a shear-like quadratic map x_0 += c x_1^2
  // has unit Jacobian determinant everywhere.
  for (int p = 2; p <= 5; ++p) {
    const auto& t = tab<F, N>(p);
    ElementNodes<D> X = reference_nodes<F, N>(p);
    ElementNodes<D> Y = X;
    for (int i = 0; i < X.cols(); ++i) Y(0, i) += 0.3 * X(1, i) * X(1, i);
    const auto r = element_quality<F>(t, Y, vertices_of<F>(X), ShapeMeasure{});
    CHECK(r.volume == doctest::Approx(F::reference_volume()).epsilon(1e-12));
    CHECK(r.ideal_volume == doctest::Approx(F::reference_volume()).epsilon(1e-12));
    CHECK(r.relative_volume_change() < 1e-12);
    CHECK(r.min_det == doctest::Approx(1.0).epsilon(1e-10));
    CHECK(r.scaled_jacobian() == doctest::Approx(1.0).epsilon(1e-10));
    // The curved element is not ideal though.
    CHECK(r.quality < 1.0);
  }
}

TEST_CASE("statistics in table form") {
  const auto s = summarize({0.0, 0.5, 1.0, 0.5}, {true, false, false, false});
  CHECK(s.count == 4);
  CHECK(s.min == 0.0);
  CHECK(s.max == 1.0);
  CHECK(s.mean == doctest::Approx(0.5));
  CHECK(s.std_dev == doctest::Approx(std::sqrt(0.125)));
  CHECK(s.inverted == 1);
}

#include "hom/mesh/elevate.hpp"
#include "hom/mesh/structured.hpp"
#include "hom/quality/mesh_quality.hpp"

TEST_CASE_TEMPLATE("mesh quality: definitions 3.7-3.8 and the table row", F, Simplex<2>, Simplex<3>, Cube<2>, Cube<3>) {
  std::array<int, F::dim> n;
  n.fill(2);
  const int p = 3;
  auto mesh = elevate(structured_mesh<F>(n), p);
  // Straight-sided elements measured against themselves: all ideal.
  const auto ideal = mesh_quality(mesh, ShapeMeasure{});
  const auto s = ideal.quality_statistics();
  CHECK(s.count == mesh.num_elements());
  CHECK(s.min == doctest::Approx(1.0).epsilon(1e-12));
  CHECK(s.inverted == 0);
  CHECK(ideal.mesh_quality == doctest::Approx(1.0).epsilon(1e-12));
  CHECK(ideal.scaled_jacobian_statistics().min == doctest::Approx(1.0).epsilon(1e-10));
  // The same through a user-given per-element ideal equal to the straight-sided one.
  const auto user = mesh_quality(mesh, ShapeMeasure{}, mesh.straight_sided_ideal(), quadrature_for<F, DefaultExactness>(p));
  CHECK(user.quality_statistics().mean == doctest::Approx(1.0).epsilon(1e-12));
  // Absolute quality against the regular element: right-angled simplices are
  // not equilateral (q < 1), the square cells of a cube mesh are.
  const auto absolute = mesh_quality(mesh, ShapeMeasure{}, IdealKind::regular);
  if constexpr (F::is_simplex) {
    CHECK(absolute.quality_statistics().max < 1.0);
    CHECK(absolute.quality_statistics().min > 0.5);
  } else {
    CHECK(absolute.quality_statistics().min == doctest::Approx(1.0).epsilon(1e-12));
  }
  // Fold one element: pull the last (face or cell) node of element 0 far
  // away. Some element holding it folds (which one depends on the direction),
  // only elements holding it can; q_M = 0.
  const int node = mesh.elements()(mesh.nodes_per_element() - 1, 0);
  mesh.nodes().col(node).array() += 5.0;
  const auto folded = mesh_quality(mesh, ShapeMeasure{});
  CHECK(folded.inverted() >= 1);
  for (int e = 0; e < mesh.num_elements(); ++e) {
    bool holds = false;
    for (int i = 0; i < mesh.nodes_per_element(); ++i) holds = holds || mesh.elements()(i, e) == node;
    if (!holds) CHECK(folded.elements[e].valid);
  }
  CHECK(folded.mesh_quality == 0.0);
  CHECK(folded.quality_statistics().min == 0.0);
  // The point-wise nodal quality sees the fold too (the moved node's own shape
  // function has zero gradient at its node, so look at all nodes).
  const auto nodal = nodal_mesh_quality(mesh, ShapeMeasure{}, IdealKind::straight_sided, quadrature_for<F, DefaultExactness>(p));
  CHECK(*std::min_element(nodal.begin(), nodal.end()) < 0.5);
  CHECK(*std::max_element(nodal.begin(), nodal.end()) == doctest::Approx(1.0));
}

TEST_CASE("valid_ideal: det D phi_I > 0 at every vertex") {
  IdealVertices<Simplex<2>> tri;
  tri << 0, 1, 0, 0, 0, 1;
  CHECK(valid_ideal<Simplex<2>>(tri));
  tri.col(2) = Eigen::Vector2d(0.5, -0.05);  // below edge 0-1: inverted
  CHECK_FALSE(valid_ideal<Simplex<2>>(tri));
  tri.col(2) = Eigen::Vector2d(0.5, 0.0);  // on edge 0-1: flat
  CHECK_FALSE(valid_ideal<Simplex<2>>(tri));
  IdealVertices<Cube<2>> quad;  // vertices in cyclic order
  quad << 0, 2, 2, 0, 0, 0, 1, 1;
  CHECK(valid_ideal<Cube<2>>(quad));
  quad.col(2) = Eigen::Vector2d(0.5, 0.5);  // a dart: vertex 2 reflex, det < 0 there only
  CHECK_FALSE(valid_ideal<Cube<2>>(quad));
  CHECK(valid_ideal<Simplex<3>>(regular_ideal_vertices<Simplex<3>>()));
  CHECK(valid_ideal<Cube<3>>(regular_ideal_vertices<Cube<3>>()));
  // The replacement is regular (equal edges), of the element's size, at its centroid.
  const auto r = straight_sided_or_regular<Simplex<2>>(tri);
  CHECK(valid_ideal<Simplex<2>>(r));
  CHECK((r.col(0) - r.col(1)).norm() == doctest::Approx((r.col(1) - r.col(2)).norm()));
  CHECK((r.rowwise().mean() - tri.rowwise().mean()).norm() < 1e-12);
  CHECK((r.col(0) - r.col(1)).norm() > 0.5);
}

namespace {

// A quadratic map of the reference triangle whose vertex triangle is inverted
// (the third vertex lands just below edge 0-1) while the map itself keeps
// det >= 0.85 (sampled): edge 0-1 bows far down, and edges 1-2 and 2-0 dip
// below the third vertex, which becomes a convex corner. It is the P2
// Lagrange interpolant of its six node images, so a degree-2 element
// reproduces it exactly. In 3D the z coordinate is carried along.
Eigen::Vector2d crescent(double x, double y) {
  const double l0 = 1 - x - y, l1 = x, l2 = y;
  const Eigen::Vector2d v0(0, 0), v1(1, 0), v2(0.5, -0.05), m01(0.5, -1), m12(0.75, -0.3), m20(0.25, -0.3);
  return l0 * (2 * l0 - 1) * v0 + l1 * (2 * l1 - 1) * v1 + l2 * (2 * l2 - 1) * v2 + 4 * l0 * l1 * m01 +
         4 * l1 * l2 * m12 + 4 * l2 * l0 * m20;
}

}  // namespace

TEST_CASE_TEMPLATE("a valid curved element whose straight-sided counterpart is inverted is measured against the "
                   "regular element",
                   F, Simplex<2>, Simplex<3>) {
  constexpr int D = F::dim;
  using M = Mesh<F, WarpBlend, D>;
  typename M::Coordinates x(D, F::num_vertices);
  typename M::Connectivity c(F::num_vertices, 1);
  for (int v = 0; v < F::num_vertices; ++v) {
    x.col(v) = F::vertex(v);
    c(v, 0) = v;
  }
  M mesh = elevate(M(1, x, c), 2);
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    auto n = mesh.nodes().col(i);
    n.template head<2>() = crescent(n[0], n[1]);
  }
  mesh.reset_ideal();
  REQUIRE_FALSE(valid_ideal<F>(IdealVertices<F>(mesh.ideal_vertices(0))));
  CHECK(count_replaced_ideals(mesh) == 1);
  // Independent reference: against the (valid) regular element the physical
  // element is valid, as det D phi_P > 0.
  const auto regular = mesh_quality(mesh, ShapeMeasure{}, IdealKind::regular);
  REQUIRE(regular.inverted() == 0);
  // Measured against its own inverted vertex element it would be inverted;
  // the default ideal falls back to the regular element, and the shape
  // measure ignores the fallback's size and position.
  const auto own = mesh_quality(mesh, ShapeMeasure{});
  CHECK(own.inverted() == 0);
  CHECK(own.elements[0].quality == doctest::Approx(regular.elements[0].quality).epsilon(1e-10));
  CHECK(valid_ideal<F>(mesh.straight_sided_ideal().vertices(0)));
  const auto through_ideal_mesh =
      mesh_quality(mesh, ShapeMeasure{}, mesh.straight_sided_ideal(), quadrature_for<F, DefaultExactness>(2));
  CHECK(through_ideal_mesh.elements[0].quality == doctest::Approx(regular.elements[0].quality).epsilon(1e-10));
}
