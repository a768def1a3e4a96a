// Certified validity (issue 8): Bernstein bases (basis/bernstein.hpp), the
// Bernstein expansion of det D phi_P (quality/jacobian_bernstein.hpp) and the
// adaptive certificate (quality/certify.hpp). Every expectation is checked
// against an independent computation: hom's Lagrange basis and Jacobians, the
// quadrature-point quality, or a closed-form map whose det is known.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include <Eigen/Dense>

#include "hom/basis/bernstein.hpp"
#include "hom/basis/lagrange.hpp"
#include "hom/measure/shape_measure.hpp"
#include "hom/mesh/elevate.hpp"
#include "hom/mesh/structured.hpp"
#include "hom/nodes/equispaced.hpp"
#include "hom/nodes/gauss_lobatto.hpp"
#include "hom/nodes/warp_blend.hpp"
#include "hom/quadrature/quadrature_policy.hpp"
#include "hom/quality/certify.hpp"
#include "hom/quality/element_quality.hpp"
#include "hom/quality/jacobian_bernstein.hpp"
#include "hom/quality/mesh_quality.hpp"

using namespace hom;

namespace {

template <class F, class N>
struct Case {
  using Family = F;
  using Nodes = N;
};

#define HOM_FAMILIES Simplex<2>, Simplex<3>, Cube<2>, Cube<3>
#define HOM_CASES                                                                                           \
  Case<Simplex<2>, Equispaced>, Case<Simplex<2>, WarpBlend>, Case<Simplex<3>, WarpBlend>,                  \
      Case<Cube<2>, GaussLobatto>, Case<Cube<2>, Equispaced>, Case<Cube<3>, WarpBlend>

/// A random point of the reference element.
template <class F>
typename F::Point random_point(std::mt19937& g) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  typename F::Point x;
  if constexpr (F::is_simplex) {
    do {
      for (int a = 0; a < F::dim; ++a) x[a] = u(g);
    } while (x.sum() > 1.0);
  } else {
    for (int a = 0; a < F::dim; ++a) x[a] = 2.0 * u(g) - 1.0;
  }
  return x;
}

Eigen::VectorXd random_vector(int n, std::mt19937& g) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) v[i] = u(g);
  return v;
}

template <class F>
using Map = std::function<Eigen::Matrix<double, F::dim, 1>(const typename F::Point&)>;

/// Element nodes of the degree-p interpolant of `map` on node set N.
template <class F, class N>
ElementNodes<F::dim> nodes_of(int p, const Map<F>& map) {
  const auto ref = N::template points<F>(p);
  ElementNodes<F::dim> X(F::dim, static_cast<Eigen::Index>(ref.size()));
  for (std::size_t j = 0; j < ref.size(); ++j) X.col(j) = map(ref[j]);
  return X;
}

/// det D phi_P at x through hom's Lagrange basis (the independent reference),
/// with the coordinates relative to the first node: at p = 10 the gradients
/// of the Lagrange basis sum to hundreds in magnitude, and an offset of the
/// element from the origin would cost the reference, not the expansion, digits.
template <class F, class N>
double direct_det(int p, const ElementNodes<F::dim>& X, const typename F::Point& x) {
  const ElementNodes<F::dim> Xc = X.colwise() - X.col(0);
  const Eigen::Matrix<double, F::dim, F::dim> J = Xc * lagrange_basis<F, N>(p).gradient(x);
  return J.determinant();
}

/// A smooth, curved, valid-looking deformation of the reference element.
template <class F>
Map<F> smooth_map(double amplitude, int seed) {
  std::mt19937 g(seed);
  Eigen::Matrix<double, F::dim, F::dim> A = Eigen::Matrix<double, F::dim, F::dim>::Identity();
  for (int i = 0; i < F::dim; ++i)
    for (int j = 0; j < F::dim; ++j) A(i, j) += 0.2 * std::uniform_real_distribution<double>(-1, 1)(g);
  if (A.determinant() < 0) A.row(0) *= -1.0;
  const Eigen::Matrix<double, F::dim, 1> phase = random_vector(F::dim, g);
  return [=](const typename F::Point& x) {
    Eigen::Matrix<double, F::dim, 1> y = A * x + Eigen::Matrix<double, F::dim, 1>::Constant(2.5);
    for (int i = 0; i < F::dim; ++i) y[i] += amplitude * std::sin(1.7 * x.sum() + 2.0 * x[(i + 1) % F::dim] + phase[i]);
    return y;
  };
}

