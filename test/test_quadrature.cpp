// Tests of the quadrature layer (include/hom/quadrature/): 1D Gauss rules,
// Gauss rules on every reference element, exactness policies and the cache.
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <thread>
#include <type_traits>
#include <vector>

#include <Eigen/Dense>

#include "hom/quadrature/gauss.hpp"
#include "hom/quadrature/gauss_jacobi.hpp"
#include "hom/quadrature/quadrature_policy.hpp"
#include "hom/quadrature/quadrature_rule.hpp"

using namespace hom;

#define HOM_FAMILIES Simplex<2>, Simplex<3>, Cube<2>, Cube<3>

namespace {

// ---------------------------------------------------------------------------
// Independent reference values (no code shared with the headers under test).

// int_{-1}^{1} (1-x)^a (1+x)^b dx = 2^(a+b+1) B(a+1, b+1).
long double jacobi_moment0(double a, double b) {
  return std::pow(2.0L, a + b + 1.0L) * std::tgamma((long double)a + 1) * std::tgamma((long double)b + 1) /
         std::tgamma((long double)a + b + 2);
}

// P_n^(a,b)(x) by the explicit sum
//   sum_s C(n+a, n-s) C(n+b, s) ((x-1)/2)^s ((x+1)/2)^(n-s),
// generalized binomials via lgamma, in long double.
long double jacobi_explicit(int n, double a, double b, long double x) {
  auto binom = [](long double top, int k) {
    return std::exp(std::lgamma(top + 1) - std::lgamma((long double)k + 1) - std::lgamma(top - k + 1));
  };
  long double s = 0;
  for (int j = 0; j <= n; ++j)
    s += binom(n + a, n - j) * binom(n + b, j) * std::pow((x - 1) / 2, j) * std::pow((x + 1) / 2, n - j);
  return s;
}

// h_n = int (P_n^(a,b))^2 (1-x)^a (1+x)^b
//     = 2^(a+b+1)/(2n+a+b+1) Gamma(n+a+1) Gamma(n+b+1) / (Gamma(n+a+b+1) n!).
long double jacobi_norm2(int n, double a, double b) {
  return std::pow(2.0L, a + b + 1) / (2 * n + a + b + 1) *
         std::exp(std::lgamma((long double)n + a + 1) + std::lgamma((long double)n + b + 1) -
                  std::lgamma((long double)n + a + b + 1) - std::lgamma((long double)n + 1));
}

long double factorial(int n) {
  long double f = 1;
  for (int i = 2; i <= n; ++i) f *= i;
  return f;
}

// Multi-indices of dimension D: total degree <= deg (simplex) or each entry <= deg (cube).
template <int D>
std::vector<std::array<int, D>> exponents(int deg, bool total) {
  std::vector<std::array<int, D>> out;
  std::array<int, D> a{};
  if constexpr (D == 2) {
    for (a[0] = 0; a[0] <= deg; ++a[0])
      for (a[1] = 0; a[1] <= deg; ++a[1])
        if (!total || a[0] + a[1] <= deg) out.push_back(a);
  } else {
    for (a[0] = 0; a[0] <= deg; ++a[0])
      for (a[1] = 0; a[1] <= deg; ++a[1])
        for (a[2] = 0; a[2] <= deg; ++a[2])
          if (!total || a[0] + a[1] + a[2] <= deg) out.push_back(a);
  }
  return out;
}

// Exact integral of x^a over the reference element, and the integral of |x^a|
// (the scale for relative errors; equal to the integral on the simplex).
template <class F>
std::pair<long double, long double> exact_monomial(const std::array<int, F::dim>& a) {
  if constexpr (F::is_simplex) {
    // Unit simplex: a! b! (c!) / (a + b (+ c) + Dim)!
    long double num = 1;
    int s = 0;
    for (int k : a) {
      num *= factorial(k);
      s += k;
    }
    const long double v = num / factorial(s + F::dim);
    return {v, v};
  } else {
    long double v = 1, m = 1;
    for (int k : a) {
      v *= k % 2 == 0 ? 2.0L / (k + 1) : 0.0L;
      m *= 2.0L / (k + 1);
    }
    return {v, m};
  }
}

// Rule applied to every monomial in `as`, via per-point power tables.
template <int D>
std::vector<long double> apply_to_monomials(const QuadratureRule<D>& rule,
                                            const std::type_identity_t<std::vector<std::array<int, D>>>& as,
                                            int maxdeg) {
  std::vector<long double> sums(as.size(), 0.0L);
  std::vector<std::array<long double, D>> pw((maxdeg + 1));
  for (int i = 0; i < rule.size(); ++i) {
    for (int d = 0; d < D; ++d) {
      pw[0][d] = 1;
      for (int k = 1; k <= maxdeg; ++k) pw[k][d] = pw[k - 1][d] * rule.points[i][d];
    }
    for (std::size_t m = 0; m < as.size(); ++m) {
      long double v = rule.weights[i];
      for (int d = 0; d < D; ++d) v *= pw[as[m][d]][d];
      sums[m] += v;
    }
  }
  return sums;
}

template <class F>
int max_tested_exactness() {
  return F::dim == 2 ? 25 : 20;
}

}  // namespace

