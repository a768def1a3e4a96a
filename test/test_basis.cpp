// Tests of the polynomial bases (include/hom/basis/): Jacobi polynomials, the
// orthonormal modal bases, Vandermonde matrices, Lagrange shape functions and
// the Lebesgue constant estimate.
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <thread>
#include <vector>

#include <Eigen/Dense>

#include "hom/basis/jacobi.hpp"
#include "hom/basis/lagrange.hpp"
#include "hom/basis/lebesgue.hpp"
#include "hom/basis/orthonormal.hpp"
#include "hom/basis/vandermonde.hpp"
#include "hom/nodes/equispaced.hpp"
#include "hom/nodes/gauss_lobatto.hpp"
#include "hom/nodes/warp_blend.hpp"
#include "hom/quadrature/gauss.hpp"
#include "hom/quadrature/gauss_jacobi.hpp"

using namespace hom;

#define HOM_FAMILIES Simplex<2>, Simplex<3>, Cube<2>, Cube<3>

namespace {

constexpr int max_p = 10;

template <ElementFamily F>
std::vector<typename F::Point> random_points(int n, std::uint64_t seed) {
  std::mt19937_64 gen(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<typename F::Point> x;
  while (int(x.size()) < n) {
    typename F::Point y;
    for (int d = 0; d < F::dim; ++d) y[d] = u(gen);
    if constexpr (F::is_simplex) {
      if (y.sum() > 1.0) continue;
    } else {
      y = 2.0 * y.array() - 1.0;
    }
    x.push_back(y);
  }
  return x;
}

// Points where the simplex bases are most delicate: the vertices (including
// the collapsed ones), points very close to them, edge midpoints, the centroid.
template <ElementFamily F>
std::vector<typename F::Point> special_points() {
  std::vector<typename F::Point> x;
  for (int v = 0; v < F::num_vertices; ++v) {
    const auto pv = F::vertex(v);
    x.push_back(pv);
    typename F::Point c = F::Point::Zero();
    for (int w = 0; w < F::num_vertices; ++w) c += F::vertex(w);
    c /= F::num_vertices;
    x.push_back(pv + 1e-9 * (c - pv));
    x.push_back(pv + 1e-3 * (c - pv));
  }
  for (const auto& e : F::edges()) x.push_back(0.5 * (F::vertex(e[0]) + F::vertex(e[1])));
  return x;
}

// All exponent multi-indices of the polynomial space of degree p on F
// (total degree <= p on simplices, each exponent <= p on cubes).
template <ElementFamily F>
std::vector<std::array<int, F::dim>> exponents(int p) {
  std::vector<std::array<int, F::dim>> out;
  std::array<int, F::dim> a{};
  int total = 1;
  for (int d = 0; d < F::dim; ++d) total *= p + 1;
  for (int id = 0; id < total; ++id) {
    int r = id, s = 0;
    for (int d = 0; d < F::dim; ++d) {
      a[d] = r % (p + 1);
      r /= p + 1;
      s += a[d];
    }
    if (!F::is_simplex || s <= p) out.push_back(a);
  }
  return out;
}

// A polynomial sum_a c_a x^a with its exact gradient.
template <ElementFamily F>
struct Polynomial {
  std::vector<std::array<int, F::dim>> exps;
  std::vector<double> coef;

  Polynomial(int p, std::uint64_t seed) : exps(exponents<F>(p)) {
    std::mt19937_64 gen(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (std::size_t i = 0; i < exps.size(); ++i) coef.push_back(u(gen));
  }
  double value(const typename F::Point& x) const {
    double s = 0.0;
    for (std::size_t i = 0; i < exps.size(); ++i) {
      double m = coef[i];
      for (int d = 0; d < F::dim; ++d) m *= std::pow(x[d], exps[i][d]);
      s += m;
    }
    return s;
  }
  typename F::Point gradient(const typename F::Point& x) const {
    typename F::Point g = F::Point::Zero();
    for (std::size_t i = 0; i < exps.size(); ++i)
      for (int k = 0; k < F::dim; ++k) {
        if (exps[i][k] == 0) continue;
        double m = coef[i] * exps[i][k] * std::pow(x[k], exps[i][k] - 1);
        for (int d = 0; d < F::dim; ++d)
          if (d != k) m *= std::pow(x[d], exps[i][d]);
        g[k] += m;
      }
    return g;
  }
};

double binomial(double n, int k) {
  double r = 1.0;
  for (int i = 1; i <= k; ++i) r = r * (n - k + i) / i;
  return r;
}

}  // namespace

// --------------------------------------------------------------------------
// Jacobi polynomials

TEST_CASE("jacobi: orthonormal w.r.t. the Jacobi weight, P_n(1) = binom(n + alpha, n)") {
  const std::vector<std::pair<double, double>> params = {{0, 0}, {1, 0}, {2, 0}, {7, 0}, {22, 0},
                                                          {0.5, -0.5}, {-0.5, -0.5}, {3, 2}, {1.5, 0.25}};
  const int n = 16;
  for (const auto& [a, b] : params) {
    CAPTURE(a);
    CAPTURE(b);
    const Rule1D rule = gauss_jacobi(n + 2, a, b);  // exact to degree 2n + 3
    Eigen::MatrixXd P(n + 1, rule.points.size());
    for (int q = 0; q < rule.points.size(); ++q) jacobi_normalized(n, a, b, rule.points[q], P.col(q));
    const Eigen::MatrixXd G = P * rule.weights.asDiagonal() * P.transpose();
    CHECK((G - Eigen::MatrixXd::Identity(n + 1, n + 1)).cwiseAbs().maxCoeff() <= 1e-13);
    // Standard normalisation at x = 1 (Abramowitz & Stegun 22.2.1 / 22.4.1).
    Eigen::VectorXd p(n + 1);
    jacobi(n, a, b, 1.0, p);
    for (int k = 0; k <= n; ++k) CHECK(p[k] == doctest::Approx(binomial(k + a, k)).epsilon(1e-12));
    // Symmetry P_n^(a,b)(-x) = (-1)^n P_n^(b,a)(x).
    Eigen::VectorXd q(n + 1);
    jacobi(n, a, b, -0.3, p);
    jacobi(n, b, a, 0.3, q);
    for (int k = 0; k <= n; ++k) CHECK(p[k] == doctest::Approx((k % 2 ? -1.0 : 1.0) * q[k]).epsilon(1e-12));
  }
}

TEST_CASE("jacobi: Legendre closed forms and derivative identity") {
  Eigen::VectorXd p(5), dp(5);
  for (double x : {-0.9, -0.25, 0.0, 0.6, 1.0}) {
    jacobi(4, 0.0, 0.0, x, p, dp);
    CHECK(p[2] == doctest::Approx(0.5 * (3 * x * x - 1)));
    CHECK(p[3] == doctest::Approx(0.5 * (5 * x * x * x - 3 * x)));
    CHECK(p[4] == doctest::Approx((35 * std::pow(x, 4) - 30 * x * x + 3) / 8));
    CHECK(dp[4] == doctest::Approx((140 * std::pow(x, 3) - 60 * x) / 8));
  }
  // d/dx P_n^(a,b) = (n + a + b + 1) / 2 * P_{n-1}^(a+1,b+1).
  const int n = 12;
  Eigen::VectorXd v(n + 1), dv(n + 1), w(n + 1);
  for (double x : {-1.0, -0.7, 0.1, 0.95}) {
    jacobi(n, 1.5, 2.0, x, v, dv);
    jacobi(n, 2.5, 3.0, x, w);
    for (int k = 1; k <= n; ++k)
      CHECK(dv[k] == doctest::Approx(0.5 * (k + 1.5 + 2.0 + 1) * w[k - 1]).epsilon(1e-12));
  }
}

TEST_CASE("jacobi: scaled form t^n P_n(u/t) and its derivatives, also at t = 0") {
  const int n = 12;
  Eigen::VectorXd q(n + 1), qu(n + 1), qt(n + 1), pv(n + 1), q2(n + 1);
  for (double alpha : {0.0, 3.0, 9.0}) {
    for (auto [u, t] : {std::pair{0.3, 0.8}, {-0.45, 0.5}, {0.2, 0.25}, {-0.1, 1.0}}) {
      scaled_jacobi_normalized(n, alpha, 0.0, u, t, q, qu, qt);
      scaled_jacobi_normalized(n, alpha, 0.0, u, t, q2);
      jacobi_normalized(n, alpha, 0.0, u / t, pv);
      for (int k = 0; k <= n; ++k) {
        CHECK(q[k] == doctest::Approx(std::pow(t, k) * pv[k]).epsilon(1e-12));
        CHECK(q2[k] == doctest::Approx(q[k]).epsilon(1e-14));
      }
    }
    // Derivatives by central differences, at t = 0 included (where u/t is undefined).
    for (auto [u, t] : {std::pair{0.3, 0.8}, {0.4, 0.0}, {0.0, 0.0}, {-0.2, 1e-8}}) {
      scaled_jacobi_normalized(n, alpha, 0.0, u, t, q, qu, qt);
      const double h = 1e-5;
      Eigen::VectorXd a(n + 1), b(n + 1);
      scaled_jacobi_normalized(n, alpha, 0.0, u + h, t, a);
      scaled_jacobi_normalized(n, alpha, 0.0, u - h, t, b);
      const Eigen::VectorXd fdu = (a - b) / (2 * h);
      scaled_jacobi_normalized(n, alpha, 0.0, u, t + h, a);
      scaled_jacobi_normalized(n, alpha, 0.0, u, t - h, b);
      const Eigen::VectorXd fdt = (a - b) / (2 * h);
      const double scale = 1.0 + qu.cwiseAbs().maxCoeff() + qt.cwiseAbs().maxCoeff();
      CHECK((fdu - qu).cwiseAbs().maxCoeff() <= 1e-6 * scale);
      CHECK((fdt - qt).cwiseAbs().maxCoeff() <= 1e-6 * scale);
    }
  }
}

// --------------------------------------------------------------------------
// Orthonormal bases

TEST_CASE_TEMPLATE("orthonormal basis: Gram matrix is the identity", F, HOM_FAMILIES) {
  for (int p = 1; p <= max_p; ++p) {
    CAPTURE(p);
    const auto rule = gauss_rule<F>(2 * p);
    const Eigen::MatrixXd V = vandermonde<F>(p, rule.points);
    REQUIRE(V.cols() == F::num_nodes(p));
    REQUIRE(OrthonormalBasis<F>::size(p) == F::num_nodes(p));
    const Eigen::Map<const Eigen::VectorXd> w(rule.weights.data(), rule.size());
    const Eigen::MatrixXd G = V.transpose() * w.asDiagonal() * V;
    CHECK((G - Eigen::MatrixXd::Identity(G.rows(), G.cols())).cwiseAbs().maxCoeff() <= 1e-12);
  }
}

TEST_CASE_TEMPLATE("orthonormal basis: documented mode order, hierarchical in p", F, HOM_FAMILIES) {
  using B = OrthonormalBasis<F>;
  const int p = 7;
  const auto modes = B::modes(p);
  const auto deg = B::mode_degrees(p);
  REQUIRE(int(modes.size()) == B::size(p));
  CHECK(std::set(modes.begin(), modes.end()).size() == modes.size());
  if constexpr (F::is_simplex) CHECK(std::is_sorted(deg.begin(), deg.end()));  // by total degree
  const auto x = random_points<F>(5, 17);
  for (int q = 1; q < p; ++q) {
    std::map<std::array<int, F::dim>, int> index_q;
    const auto mq = B::modes(q);
    for (int j = 0; j < int(mq.size()); ++j) index_q[mq[j]] = j;
    for (const auto& xi : x) {
      Eigen::VectorXd vp(B::size(p)), vq(B::size(q));
      B::evaluate(p, xi, vp);
      B::evaluate(q, xi, vq);
      for (int j = 0; j < B::size(p); ++j) {
        auto it = index_q.find(modes[j]);
        if (it != index_q.end()) CHECK(vp[j] == doctest::Approx(vq[it->second]).epsilon(1e-13));
        // Simplices: the first size(q) modes are the degree-q basis.
        if (F::is_simplex && it != index_q.end()) CHECK(it->second == j);
      }
    }
  }
}

TEST_CASE_TEMPLATE("orthonormal basis: gradient matches finite differences, vertices included", F, HOM_FAMILIES) {
  using B = OrthonormalBasis<F>;
  auto x = special_points<F>();
  const auto r = random_points<F>(20, 3);
  x.insert(x.end(), r.begin(), r.end());
  for (int p = 1; p <= max_p; ++p) {
    CAPTURE(p);
    const int n = B::size(p);
    typename B::Gradient g(n, F::dim), g2(n, F::dim);
    Eigen::VectorXd v(n), v2(n), a(n), b(n), c(n), d(n);
    for (const auto& xi : x) {
      CAPTURE(xi.transpose());
      B::gradient(p, xi, g);
      B::evaluate_with_gradient(p, xi, v2, g2);
      B::evaluate(p, xi, v);
      CHECK((v2 - v).cwiseAbs().maxCoeff() <= 1e-14 * (1.0 + v.cwiseAbs().maxCoeff()));
      CHECK((g2 - g).cwiseAbs().maxCoeff() <= 1e-14 * (1.0 + g.cwiseAbs().maxCoeff()));
      REQUIRE(g.allFinite());
      // Fourth-order central differences; the polynomials extend smoothly
      // outside the element, so stencils may leave it at the vertices.
      const double h = 1e-4;
      for (int k = 0; k < F::dim; ++k) {
        typename F::Point e = F::Point::Zero();
        e[k] = h;
        B::evaluate(p, xi + 2 * e, a);
        B::evaluate(p, xi + e, b);
        B::evaluate(p, xi - e, c);
        B::evaluate(p, xi - 2 * e, d);
        const Eigen::VectorXd fd = (-a + 8 * b - 8 * c + d) / (12 * h);
        const double scale = 1.0 + g.cwiseAbs().maxCoeff();
        CHECK((fd - g.col(k)).cwiseAbs().maxCoeff() <= 1e-7 * scale);
      }
    }
  }
}

TEST_CASE_TEMPLATE("vandermonde_gradient agrees with OrthonormalBasis::gradient", F, HOM_FAMILIES) {
  using B = OrthonormalBasis<F>;
  const int p = 5;
  const auto x = random_points<F>(7, 11);
  const auto dv = vandermonde_gradient<F>(p, x);
  typename B::Gradient g(B::size(p), F::dim);
  for (std::size_t i = 0; i < x.size(); ++i) {
    B::gradient(p, x[i], g);
    for (int k = 0; k < F::dim; ++k) CHECK((dv[k].row(i).transpose() - g.col(k)).norm() == 0.0);
  }
}

// --------------------------------------------------------------------------
// Lagrange shape functions

namespace {

template <ElementFamily F, class Fn>
void for_each_node_set(Fn&& f) {
  f.template operator()<Equispaced>();
  f.template operator()<WarpBlend>();
  if constexpr (GaussLobatto::supports<F>) f.template operator()<GaussLobatto>();
}

}  // namespace

TEST_CASE_TEMPLATE("lagrange: Kronecker property, partition of unity, zero gradient sum", F, HOM_FAMILIES) {
  for_each_node_set<F>([]<class N>() {
    for (int p = 1; p <= max_p; ++p) {
      CAPTURE(N::name);
      CAPTURE(p);
      const LagrangeBasis<F, N> basis(p);
      REQUIRE(basis.size() == F::num_nodes(p));
      CHECK(basis.degree() == p);
      CHECK(basis.nodes() == N::template points<F>(p));
      const Eigen::MatrixXd at_nodes = basis.values(basis.nodes());
      CHECK((at_nodes - Eigen::MatrixXd::Identity(basis.size(), basis.size())).cwiseAbs().maxCoeff() <= 1e-10);

      auto x = random_points<F>(30, 100 + p);
      const auto sp = special_points<F>();
      x.insert(x.end(), sp.begin(), sp.end());
      const Eigen::MatrixXd vals = basis.values(x);
      CHECK((vals.rowwise().sum().array() - 1.0).abs().maxCoeff() <= 1e-11);
      const auto grads = basis.gradients(x);
      for (int k = 0; k < F::dim; ++k) {
        const double scale = 1.0 + grads[k].cwiseAbs().maxCoeff();
        CHECK(grads[k].rowwise().sum().cwiseAbs().maxCoeff() <= 1e-11 * scale);
      }
      // Single-point versions agree with the batched ones.
      for (std::size_t i = 0; i < x.size(); i += 7) {
        CHECK((basis.value(x[i]) - vals.row(i).transpose()).cwiseAbs().maxCoeff() <= 1e-13);
        const auto g = basis.gradient(x[i]);
        for (int k = 0; k < F::dim; ++k)
          CHECK((g.col(k) - grads[k].row(i).transpose()).cwiseAbs().maxCoeff() <=
                1e-13 * (1.0 + g.cwiseAbs().maxCoeff()));
      }
    }
  });
}

TEST_CASE_TEMPLATE("lagrange: the tensor-product path equals the Vandermonde definition", F, HOM_FAMILIES) {
  for_each_node_set<F>([]<class N>() {
    for (int p = 1; p <= 8; ++p) {
      CAPTURE(N::name);
      CAPTURE(p);
      const LagrangeBasis<F, N> basis(p);
      CHECK(basis.tensor_product() == !F::is_simplex);
      // N(x)^T = psi(x)^T V^{-1}, computed here from the definition.
      const auto x = random_points<F>(10, 40 + p);
      const Eigen::PartialPivLU<Eigen::MatrixXd> lu(basis.vandermonde_matrix().transpose());
      const Eigen::MatrixXd expected = lu.solve(vandermonde<F>(p, x).transpose()).transpose();
      CHECK((basis.values(x) - expected).cwiseAbs().maxCoeff() <= 1e-12);
      const auto dv = vandermonde_gradient<F>(p, x);
      const auto g = basis.gradients(x);
      for (int k = 0; k < F::dim; ++k) {
        const Eigen::MatrixXd dexp = lu.solve(dv[k].transpose()).transpose();
        CHECK((g[k] - dexp).cwiseAbs().maxCoeff() <= 1e-11 * (1.0 + dexp.cwiseAbs().maxCoeff()));
      }
    }
  });
}

namespace {

// Interpolates a random polynomial of degree p at the nodes and returns the
// relative errors of the interpolant and of its gradient at random points.
template <ElementFamily F, NodeSet N>
std::pair<double, double> reproduction_error(int p, std::uint64_t seed) {
  const LagrangeBasis<F, N> basis(p);
  const Polynomial<F> f(p, seed);
  Eigen::VectorXd u(basis.size());
  for (int j = 0; j < basis.size(); ++j) u[j] = f.value(basis.nodes()[j]);
  auto x = random_points<F>(40, seed + 1);
  const auto sp = special_points<F>();
  x.insert(x.end(), sp.begin(), sp.end());
  const Eigen::VectorXd interp = basis.values(x) * u;
  const auto grads = basis.gradients(x);
  double err = 0, fmax = 0, gerr = 0, gmax = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double fx = f.value(x[i]);
    const auto gx = f.gradient(x[i]);
    err = std::max(err, std::abs(interp[i] - fx));
    fmax = std::max(fmax, std::abs(fx));
    for (int k = 0; k < F::dim; ++k) {
      gerr = std::max(gerr, std::abs(grads[k].row(i).dot(u) - gx[k]));
      gmax = std::max(gmax, std::abs(gx[k]));
    }
  }
  return {err / fmax, gerr / gmax};
}

}  // namespace

TEST_CASE_TEMPLATE("lagrange: interpolation reproduces polynomials of degree p and their gradients", F,
                   HOM_FAMILIES) {
  for_each_node_set<F>([]<class N>() {
    for (int p = 1; p <= max_p; ++p) {
      CAPTURE(N::name);
      CAPTURE(p);
      const auto [err, gerr] = reproduction_error<F, N>(p, 1000 + p);
      CHECK(err <= 1e-10);
      CHECK(gerr <= 1e-9);
    }
  });
}

TEST_CASE_TEMPLATE("lagrange: quasi-optimal nodes stay usable up to p = 15", F, Simplex<2>, Simplex<3>, Cube<2>) {
  for (int p = 11; p <= 15; ++p) {
    CAPTURE(p);
    const auto [err, gerr] = reproduction_error<F, WarpBlend>(p, 77 + p);
    CHECK(err <= 1e-9);
    CHECK(gerr <= 1e-8);
  }
}

TEST_CASE("lagrange: hexahedron up to p = 12") {
  for (int p = 11; p <= 12; ++p) {
    CAPTURE(p);
    const auto [err, gerr] = reproduction_error<Cube<3>, GaussLobatto>(p, 5 + p);
    CHECK(err <= 1e-9);
    CHECK(gerr <= 1e-8);
  }
}

TEST_CASE("lagrange: linear shape functions are the barycentric coordinates") {
  const LagrangeBasis<Simplex<3>> basis(1);
  for (const auto& x : random_points<Simplex<3>>(10, 9)) {
    const Eigen::VectorXd n = basis.value(x);
    CHECK(n[0] == doctest::Approx(1.0 - x.sum()));
    for (int d = 0; d < 3; ++d) CHECK(n[d + 1] == doctest::Approx(x[d]));
  }
}

TEST_CASE("lagrange_basis caches one instance per degree, thread-safely") {
  std::vector<const LagrangeBasis<Simplex<3>, WarpBlend>*> got(8, nullptr);
  std::vector<std::thread> threads;
  for (int t = 0; t < 8; ++t)
    threads.emplace_back([&got, t] { got[t] = &lagrange_basis<Simplex<3>, WarpBlend>(6); });
  for (auto& th : threads) th.join();
  for (auto* g : got) CHECK(g == got[0]);
  CHECK(&lagrange_basis<Simplex<3>, WarpBlend>(5) != got[0]);
  CHECK(got[0]->degree() == 6);
}

// --------------------------------------------------------------------------
// Conditioning and Lebesgue constants

TEST_CASE_TEMPLATE("lebesgue constant: 1 for linear elements, >= 1 always", F, HOM_FAMILIES) {
  // Linear (and multilinear) shape functions are non-negative: sum |N_j| = sum N_j = 1.
  CHECK(lebesgue_constant<F, WarpBlend>(1) == doctest::Approx(1.0).epsilon(1e-12));
  for (int p = 2; p <= 4; ++p) CHECK(lebesgue_constant<F, WarpBlend>(p) > 1.0);
}

TEST_CASE_TEMPLATE("lebesgue constant: quasi-optimal nodes beat equispaced for p >= 4", F, HOM_FAMILIES) {
  for (int p = 4; p <= max_p; ++p) {
    CAPTURE(p);
    const double eq = lebesgue_constant<F, Equispaced>(p);
    const double wb = lebesgue_constant<F, WarpBlend>(p);
    CHECK(wb < eq);
    if (p >= 8) CHECK(wb < 0.5 * eq);  // equispaced grows exponentially
    // Conditioning (the SVD of the hexahedron's 1331 x 1331 matrix at p = 10
    // takes a second: stop at p = 7 there).
    if (p >= 6 && (F::dim == 2 || F::is_simplex || p <= 7)) {
      const double c_wb = lagrange_basis<F, WarpBlend>(p).vandermonde_condition();
      CHECK(c_wb >= 1.0);
      CHECK(c_wb < lagrange_basis<F, Equispaced>(p).vandermonde_condition());
    }
  }
}

namespace {

// Warp & blend with the blending parameter scaled by Scale / 2 (0: no blending,
// 2: the optimum, 4: twice it), to test that the tabulated alpha is optimal.
template <int Scale>
struct ScaledAlpha {
  static constexpr std::string_view name = "warp_blend_scaled_alpha";
  template <ElementFamily F>
  static constexpr bool supports = F::is_simplex;
  template <ElementFamily F>
  static std::vector<typename F::Point> points(int p) {
    const double a = F::dim == 2 ? warp_blend_alpha_triangle(p) : warp_blend_alpha_tetrahedron(p);
    return WarpBlend::points<F>(p, 0.5 * Scale * a);
  }
};

}  // namespace

TEST_CASE_TEMPLATE("warp & blend: the tabulated alpha lowers the Lebesgue constant", F, Simplex<2>, Simplex<3>) {
  // Degrees where the published optimum is far from 0 (and where there is more
  // than the single, centroid, interior node of p = 3 on the triangle).
  const std::vector<int> degrees = F::dim == 2 ? std::vector<int>{6, 8, 10} : std::vector<int>{5, 6, 8, 10};
  for (int p : degrees) {
    CAPTURE(p);
    const double opt = lebesgue_constant(LagrangeBasis<F, ScaledAlpha<2>>(p));
    CHECK(opt == doctest::Approx(lebesgue_constant<F, WarpBlend>(p)).epsilon(1e-12));
    CHECK(opt < lebesgue_constant(LagrangeBasis<F, ScaledAlpha<0>>(p)));
    CHECK(opt < lebesgue_constant(LagrangeBasis<F, ScaledAlpha<4>>(p)));
  }
}