/// The vertices of the element's straight-sided ideal.
template <class F>
IdealVertices<F> vertices_of(const ElementNodes<F::dim>& X) {
  return X.leftCols(F::num_vertices);
}

}  // namespace

// ---------------------------------------------------------------------------
// Bernstein bases

TEST_CASE_TEMPLATE("bernstein: partition of unity, non-negativity, vertex coefficients are values", F, HOM_FAMILIES) {
  std::mt19937 g(1);
  for (int n = 0; n <= 7; ++n) {
    const auto& s = bernstein_space<F>(n);
    CAPTURE(n);
    CHECK(s.size() == F::num_nodes(n));  // as many as the Lagrange nodes of degree n
    const Eigen::VectorXd c = random_vector(s.size(), g);
    for (int k = 0; k < 20; ++k) {
      const auto x = random_point<F>(g);
      const Eigen::VectorXd b = s.values(x);
      CHECK(b.sum() == doctest::Approx(1.0).epsilon(1e-14));
      CHECK(b.minCoeff() >= 0.0);
      const double v = s.evaluate(c, x);  // convex combination: within the coefficients' range
      CHECK(v >= c.minCoeff() - 1e-14);
      CHECK(v <= c.maxCoeff() + 1e-14);
    }
    const auto corners = s.corners();
    for (int v = 0; v < F::num_vertices; ++v) CHECK(s.evaluate(c, F::vertex(v)) == doctest::Approx(c[corners[v]]).epsilon(1e-13));
  }
}

TEST_CASE_TEMPLATE("bernstein: products, degree elevation and derivatives are exact", F, HOM_FAMILIES) {
  std::mt19937 g(2);
  using Degree = BernsteinDegree<F>;
  // Cubes also with different degrees per axis (the entries of D phi_P).
  std::vector<std::pair<Degree, Degree>> cases = {{detail::uniform_degree<F>(2), detail::uniform_degree<F>(3)},
                                                  {detail::uniform_degree<F>(0), detail::uniform_degree<F>(4)},
                                                  {detail::uniform_degree<F>(5), detail::uniform_degree<F>(1)}};
  if constexpr (!F::is_simplex) {
    Degree a = detail::uniform_degree<F>(3), b = detail::uniform_degree<F>(2);
    a[0] = 1;
    b[F::dim - 1] = 4;
    cases.push_back({a, b});
  }
  for (const auto& [da, db] : cases) {
    const auto& sa = bernstein_space<F>(da);
    const auto& sb = bernstein_space<F>(db);
    const Eigen::VectorXd a = random_vector(sa.size(), g), b = random_vector(sb.size(), g);
    const Eigen::VectorXd ab = bernstein_product(sa, a, sb, b);
    const auto& sab = bernstein_space<F>(product_degree<F>(da, db));
    REQUIRE(ab.size() == sab.size());
    const Eigen::VectorXd up = bernstein_elevate(sa, a, detail::uniform_degree<F>(2));
    const auto& sup = bernstein_space<F>(product_degree<F>(da, detail::uniform_degree<F>(2)));
    for (int k = 0; k < 20; ++k) {
      const auto x = random_point<F>(g);
      CHECK(sab.evaluate(ab, x) == doctest::Approx(sa.evaluate(a, x) * sb.evaluate(b, x)).epsilon(1e-12));
      CHECK(sup.evaluate(up, x) == doctest::Approx(sa.evaluate(a, x)).epsilon(1e-12));
      // Derivatives against central differences.
      for (int axis = 0; axis < F::dim; ++axis) {
        if (sa.degree()[axis] == 0 || (F::is_simplex && sa.total_degree() == 0)) continue;
        const Eigen::VectorXd d = bernstein_derivative(sa, a, axis);
        const auto& sd = bernstein_space<F>(derivative_degree<F>(da, axis));
        const double h = 1e-6;
        typename F::Point xp = x, xm = x;
        xp[axis] += h;
        xm[axis] -= h;
        const double fd = (sa.evaluate(a, xp) - sa.evaluate(a, xm)) / (2 * h);
        CHECK(sd.evaluate(d, x) == doctest::Approx(fd).epsilon(1e-7).scale(1.0));
      }
    }
  }
}