// ---------------------------------------------------------------------------
// 1D rules

TEST_CASE("gauss_jacobi: classical small rules") {
  const Rule1D g2 = gauss_legendre(2);
  CHECK(g2.points[0] == doctest::Approx(-1.0 / std::sqrt(3.0)).epsilon(1e-15));
  CHECK(g2.points[1] == doctest::Approx(1.0 / std::sqrt(3.0)).epsilon(1e-15));
  CHECK(g2.weights[0] == doctest::Approx(1.0).epsilon(1e-15));
  const Rule1D l3 = gauss_lobatto_legendre(3);
  CHECK(l3.points[0] == -1.0);
  CHECK(l3.points[1] == doctest::Approx(0.0).epsilon(1e-15));
  CHECK(l3.points[2] == 1.0);
  CHECK(l3.weights[0] == doctest::Approx(1.0 / 3).epsilon(1e-15));
  CHECK(l3.weights[1] == doctest::Approx(4.0 / 3).epsilon(1e-15));
  const Rule1D c = gauss_jacobi(6, -0.5, -0.5);  // Gauss–Chebyshev: x_i = cos((2i-1) pi / 2n)
  for (int i = 0; i < 6; ++i) {
    CHECK(c.points[5 - i] == doctest::Approx(std::cos((2 * i + 1) * M_PI / 12)).epsilon(1e-14));
    CHECK(c.weights[i] == doctest::Approx(M_PI / 6).epsilon(1e-14));
  }
  CHECK_THROWS(gauss_jacobi(0, 0, 0));
  CHECK_THROWS(gauss_jacobi(3, -1, 0));
  CHECK_THROWS(gauss_lobatto_legendre(1));
}

TEST_CASE("gauss_jacobi: exact to degree 2n-1, not to 2n") {
  const std::vector<std::pair<double, double>> params{{0, 0}, {1, 0}, {2, 0}, {0, 1}, {1, 1},
                                                      {2, 1}, {0.5, 0.5}, {-0.5, 0.5}, {1.5, -0.3}};
  for (auto [a, b] : params) {
    const long double m0 = jacobi_moment0(a, b);
    for (int n = 1; n <= 40; ++n) {
      CAPTURE(a);
      CAPTURE(b);
      CAPTURE(n);
      const Rule1D r = gauss_jacobi(n, a, b);
      REQUIRE(r.points.size() == n);
      REQUIRE(r.weights.size() == n);
      for (int i = 0; i < n; ++i) {
        CHECK(r.weights[i] > 0);
        CHECK(r.points[i] > -1.0);
        CHECK(r.points[i] < 1.0);
        if (i > 0) CHECK(r.points[i] > r.points[i - 1]);
        if (a == b) CHECK(r.points[i] == -r.points[n - 1 - i]);
      }
      // Exactness in the basis t^k, t = (1+x)/2 (spans the same polynomials as
      // x^k, with positive integrands): int t^k w = 2^(a+b+1) B(k+b+1, a+1),
      // built by the ratio B(k+b+1, a+1) / B(k+b, a+1) = (k+b) / (k+a+b+1).
      long double exact = m0;
      for (int k = 0; k <= 2 * n - 1; ++k) {
        if (k > 0) exact *= (k + b) / (k + a + b + 1);
        long double s = 0;
        for (int i = 0; i < n; ++i) s += r.weights[i] * std::pow((1.0L + r.points[i]) / 2, k);
        CHECK(double(std::abs(s - exact) / exact) < 1e-13);
      }
      // Degree 2n: (P_n)^2 vanishes at every point but has integral h_n > 0.
      long double s = 0;
      for (int i = 0; i < n; ++i) s += r.weights[i] * std::pow(jacobi_explicit(n, a, b, r.points[i]), 2);
      CHECK(double(s / jacobi_norm2(n, a, b)) < 1e-6);
    }
  }
}

