#pragma once
/// @file gauss_jacobi.hpp
/// One-dimensional Gauss rules on [-1, 1]: Gauss–Jacobi, Gauss–Legendre and
/// Gauss–Lobatto–Legendre. They are the building blocks of hom's tensor
/// (cube) and collapsed-coordinate (simplex) rules, and their points are the
/// Gauss–Lobatto node sets.
///
/// Method (Golub & Welsch 1969): the n points of the Gauss rule for the weight
/// w(x) = (1 - x)^alpha (1 + x)^beta are the eigenvalues of the symmetric
/// tridiagonal Jacobi matrix of the orthonormal Jacobi polynomials. The
/// eigenvalues are then polished by Newton steps on P_n^(alpha,beta), and the
/// weights come from the closed formula
///
///   w_i = 2^(alpha+beta+1) Gamma(n+alpha+1) Gamma(n+beta+1)
///         / ( Gamma(n+alpha+beta+1) n! (1 - x_i^2) [P_n'(x_i)]^2 ),
///
/// which is more accurate than the squared first eigenvector components
/// (those lose relative accuracy for the small weights near the ends).
/// Monomials up to degree 2n - 1 integrate to ~1e-14 relative for n <= 40
/// (test/test_quadrature.cpp).

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

namespace hom {

/// A one-dimensional rule on [-1, 1]: sum_i weights[i] f(points[i]).
struct Rule1D {
  Eigen::VectorXd points;   ///< ascending, n entries
  Eigen::VectorXd weights;  ///< n entries, positive
};

namespace detail {

/// P_n^(alpha,beta)(x) and its derivative, standard normalisation
/// P_n(1) = binom(n + alpha, n), by the three-term recurrence.
inline std::pair<double, double> jacobi_value_and_derivative(int n, double alpha, double beta, double x) {
  if (n == 0) return {1.0, 0.0};
  const double ab = alpha + beta;
  double p0 = 1.0, d0 = 0.0;
  double p1 = 0.5 * (alpha - beta) + 0.5 * (ab + 2.0) * x;
  double d1 = 0.5 * (ab + 2.0);
  for (int k = 2; k <= n; ++k) {
    // 2k(k+a+b)(2k+a+b-2) P_k = (2k+a+b-1)[(2k+a+b)(2k+a+b-2) x + a^2 - b^2] P_{k-1}
    //                           - 2(k+a-1)(k+b-1)(2k+a+b) P_{k-2}
    const double c = 2.0 * k + ab;
    const double a1 = 2.0 * k * (k + ab) * (c - 2.0);
    const double a2 = (c - 1.0) * (alpha * alpha - beta * beta);
    const double a3 = (c - 1.0) * c * (c - 2.0);
    const double a4 = 2.0 * (k + alpha - 1.0) * (k + beta - 1.0) * c;
    const double p2 = ((a2 + a3 * x) * p1 - a4 * p0) / a1;
    const double d2 = ((a2 + a3 * x) * d1 + a3 * p1 - a4 * d0) / a1;
    p0 = p1;
    p1 = p2;
    d0 = d1;
    d1 = d2;
  }
  return {p1, d1};
}

/// Eigenvalues of the Jacobi matrix for weight (1-x)^alpha (1+x)^beta, ascending.
/// The matrix is already tridiagonal, so only the implicit QL iteration runs.
inline Eigen::VectorXd golub_welsch_points(int n, double alpha, double beta) {
  const double ab = alpha + beta;
  Eigen::VectorXd diag(n);
  Eigen::VectorXd sub(std::max(n - 1, 0));
  for (int k = 0; k < n; ++k) {
    const double c = 2.0 * k + ab;
    // Diagonal: (beta^2 - alpha^2) / ((2k+a+b)(2k+a+b+2)); the k = 0 term is
    // written in cancelled form so that alpha + beta = 0 does not divide by 0.
    diag[k] = k == 0 ? (beta - alpha) / (ab + 2.0) : (beta * beta - alpha * alpha) / (c * (c + 2.0));
  }
  for (int k = 1; k < n; ++k) {
    const double m = k;
    const double cm = 2.0 * m + ab;
    double b2;
    if (k == 1)  // cancelled form of the general expression (safe when a + b + 1 = 0)
      b2 = 4.0 * (1.0 + alpha) * (1.0 + beta) / ((ab + 2.0) * (ab + 2.0) * (ab + 3.0));
    else
      b2 = 4.0 * m * (m + alpha) * (m + beta) * (m + ab) / (cm * cm * (cm + 1.0) * (cm - 1.0));
    sub[k - 1] = std::sqrt(b2);
  }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es;
  es.computeFromTridiagonal(diag, sub, Eigen::EigenvaluesOnly);
  return es.eigenvalues();
}

}  // namespace detail

/// n-point Gauss–Jacobi rule on [-1, 1] for the weight (1-x)^alpha (1+x)^beta
/// (alpha, beta > -1): exact for polynomials of degree <= 2n - 1. Points
/// ascending, all strictly inside (-1, 1); weights positive and summing to
/// int_{-1}^{1} (1-x)^alpha (1+x)^beta dx.
inline Rule1D gauss_jacobi(int n, double alpha, double beta) {
  if (n < 1) throw std::invalid_argument("hom::gauss_jacobi: need n >= 1 points, got " + std::to_string(n));
  if (!(alpha > -1.0) || !(beta > -1.0))
    throw std::invalid_argument("hom::gauss_jacobi: need alpha, beta > -1");

  Rule1D r;
  r.points = detail::golub_welsch_points(n, alpha, beta);
  r.weights.resize(n);

  // Polish each eigenvalue by Newton on P_n; stop when the step stalls.
  for (int i = 0; i < n; ++i) {
    double x = r.points[i];
    for (int it = 0; it < 4; ++it) {
      const auto [p, dp] = detail::jacobi_value_and_derivative(n, alpha, beta, x);
      const double dx = p / dp;
      x -= dx;
      if (std::abs(dx) <= 1e-16 * std::max(1.0, std::abs(x))) break;
    }
    r.points[i] = x;
  }
  // Symmetric weight: enforce exact symmetry of the points.
  if (alpha == beta) {
    for (int i = 0; i < n / 2; ++i) {
      const double s = 0.5 * (r.points[n - 1 - i] - r.points[i]);
      r.points[i] = -s;
      r.points[n - 1 - i] = s;
    }
    if (n % 2 == 1) r.points[n / 2] = 0.0;
  }

  // c = 2^(a+b+1) Gamma(n+a+1) Gamma(n+b+1) / (Gamma(n+a+b+1) n!), built as a
  // product of ratios from its n = 1 value (finite for all alpha, beta > -1):
  // exp(lgamma(...)) would lose ~|lgamma| ulps (1e-14 at n = 30).
  double c = std::pow(2.0, alpha + beta + 1.0) * std::tgamma(alpha + 2.0) * std::tgamma(beta + 2.0) /
             std::tgamma(alpha + beta + 2.0);
  for (int k = 2; k <= n; ++k) c *= (k + alpha) * (k + beta) / ((k + alpha + beta) * k);
  for (int i = 0; i < n; ++i) {
    const double x = r.points[i];
    const double dp = detail::jacobi_value_and_derivative(n, alpha, beta, x).second;
    r.weights[i] = c / ((1.0 - x) * (1.0 + x) * dp * dp);
  }
  return r;
}

/// n-point Gauss–Legendre rule (alpha = beta = 0): exact to degree 2n - 1.
inline Rule1D gauss_legendre(int n) { return gauss_jacobi(n, 0.0, 0.0); }

/// n-point Gauss–Lobatto–Legendre rule (n >= 2): the endpoints -1, 1 and the
/// n - 2 roots of P'_{n-1}, which are the Gauss–Jacobi(1, 1) points. Exact to
/// degree 2n - 3. Weights: w_i = 2 / (n (n - 1) P_{n-1}(x_i)^2), so
/// 2 / (n (n - 1)) at the endpoints.
inline Rule1D gauss_lobatto_legendre(int n) {
  if (n < 2)
    throw std::invalid_argument("hom::gauss_lobatto_legendre: need n >= 2 points, got " + std::to_string(n));
  Rule1D r;
  r.points.resize(n);
  r.weights.resize(n);
  r.points[0] = -1.0;
  r.points[n - 1] = 1.0;
  if (n > 2) r.points.segment(1, n - 2) = gauss_jacobi(n - 2, 1.0, 1.0).points;
  const double c = 2.0 / (double(n) * (n - 1));
  for (int i = 0; i < n; ++i) {
    const double pl = detail::jacobi_value_and_derivative(n - 1, 0.0, 0.0, r.points[i]).first;
    r.weights[i] = c / (pl * pl);
  }
  return r;
}

}  // namespace hom