TEST_CASE_TEMPLATE("bernstein: de Casteljau subdivision reproduces the polynomial on each piece", F, HOM_FAMILIES) {
  std::mt19937 g(3);
  for (int n : {1, 3, 6}) {
    const auto& s = bernstein_space<F>(n);
    const Eigen::VectorXd c = random_vector(s.size(), g);
    Eigen::VectorXd lo, hi;
    if constexpr (F::is_simplex) {
      for (int a = 0; a <= F::dim; ++a)
        for (int b = 0; b <= F::dim; ++b) {
          if (a == b) continue;
          bernstein_bisect(s, c, a, b, lo, hi);
          // Vertices of the pieces in the reference element.
          std::array<typename F::Point, F::dim + 1> va, vb;
          for (int v = 0; v <= F::dim; ++v) va[v] = vb[v] = F::vertex(v);
          const typename F::Point m = 0.5 * (F::vertex(a) + F::vertex(b));
          va[b] = m;
          vb[a] = m;
          for (int k = 0; k < 10; ++k) {
            const auto x = random_point<F>(g);  // local barycentric point of a piece
            typename F::Point ya = va[0] * (1 - x.sum()), yb = vb[0] * (1 - x.sum());
            for (int d = 0; d < F::dim; ++d) {
              ya += va[d + 1] * x[d];
              yb += vb[d + 1] * x[d];
            }
            CHECK(s.evaluate(lo, x) == doctest::Approx(s.evaluate(c, ya)).epsilon(1e-13));
            CHECK(s.evaluate(hi, x) == doctest::Approx(s.evaluate(c, yb)).epsilon(1e-13));
          }
          // The pieces' bounds are at least as tight as the parent's.
          CHECK(std::min(lo.minCoeff(), hi.minCoeff()) >= c.minCoeff() - 1e-15);
        }
    } else {
      for (int axis = 0; axis < F::dim; ++axis) {
        bernstein_bisect(s, c, axis, lo, hi);
        for (int k = 0; k < 10; ++k) {
          const auto x = random_point<F>(g);
          typename F::Point ya = x, yb = x;
          ya[axis] = (x[axis] - 1.0) / 2.0;  // [-1, 1] -> [-1, 0]
          yb[axis] = (x[axis] + 1.0) / 2.0;  // [-1, 1] -> [0, 1]
          CHECK(s.evaluate(lo, x) == doctest::Approx(s.evaluate(c, ya)).epsilon(1e-13));
          CHECK(s.evaluate(hi, x) == doctest::Approx(s.evaluate(c, yb)).epsilon(1e-13));
        }
        CHECK(std::max(lo.maxCoeff(), hi.maxCoeff()) <= c.maxCoeff() + 1e-15);
      }
    }
  }
}

TEST_CASE_TEMPLATE("bernstein: Lagrange -> Bernstein conversion reproduces the nodal interpolant", C, HOM_CASES) {
  using F = typename C::Family;
  using N = typename C::Nodes;
  std::mt19937 g(4);
  for (int p : {1, 2, 4, 7, 10}) {
    if (F::dim == 3 && p > 7) continue;
    CAPTURE(p);
    const auto& basis = lagrange_basis<F, N>(p);
    const auto& conv = lagrange_to_bernstein<F, N>(p);
    const Eigen::MatrixXd f = random_vector(basis.size(), g).transpose();
    const Eigen::VectorXd b = conv.apply(f).row(0).transpose();
    // Random nodal values make a wiggly polynomial with large Bernstein
    // coefficients at high p (equispaced nodes above all); evaluating it in
    // double costs round-off relative to them.
    const double scale = std::max(1.0, b.cwiseAbs().maxCoeff());
    for (int k = 0; k < 20; ++k) {
      const auto x = random_point<F>(g);
      CHECK(std::abs(conv.space().evaluate(b, x) - basis.value(x).dot(f.row(0).transpose())) <= 1e-13 * scale);
    }
  }
}

// ---------------------------------------------------------------------------
// det D phi_P in Bernstein form