TEST_CASE("gauss_legendre and Gauss-Jacobi with integer weights: monomials x^k") {
  for (int a = 0; a <= 2; ++a)
    for (int b = 0; b <= 2; ++b) {
      // Coefficients of (1-x)^a (1+x)^b, so int x^k w = sum_j c_j int x^(k+j).
      std::vector<double> c{1.0};
      for (int i = 0; i < a + b; ++i) {
        std::vector<double> d(c.size() + 1, 0.0);
        for (std::size_t j = 0; j < c.size(); ++j) {
          d[j] += c[j];
          d[j + 1] += i < a ? -c[j] : c[j];
        }
        c = d;
      }
      for (int n = 1; n <= 40; ++n) {
        CAPTURE(a);
        CAPTURE(b);
        CAPTURE(n);
        const Rule1D r = gauss_jacobi(n, a, b);
        for (int k = 0; k <= 2 * n; ++k) {
          long double exact = 0, scale = 0;
          for (std::size_t j = 0; j < c.size(); ++j) {
            const int m = k + int(j);
            exact += m % 2 == 0 ? c[j] * 2.0L / (m + 1) : 0.0L;
            scale += std::abs(c[j]) * 2.0L / (m + 1);
          }
          long double s = 0;
          for (int i = 0; i < n; ++i) s += r.weights[i] * std::pow((long double)r.points[i], k);
          const double err = double(std::abs(s - exact) / scale);
          if (k <= 2 * n - 1)
            CHECK(err < 1e-13);
          else if (n <= 10)  // x^(2n) error ~ 4^-n: visible in double for small n
            CHECK(err > 1e-9);
        }
      }
    }
}

TEST_CASE("gauss_lobatto_legendre: endpoints, exact to 2n-3, not to 2n-2") {
  for (int n = 2; n <= 40; ++n) {
    CAPTURE(n);
    const Rule1D r = gauss_lobatto_legendre(n);
    REQUIRE(r.points.size() == n);
    CHECK(r.points[0] == -1.0);
    CHECK(r.points[n - 1] == 1.0);
    for (int i = 0; i < n; ++i) {
      CHECK(r.weights[i] > 0);
      if (i > 0) CHECK(r.points[i] > r.points[i - 1]);
      CHECK(r.points[i] == -r.points[n - 1 - i]);
    }
    CHECK(r.weights[0] == doctest::Approx(2.0 / (n * (n - 1.0))).epsilon(1e-14));
    for (int k = 0; k <= 2 * n - 2; ++k) {
      long double s = 0;
      for (int i = 0; i < n; ++i) s += r.weights[i] * std::pow((long double)r.points[i], k);
      const long double exact = k % 2 == 0 ? 2.0L / (k + 1) : 0.0L;
      const double err = double(std::abs(s - exact) / (2.0L / (k + 1)));
      if (k <= 2 * n - 3)
        CHECK(err < 1e-13);
      else if (n <= 10)
        CHECK(err > 1e-9);
    }
    // Degree 2n-2: (1-x^2) (P^(1,1)_{n-2})^2 vanishes at every GLL point.
    long double s = 0;
    for (int i = 0; i < n; ++i) {
      const long double x = r.points[i];
      s += r.weights[i] * (1 - x * x) * std::pow(jacobi_explicit(n - 2, 1, 1, x), 2);
    }
    CHECK(double(s / jacobi_norm2(n - 2, 1, 1)) < 1e-6);
  }
}

// ---------------------------------------------------------------------------
// Rules on reference elements

TEST_CASE_TEMPLATE("gauss_rule: positive weights, interior points, volume", F, HOM_FAMILIES) {
  for (int e = 0; e <= max_tested_exactness<F>(); ++e) {
    CAPTURE(e);
    const QuadratureRule<F::dim> rule = gauss_rule<F>(e);
    const int n = (e + 2) / 2;  // ceil((e+1)/2)
    CHECK(rule.size() == (F::dim == 2 ? n * n : n * n * n));
    CHECK(int(rule.points.size()) == rule.size());
    CHECK(rule.exactness >= e);
    CHECK(rule.exactness == 2 * n - 1);
    CHECK(!rule.name.empty());
    double sum = 0;
    for (int i = 0; i < rule.size(); ++i) {
      CHECK(rule.weights[i] > 0);
      sum += rule.weights[i];
      const auto& x = rule.points[i];
      if constexpr (F::is_simplex) {
        CHECK(x.minCoeff() > 0);
        CHECK(x.sum() < 1);
      } else {
        CHECK(x.cwiseAbs().maxCoeff() < 1);
      }
    }
    CHECK(sum == doctest::Approx(F::reference_volume()).epsilon(1e-14));
  }
  CHECK_THROWS(gauss_rule<F>(-1));
}

