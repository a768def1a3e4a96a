#pragma once
/// @file jacobi.hpp
/// Jacobi polynomials P_n^(alpha,beta) on [-1, 1], all degrees 0..n at once,
/// with first derivatives, by the three-term recurrence; orthonormal versions
/// (w.r.t. the weight (1 - x)^alpha (1 + x)^beta); and the "scaled" (homogeneous)
/// form t^n P_n(u / t) that the simplex bases use to stay free of the
/// collapsed-coordinate singularity.
///
/// Recurrence (Abramowitz & Stegun 22.7.1), with c = 2n + alpha + beta:
///
///   2(n+1)(n+alpha+beta+1) c P_{n+1} = (c+1) [ (c+2) c x + alpha^2 - beta^2 ] P_n
///                                      - 2(n+alpha)(n+beta)(c+2) P_{n-1},
///   P_0 = 1,  P_1 = ((alpha + beta + 2) x + alpha - beta) / 2,
///
/// written as P_{n+1} = (A_n x + B_n) P_n - C_n P_{n-1}. Normalisation:
///
///   h_n = int_{-1}^{1} (1-x)^alpha (1+x)^beta P_n^2 dx
///       = 2^(alpha+beta+1) / (2n+alpha+beta+1)
///         * Gamma(n+alpha+1) Gamma(n+beta+1) / (Gamma(n+alpha+beta+1) n!).
///
/// All functions take output vectors of size >= n + 1 (entry k = degree k).

#include <cassert>
#include <cmath>

#include <Eigen/Core>