TEST_CASE_TEMPLATE("jacobian bernstein: the expansion reproduces det D phi_P to 1e-12 relative", C, HOM_CASES) {
  using F = typename C::Family;
  using N = typename C::Nodes;
  std::mt19937 g(5);
  const std::vector<int> degrees = F::dim == 3 && !F::is_simplex ? std::vector<int>{1, 2, 4, 10}
                                                                   : std::vector<int>{1, 2, 3, 5, 8, 10};
  for (int p : degrees) {
    CAPTURE(p);
    const auto X = nodes_of<F, N>(p, smooth_map<F>(0.15, p));
    const auto& jb = jacobian_bernstein<F, N>(p);
    const auto expected = jacobian_determinant_degree<F>(p);
    CHECK(jb.space().degree() == expected);
    CHECK(expected[0] == (F::is_simplex ? F::dim * (p - 1) : F::dim * p - 1));
    const Eigen::VectorXd c = jb.coefficients(X);
    REQUIRE(c.size() == jb.space().size());
    const double scale = c.cwiseAbs().maxCoeff();
    double worst = 0.0;
    for (int k = 0; k < 40; ++k) {
      const auto x = random_point<F>(g);
      worst = std::max(worst, std::abs(jb.space().evaluate(c, x) - direct_det<F, N>(p, X, x)) / scale);
    }
    CHECK(worst <= 1e-12);
    // Vertex coefficients are det at the vertices.
    const auto corners = jb.space().corners();
    for (int v = 0; v < F::num_vertices; ++v)
      CHECK(std::abs(c[corners[v]] - direct_det<F, N>(p, X, F::vertex(v))) <= 1e-12 * scale);
  }
}

TEST_CASE_TEMPLATE("jacobian bernstein: translation and affine maps", F, HOM_FAMILIES) {
  // det of an affine map is constant: every coefficient equals it, at every
  // degree, wherever the element sits (coordinates are taken relative to a vertex).
  for (int p : {1, 4, 7}) {
    Eigen::Matrix<double, F::dim, F::dim> A = Eigen::Matrix<double, F::dim, F::dim>::Random();
    A.diagonal().array() += 3.0;
    const Eigen::Matrix<double, F::dim, 1> t = Eigen::Matrix<double, F::dim, 1>::Constant(100.0);
    const auto X = nodes_of<F, WarpBlend>(p, [&](const typename F::Point& x) { return Eigen::Matrix<double, F::dim, 1>(A * x + t); });
    const Eigen::VectorXd c = jacobian_bernstein<F, WarpBlend>(p).coefficients(X);
    CHECK((c.array() - A.determinant()).abs().maxCoeff() <= 1e-12 * std::abs(A.determinant()));
  }
}

// ---------------------------------------------------------------------------
// Certificates

TEST_CASE_TEMPLATE("certify: every element of a straight-sided mesh is certified valid at depth 0", F, HOM_FAMILIES) {
  std::mt19937 g(7);
  for (int p : {1, 3, 6}) {
    CAPTURE(p);
    auto linear = structured_mesh<F, WarpBlend>(detail::uniform_degree<F>(3));
    // Random vertex displacements of a tenth of the spacing (cubes stay convex).
    for (int i = 0; i < linear.num_nodes(); ++i) linear.node(i) += 0.1 / 3 * random_vector(F::dim, g);
    linear.reset_ideal();
    const auto mesh = elevate(linear, p);
    const auto cert = certify_mesh(mesh);
    CHECK(cert.valid == mesh.num_elements());
    CHECK(cert.max_depth == 0);
    for (const auto& e : cert.elements) CHECK(e.pieces == 1);
    CHECK(cert.min_scaled_jacobian > 0.0);
    // Simplices: affine, det constant, so the bound is the exact value 1.
    if constexpr (F::is_simplex) CHECK(cert.min_scaled_jacobian == doctest::Approx(1.0).epsilon(1e-12));
  }
}