TEST_CASE_TEMPLATE("gauss_rule: every monomial up to the exactness is exact", F, HOM_FAMILIES) {
  constexpr int D = F::dim;
  for (int e = 0; e <= max_tested_exactness<F>(); ++e) {
    CAPTURE(e);
    const QuadratureRule<D> rule = gauss_rule<F>(e);
    const auto as = exponents<D>(e, F::is_simplex);
    const auto sums = apply_to_monomials(rule, as, e);
    for (std::size_t m = 0; m < as.size(); ++m) {
      const auto [exact, scale] = exact_monomial<F>(as[m]);
      CAPTURE(as[m][0]);
      CAPTURE(as[m][1]);
      CHECK(double(std::abs(sums[m] - exact) / scale) < 1e-13);
    }
  }
}

TEST_CASE_TEMPLATE("gauss_rule: not exact one degree beyond", F, HOM_FAMILIES) {
  constexpr int D = F::dim;
  for (int e = 0; e <= max_tested_exactness<F>(); ++e) {
    CAPTURE(e);
    const QuadratureRule<D> rule = gauss_rule<F>(e);
    const int n = (rule.exactness + 1) / 2;
    const int deg = rule.exactness + 1;  // = 2n
    // Monomials of degree 2n (total for simplices; per axis for cubes): the
    // worst one's error is visible in double while it is not swamped by the
    // 4^-n (cube) or 16^-n (simplex, shifted to [0, 1]) decay of the error.
    const bool visible = F::is_simplex ? n <= 4 : n <= 8;
    if (visible) {
      std::vector<std::array<int, D>> as;
      for (const auto& a : exponents<D>(deg, F::is_simplex)) {
        int s = 0, mx = 0;
        for (int k : a) {
          s += k;
          mx = std::max(mx, k);
        }
        if ((F::is_simplex && s == deg) || (!F::is_simplex && mx == deg)) as.push_back(a);
      }
      const auto sums = apply_to_monomials(rule, as, deg);
      double worst = 0;
      for (std::size_t m = 0; m < as.size(); ++m) {
        const auto [exact, scale] = exact_monomial<F>(as[m]);
        worst = std::max(worst, double(std::abs(sums[m] - exact) / scale));
      }
      CHECK(worst > 1e-9);
    }
    // Every exactness: a degree-2n polynomial that vanishes at all the points.
    // Simplex: (P_n^(alpha,0)(2t-1))^2 in the last coordinate t, alpha = Dim-1,
    //   int = c 2^(-alpha-1) h_n with int_simplex g(t) = c int_0^1 g(t)(1-t)^alpha dt,
    //   c = 1 (triangle), 1/2 (tetrahedron).
    // Cube: (P_n(x))^2 in the first coordinate, int = 2^(Dim-1) 2/(2n+1).
    long double s = 0, exact;
    if constexpr (F::is_simplex) {
      const double alpha = D - 1;
      for (int i = 0; i < rule.size(); ++i)
        s += rule.weights[i] * std::pow(jacobi_explicit(n, alpha, 0, 2.0L * rule.points[i][D - 1] - 1), 2);
      exact = (D == 2 ? 1.0L : 0.5L) * std::pow(2.0L, -alpha - 1) * jacobi_norm2(n, alpha, 0);
    } else {
      for (int i = 0; i < rule.size(); ++i)
        s += rule.weights[i] * std::pow(jacobi_explicit(n, 0, 0, rule.points[i][0]), 2);
      exact = std::pow(2.0L, D - 1) * 2.0L / (2 * n + 1);
    }
    CHECK(double(std::abs(s - exact) / exact) > 0.999);
  }
}

// ---------------------------------------------------------------------------
// Policies and the cache

namespace {

// det D phi for phi(x) = x + sum_a c_{i,a} x^a over a degree-p polynomial space
// (total degree for simplices, per-axis degree for cubes), random c.
template <class F>
struct RandomMap {
  static constexpr int D = F::dim;
  std::vector<std::array<int, D>> as;
  std::vector<Eigen::Matrix<double, D, 1>> coef;  // one vector per monomial

  RandomMap(int p, std::mt19937& rng) : as(exponents<D>(p, F::is_simplex)) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (std::size_t m = 0; m < as.size(); ++m) {
      Eigen::Matrix<double, D, 1> c;
      for (int d = 0; d < D; ++d) c[d] = 0.3 * u(rng) / as.size();
      coef.push_back(c);
    }
  }