namespace hom {

namespace detail {

/// Coefficients (A_n, B_n, C_n) of P_{n+1} = (A_n x + B_n) P_n - C_n P_{n-1}, n >= 1.
struct JacobiStep {
  double a, b, c;
};

inline JacobiStep jacobi_step(int n, double alpha, double beta) {
  const double ab = alpha + beta;
  const double c = 2.0 * n + ab;
  const double den = 2.0 * (n + 1) * (n + ab + 1.0) * c;
  return {(c + 1.0) * (c + 2.0) * c / den, (c + 1.0) * (alpha * alpha - beta * beta) / den,
          2.0 * (n + alpha) * (n + beta) * (c + 2.0) / den};
}

}  // namespace detail

/// Ratio h_{k+1} / h_k of consecutive squared norms (k >= 0), in a form that
/// is finite for every alpha, beta > -1 (also alpha + beta = -1).
inline double jacobi_norm_ratio(int k, double alpha, double beta) {
  const double ab = alpha + beta;
  if (k == 0) return (1.0 + alpha) * (1.0 + beta) / (ab + 3.0);
  return (2.0 * k + ab + 1.0) / (2.0 * k + ab + 3.0) * (k + 1.0 + alpha) * (k + 1.0 + beta) /
         ((k + 1.0 + ab) * (k + 1.0));
}

/// h_n = squared weighted L2 norm of P_n^(alpha,beta) on [-1, 1] (alpha, beta > -1).
/// Built as a product of ratios from h_0 so that large n does not overflow.
inline double jacobi_norm_squared(int n, double alpha, double beta) {
  const double ab = alpha + beta;
  // h_0 = 2^(a+b+1) Gamma(a+1) Gamma(b+1) / Gamma(a+b+2); for beta = 0 (every
  // use in the simplex bases) it is 2^(a+1) / (a+1), without the Gamma calls.
  double h = beta == 0.0 ? std::pow(2.0, alpha + 1.0) / (alpha + 1.0)
                         : std::pow(2.0, ab + 1.0) * std::tgamma(alpha + 1.0) * std::tgamma(beta + 1.0) /
                               std::tgamma(ab + 2.0);
  for (int k = 0; k < n; ++k) h *= jacobi_norm_ratio(k, alpha, beta);
  return h;
}

namespace detail {

/// Multiplies entry k of each given vector by 1 / sqrt(h_k), k = 0..n, in O(n).
template <class... Vectors>
void normalize_jacobi(int n, double alpha, double beta, Vectors&... v) {
  double s = 1.0 / std::sqrt(jacobi_norm_squared(0, alpha, beta));
  for (int k = 0; k <= n; ++k) {
    ((v[k] *= s), ...);
    if (k < n) s /= std::sqrt(jacobi_norm_ratio(k, alpha, beta));
  }
}

}  // namespace detail

/// p[k] = P_k^(alpha,beta)(x), k = 0..n.
inline void jacobi(int n, double alpha, double beta, double x, Eigen::Ref<Eigen::VectorXd> p) {
  assert(p.size() > n);
  p[0] = 1.0;
  if (n == 0) return;
  p[1] = 0.5 * ((alpha + beta + 2.0) * x + alpha - beta);
  for (int k = 1; k < n; ++k) {
    const auto s = detail::jacobi_step(k, alpha, beta);
    p[k + 1] = (s.a * x + s.b) * p[k] - s.c * p[k - 1];
  }
}

/// p[k] = P_k(x), dp[k] = P_k'(x), k = 0..n: the recurrence differentiated,
/// P'_{k+1} = (A x + B) P'_k + A P_k - C P'_{k-1}.
inline void jacobi(int n, double alpha, double beta, double x, Eigen::Ref<Eigen::VectorXd> p,
                   Eigen::Ref<Eigen::VectorXd> dp) {
  assert(p.size() > n && dp.size() > n);
  p[0] = 1.0;
  dp[0] = 0.0;
  if (n == 0) return;
  p[1] = 0.5 * ((alpha + beta + 2.0) * x + alpha - beta);
  dp[1] = 0.5 * (alpha + beta + 2.0);
  for (int k = 1; k < n; ++k) {
    const auto s = detail::jacobi_step(k, alpha, beta);
    p[k + 1] = (s.a * x + s.b) * p[k] - s.c * p[k - 1];
    dp[k + 1] = (s.a * x + s.b) * dp[k] + s.a * p[k] - s.c * dp[k - 1];
  }
}

/// Orthonormal Jacobi polynomials p[k] = P_k(x) / sqrt(h_k), k = 0..n:
/// int_{-1}^{1} (1-x)^alpha (1+x)^beta p_j p_k dx = delta_jk.
inline void jacobi_normalized(int n, double alpha, double beta, double x, Eigen::Ref<Eigen::VectorXd> p) {
  jacobi(n, alpha, beta, x, p);
  detail::normalize_jacobi(n, alpha, beta, p);
}

/// Orthonormal Jacobi polynomials and their derivatives.
inline void jacobi_normalized(int n, double alpha, double beta, double x, Eigen::Ref<Eigen::VectorXd> p,
                              Eigen::Ref<Eigen::VectorXd> dp) {
  jacobi(n, alpha, beta, x, p, dp);
  detail::normalize_jacobi(n, alpha, beta, p, dp);
}

/// Scaled (homogeneous) orthonormal Jacobi polynomials, values only (see below).
inline void scaled_jacobi_normalized(int n, double alpha, double beta, double u, double t,
                                     Eigen::Ref<Eigen::VectorXd> q) {
  assert(q.size() > n);
  q[0] = 1.0;
  if (n > 0) q[1] = 0.5 * ((alpha + beta + 2.0) * u + (alpha - beta) * t);
  for (int k = 1; k < n; ++k) {
    const auto s = detail::jacobi_step(k, alpha, beta);
    q[k + 1] = (s.a * u + s.b * t) * q[k] - s.c * t * t * q[k - 1];
  }
  detail::normalize_jacobi(n, alpha, beta, q);
}

/// Scaled (homogeneous) orthonormal Jacobi polynomials and their derivatives
///
///   q[k](u, t) = t^k * P_k(u / t) / sqrt(h_k),   k = 0..n,
///
/// a polynomial of degree k in (u, t), evaluated by the recurrence multiplied
/// through by t^(k+1): q_{k+1} = (A u + B t) q_k - C t^2 q_{k-1}. It is defined
/// (and smooth) at t = 0, which is what makes the collapsed-coordinate simplex
/// bases and their gradients exact at the collapsed vertex (R. C. Kirby,
/// "Singularity-free evaluation of collapsed-coordinate orthogonal
/// polynomials", ACM TOMS 37(1), 2010). du[k], dt[k] are the partial
/// derivatives in u and t.
inline void scaled_jacobi_normalized(int n, double alpha, double beta, double u, double t,
                                     Eigen::Ref<Eigen::VectorXd> q, Eigen::Ref<Eigen::VectorXd> du,
                                     Eigen::Ref<Eigen::VectorXd> dt) {
  assert(q.size() > n && du.size() > n && dt.size() > n);
  q[0] = 1.0;
  du[0] = 0.0;
  dt[0] = 0.0;
  if (n > 0) {
    q[1] = 0.5 * ((alpha + beta + 2.0) * u + (alpha - beta) * t);
    du[1] = 0.5 * (alpha + beta + 2.0);
    dt[1] = 0.5 * (alpha - beta);
  }
  for (int k = 1; k < n; ++k) {
    const auto s = detail::jacobi_step(k, alpha, beta);
    const double lin = s.a * u + s.b * t;
    const double t2 = t * t;
    q[k + 1] = lin * q[k] - s.c * t2 * q[k - 1];
    du[k + 1] = lin * du[k] + s.a * q[k] - s.c * t2 * du[k - 1];
    dt[k + 1] = lin * dt[k] + s.b * q[k] - s.c * (t2 * dt[k - 1] + 2.0 * t * q[k - 1]);
  }
  detail::normalize_jacobi(n, alpha, beta, q, du, dt);
}

}  // namespace hom