// A fold thinner than the spacing of the quadrature points: along xi_0 the map
// is x_0 = (xi_0 - c)^3 / 3 - eps xi_0, so det D phi_P = (xi_0 - c)^2 - eps,
// negative only for |xi_0 - c| < sqrt(eps), placed in the widest gap between
// the quadrature points' xi_0 coordinates. The element is valid at every
// quadrature point and inverted between them.
TEST_CASE_TEMPLATE("certify: a fold between the quadrature points is caught", F, HOM_FAMILIES) {
  for (int p : {3, 6}) {
    CAPTURE(p);
    const auto& rule = quadrature_for<F, DefaultExactness>(p);
    std::vector<double> xs;
    for (const auto& q : rule.points) xs.push_back(q[0]);
    std::sort(xs.begin(), xs.end());
    double gap = 0.0, c = 0.0;
    for (std::size_t i = 0; i + 1 < xs.size(); ++i)
      if (xs[i + 1] - xs[i] > gap) {
        gap = xs[i + 1] - xs[i];
        c = 0.5 * (xs[i] + xs[i + 1]);
      }
    const double eps = (gap / 4) * (gap / 4);
    const Map<F> fold = [&](const typename F::Point& x) {
      Eigen::Matrix<double, F::dim, 1> y = x;
      y[0] = std::pow(x[0] - c, 3) / 3.0 - eps * x[0];
      return y;
    };
    const auto X = nodes_of<F, WarpBlend>(p, fold);
    const auto& tab = tabulation<F, WarpBlend>(p, rule);
    // The premise: the quadrature-point check calls it valid...
    REQUIRE(element_quality<F>(tab, X, vertices_of<F>(X), ShapeMeasure{}).valid);
    // ... but det < 0 at the fold.
    typename F::Point mid = F::Point::Zero();
    mid[0] = c;
    REQUIRE(direct_det<F, WarpBlend>(p, X, mid) < 0.0);

    const auto& jb = jacobian_bernstein<F, WarpBlend>(p);
    const auto cert = certify_element<F>(jb, X);
    CHECK(cert.status == Certificate::certified_invalid);
    REQUIRE(cert.invalid_point.has_value());
    const double x0 = (*cert.invalid_point)[0];
    CHECK(std::abs(x0 - c) <= std::sqrt(eps) + 1e-8);  // inside the fold
    CHECK(direct_det<F, WarpBlend>(p, X, *cert.invalid_point) <= 1e-12);
    CHECK(cert.min_scaled_jacobian < 0.0);
  }
}

// det = (xi_0 - c)^2 + delta > 0 everywhere but close to 0 near xi_0 = c:
// positive coefficients need small pieces, so a shallow limit leaves it
// undecided and a deeper one certifies it.
TEST_CASE_TEMPLATE("certify: a nearly degenerate valid element needs depth", F, HOM_FAMILIES) {
  const int p = 3;
  const double c = 0.3, delta = 1e-3;
  const Map<F> squeeze = [&](const typename F::Point& x) {
    Eigen::Matrix<double, F::dim, 1> y = x;
    y[0] = std::pow(x[0] - c, 3) / 3.0 + delta * x[0];
    return y;
  };
  const auto X = nodes_of<F, Equispaced>(p, squeeze);
  const auto& jb = jacobian_bernstein<F, Equispaced>(p);
  CertifyOptions shallow;
  shallow.max_depth = 1;
  const auto a = certify_element<F>(jb, X, shallow);
  CHECK(a.status == Certificate::undecided);
  CHECK(a.depth == 1);
  CertifyOptions deep;
  deep.max_depth = 10;
  const auto b = certify_element<F>(jb, X, deep);
  CHECK(b.status == Certificate::certified_valid);
  CHECK(b.depth > 1);
  CHECK(b.min_det_bound > 0.0);
  CHECK(b.min_det_bound <= delta + 1e-15);  // the true minimum is delta
}

namespace {

/// The equispaced / warp & blend cubic triangle of figure 3.4 on the equilateral triangle.
template <class N>
ElementNodes<2> figure_3_4_triangle() {
  const auto v = regular_ideal_vertices<Simplex<2>>();
  return nodes_of<Simplex<2>, N>(3, [&](const Eigen::Vector2d& x) {
    return Eigen::Vector2d(v.col(0) + (v.col(1) - v.col(0)) * x[0] + (v.col(2) - v.col(0)) * x[1]);
  });
}

}  // namespace

// Figure 3.4 / table 3.1: the edge node x4 (hom node 3) at y = -3/2, 3/2 and the
// face node x10 (hom node 9) at y = -1, 3/2 tangle the element; the vertex x3
// (hom node 2) moving along x is a shear with constant det (test_figures.cpp).
TEST_CASE_TEMPLATE("certify: figure 3.4 configurations", N, Equispaced, WarpBlend) {
  const auto X0 = figure_3_4_triangle<N>();
  const auto& jb = jacobian_bernstein<Simplex<2>, N>(3);
  const struct {
    int node;
    double y;
  } tangled[4] = {{3, -1.5}, {3, 1.5}, {9, -1.0}, {9, 1.5}};
  for (const auto& m : tangled) {
    CAPTURE(m.node);
    CAPTURE(m.y);
    ElementNodes<2> X = X0;
    X(1, m.node) = m.y;
    const auto cert = certify_element<Simplex<2>>(jb, X);
    CHECK(cert.status == Certificate::certified_invalid);
    REQUIRE(cert.invalid_point.has_value());
    CHECK(direct_det<Simplex<2>, N>(3, X, *cert.invalid_point) <= 1e-12);
  }
  if constexpr (std::is_same_v<N, Equispaced>) {
    for (int k = 0; k <= 20; ++k) {
      ElementNodes<2> X = X0;
      X(0, 2) = -2.0 + 0.25 * k;
      const auto cert = certify_element<Simplex<2>>(jb, X);
      CHECK(cert.status == Certificate::certified_valid);
      CHECK(cert.depth == 0);
    }
  }
}