  double det(const Eigen::Matrix<double, D, 1>& x) const { return jacobian(x).determinant(); }

  Eigen::Matrix<double, D, D> jacobian(const Eigen::Matrix<double, D, 1>& x) const {
    Eigen::Matrix<double, D, D> J = Eigen::Matrix<double, D, D>::Identity();
    for (std::size_t m = 0; m < as.size(); ++m)
      for (int j = 0; j < D; ++j) {
        if (as[m][j] == 0) continue;
        double v = as[m][j];
        for (int d = 0; d < D; ++d) v *= std::pow(x[d], d == j ? as[m][d] - 1 : as[m][d]);
        J.col(j) += v * coef[m];
      }
    return J;
  }
};

template <int D, class G>
double integrate(const QuadratureRule<D>& rule, G&& g) {
  double s = 0;
  for (int i = 0; i < rule.size(); ++i) s += rule.weights[i] * g(rule.points[i]);
  return s;
}

}  // namespace

TEST_CASE_TEMPLATE("policies: documented degrees and what they integrate", F, HOM_FAMILIES) {
  static_assert(QuadraturePolicy<ThesisExactness>);
  static_assert(QuadraturePolicy<DefaultExactness>);
  static_assert(QuadraturePolicy<ReducedExactness>);
  std::mt19937 rng(12345);
  const int pmax = F::dim == 2 ? 6 : 4;
  for (int p = 1; p <= pmax; ++p) {
    CAPTURE(p);
    const int thesis = ThesisExactness::exactness<F>(p);
    const int dflt = DefaultExactness::exactness<F>(p);
    if constexpr (F::is_simplex) CHECK(thesis == 6 * p - 3);  // thesis sec 3.1.3
    CHECK(dflt <= thesis);
    CHECK(dflt >= 1);

    const auto& rt = quadrature_for<F, ThesisExactness>(p);
    const auto& rd = quadrature_for<F>(p);  // DefaultExactness
    const auto& rr = quadrature_for<F, ReducedExactness>(p);
    CHECK(rt.exactness >= thesis);
    CHECK(rd.exactness >= dflt);
    CHECK(rr.exactness >= ReducedExactness::exactness<F>(p));
    CHECK(rr.size() <= rd.size());
    // p + 1 points per direction (collapsed Gauss-Jacobi or tensor Gauss).
    CHECK(rr.size() == int(std::pow(p + 1, F::dim)));

    // Reference: a rule far beyond the degree of (det D phi)^2.
    const int det_degree = F::is_simplex ? F::dim * (p - 1) : F::dim * p - 1;
    const auto ref = gauss_rule<F>(2 * det_degree + 6);
    for (int trial = 0; trial < 3; ++trial) {
      const RandomMap<F> map(p, rng);
      auto det = [&](const auto& x) { return map.det(x); };
      auto det2 = [&](const auto& x) { return std::pow(map.det(x), 2); };
      // Thesis policy integrates (det D phi)^2 exactly; the default, det D phi.
      CHECK(integrate(rt, det2) == doctest::Approx(integrate(ref, det2)).epsilon(1e-12));
      CHECK(integrate(rd, det) == doctest::Approx(integrate(ref, det)).epsilon(1e-12));
      // The reduced policy integrates |D phi|^2, the shape measure's numerator.
      auto frobenius2 = [&](const auto& x) { return map.jacobian(x).squaredNorm(); };
      CHECK(integrate(rr, frobenius2) == doctest::Approx(integrate(ref, frobenius2)).epsilon(1e-12));
    }
  }
}

TEST_CASE_TEMPLATE("quadrature_for: cached, shared, thread-safe", F, HOM_FAMILIES) {
  const auto* a = &quadrature_for<F, ThesisExactness>(3);
  const auto* b = &quadrature_for<F, ThesisExactness>(3);
  CHECK(a == b);
  CHECK(&cached_gauss_rule<F>(ThesisExactness::exactness<F>(3)) == a);

  // Many threads asking for new degrees at once get one rule per degree.
  constexpr int threads = 8;
  std::vector<std::array<const QuadratureRule<F::dim>*, 6>> seen(threads);
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t)
    pool.emplace_back([&seen, t] {
      for (int k = 0; k < 6; ++k) seen[t][k] = &cached_gauss_rule<F>(30 + (k + t) % 6);
    });
  for (auto& th : pool) th.join();
  for (int t = 0; t < threads; ++t)
    for (int k = 0; k < 6; ++k) {
      CHECK(seen[t][k] == seen[0][(k + t) % 6]);
      CHECK(seen[t][k]->exactness >= 30 + (k + t) % 6);
    }
}