TEST_CASE_TEMPLATE("certify: bounds hold at sampled points; the scaled-Jacobian bound is below the table's", C,
                   HOM_CASES) {
  using F = typename C::Family;
  using N = typename C::Nodes;
  std::mt19937 g(8);
  int counts[3] = {0, 0, 0};
  for (int p : {2, 4}) {
    const auto& jb = jacobian_bernstein<F, N>(p);
    const auto& tab = tabulation<F, N>(p, quadrature_for<F, DefaultExactness>(p));
    for (int trial = 0; trial < 12; ++trial) {
      // Amplitudes from gently curved to tangled.
      const auto X = nodes_of<F, N>(p, smooth_map<F>(0.05 + 0.05 * trial, 100 * p + trial));
      const auto cert = certify_element<F>(jb, X);
      ++counts[int(cert.status)];
      const auto q = element_quality<F>(tab, X, vertices_of<F>(X), ShapeMeasure{});
      CAPTURE(p);
      CAPTURE(trial);
      CHECK(cert.min_scaled_jacobian <= q.scaled_jacobian() + 1e-12);
      CHECK(cert.min_scaled_jacobian >= -1.0);
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      for (int k = 0; k < 300; ++k) {
        const double d = direct_det<F, N>(p, X, random_point<F>(g));
        lo = std::min(lo, d);
        hi = std::max(hi, d);
      }
      const double scale = std::max(std::abs(cert.min_det_bound), std::abs(cert.max_det_bound));
      CHECK(cert.min_det_bound <= lo + 1e-12 * scale);
      CHECK(cert.max_det_bound >= hi - 1e-12 * scale);
      if (cert.status == Certificate::certified_valid) {
        CHECK(cert.min_scaled_jacobian <= lo / hi + 1e-12);
        CHECK(q.valid);  // valid everywhere implies valid at the quadrature points
      }
      if (!q.valid) CHECK(cert.status == Certificate::certified_invalid);  // an attained det <= 0 exists
    }
  }
  // The sweep exercised both outcomes.
  CHECK(counts[int(Certificate::certified_valid)] > 0);
  CHECK(counts[int(Certificate::certified_invalid)] > 0);
}

TEST_CASE("certify: mesh counts, thread independence and the mesh-level bound") {
  std::mt19937 g(9);
  auto linear = structured_mesh<Simplex<3>, WarpBlend>({2, 2, 2});
  auto mesh = elevate(linear, 4);
  // Curve the interior nodes randomly: some elements stay valid, some fold.
  for (int i = 0; i < mesh.num_nodes(); ++i) mesh.node(i) += 0.04 * random_vector(3, g);
  CertifyOptions one, two;
  one.threads = 1;
  two.threads = 2;
  const auto a = certify_mesh(mesh, one), b = certify_mesh(mesh, two);
  CHECK(a.valid + a.invalid + a.undecided == mesh.num_elements());
  CHECK(a.valid == b.valid);
  CHECK(a.invalid == b.invalid);
  CHECK(a.min_scaled_jacobian == b.min_scaled_jacobian);
  double m = std::numeric_limits<double>::infinity();
  for (const auto& e : a.elements) m = std::min(m, e.min_scaled_jacobian);
  CHECK(a.min_scaled_jacobian == m);
  const auto q = mesh_quality(mesh, ShapeMeasure{});
  CHECK(a.min_scaled_jacobian <= q.scaled_jacobian_statistics().min + 1e-12);
  for (int e = 0; e < mesh.num_elements(); ++e)
    if (!q.elements[e].valid) CHECK(a.elements[e].status == Certificate::certified_invalid);
  const auto codes = a.status_codes();
  CHECK(int(codes.size()) == mesh.num_elements());
}
