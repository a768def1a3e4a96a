#pragma once
/// @file regularization.hpp
/// Regularization policies of the determinant sigma = det J that enters the
/// denominator of the Jacobian-based distortion measures (section 3.1.1).
///
/// A distortion measure never divides by sigma itself but by a policy's
/// reg(sigma) >= 0, and reads the policy's first and second derivatives for
/// its own gradient and Hessian (chain rule through sigma, d sigma / dJ = cof J).
///
/// Concept DeterminantRegularization. Required members of a (const) policy r:
///   - `r.value(s) -> double`: the regularized determinant, >= 0, non-decreasing in s;
///     a measure is +infinity where it is 0;
///   - `r.jet(s) -> DeterminantJet`: value, first and second derivative in s at once
///     (one square root instead of three on the hot path).
/// Optional, used by the optimizer's batched point loops when present:
///   - `r.first_jet<W>(s, v, d)`: value and first derivative in W lanes
///     (double[W] arrays, point_lanes.hpp).
/// Models:
///   - RegularizedDeterminant{delta}: sigma_delta, eq 3.4 (optimization, untangling);
///   - ClampedDeterminant: sigma_0, eq 3.8 (validation: q = 0 for sigma <= 0);
///   - AbsoluteDeterminant: |sigma|, eq 3.2 exactly as printed (only to reproduce
///     figure 4.5(a)/(c), where the unregularized measure has a second, inverted,
///     minimum at x = -sqrt(3)/2; never use it to validate a mesh).

#include <algorithm>
#include <cmath>
#include <concepts>
#include <limits>

#include <Eigen/Core>

#include "hom/detail/point_lanes.hpp"

namespace hom {

/// A regularized determinant and its first two derivatives at one sigma.
struct DeterminantJet {
  double value;   ///< reg(sigma)
  double first;   ///< reg'(sigma)
  double second;  ///< reg''(sigma)
};

template <class Reg>
concept DeterminantRegularization = requires(const Reg& reg, double sigma) {
  { reg.value(sigma) } -> std::same_as<double>;
  { reg.jet(sigma) } -> std::same_as<DeterminantJet>;
};

/// sigma_delta(s) = (s + sqrt(s^2 + 4 delta^2)) / 2, eq 3.4 (Escobar et al. 2003).
///
/// For delta > 0 it is smooth, strictly increasing, sigma_delta(0) = delta,
/// sigma_delta(s) -> 0 as s -> -inf and sigma_delta(s) - s -> 0 as s -> +inf,
/// so a measure using it has no asymptote at sigma = 0 and an optimizer can
/// leave an inverted configuration (section 4.2.1). delta = 0 gives sigma_0.
///
/// Evaluated without cancellation: with r = sqrt(s^2 + 4 delta^2),
///   sigma_delta  = (s + r) / 2            for s >= 0,
///                = 2 delta^2 / (r - s)    for s < 0   (same number, no s + r cancellation),
///   sigma_delta' = sigma_delta / r        (= (1 + s/r) / 2),
///   sigma_delta''= 2 delta^2 / r^3.
///
/// delta is in the units of the sigma the measure sees, which in hom is always
/// det(D phi_E) (the Jacobian measured relative to the ideal element, sigma = 1
/// at the ideal). Use element_regularization() for the thesis's choice of delta.
struct RegularizedDeterminant {
  double delta = 0.0;  ///< >= 0

  [[nodiscard]] double value(double s) const {
    const double r = std::hypot(s, 2.0 * delta);
    return s >= 0.0 ? 0.5 * (s + r) : 2.0 * delta * delta / (r - s);
  }
  [[nodiscard]] double derivative(double s) const { return jet(s).first; }
  [[nodiscard]] double second_derivative(double s) const { return jet(s).second; }

  [[nodiscard]] DeterminantJet jet(double s) const {
    const double r = std::hypot(s, 2.0 * delta);
    // delta = 0 and s = 0: sigma_0 has a kink here; the measure is +inf anyway.
    if (r == 0.0) return {0.0, 0.5, 0.0};
    const double v = s >= 0.0 ? 0.5 * (s + r) : 2.0 * delta * delta / (r - s);
    return {v, v / r, 2.0 * delta * delta / (r * r * r)};
  }

  /// value and first derivative in W lanes at once (point_lanes.hpp): the
  /// formulas of jet() on Eigen arrays, whose packed square root, division
  /// and selects vectorize where hypot and a branch on the sign do not.
  /// Overflow-safe like hypot: r = m sqrt((s/m)^2 + (2 delta/m)^2) with
  /// m = max(|s|, 2 delta); r + |s| (= r - s below 0) is never 0 unless
  /// delta = s = 0.
  template <int W>
  void first_jet(const double (&s)[W], double (&v)[W], double (&d)[W]) const {
    using Lanes = Eigen::Array<double, W, 1>;
    constexpr double tiny = std::numeric_limits<double>::min();
    const Eigen::Map<const Lanes> sigma(s);
    Eigen::Map<Lanes> value(v), slope(d);
    const double t = 2.0 * delta;
    const Lanes m = sigma.abs().max(t).max(tiny);
    const Lanes r = m * ((sigma / m).square() + (t / m).square()).sqrt();
    const Lanes below = (2.0 * delta * delta) / (r + sigma.abs()).max(tiny);
    const Lanes above = 0.5 * (sigma + r);
    value = (sigma >= 0.0).select(above, below);
    const Lanes ratio = value / r.max(tiny);  // evaluated here, not inside the select
    slope = (r > 0.0).select(ratio, Lanes::Constant(0.5));
  }
};

/// sigma_0(s) = (s + |s|) / 2 = max(s, 0), eq 3.8: the delta -> 0 limit of eq 3.4
/// used for validation (eq 3.7). A measure using it is +infinity, q = 1/eta = 0,
/// exactly when sigma <= 0, and equals the unregularized measure for sigma > 0.
/// Its derivatives are those of the valid branch (1, 0) for s > 0 and 0 otherwise;
/// where the value is 0 the measure's derivatives do not exist.
struct ClampedDeterminant {
  [[nodiscard]] double value(double s) const { return s > 0.0 ? s : 0.0; }
  [[nodiscard]] double derivative(double s) const { return s > 0.0 ? 1.0 : 0.0; }
  [[nodiscard]] double second_derivative(double) const { return 0.0; }
  [[nodiscard]] DeterminantJet jet(double s) const { return {value(s), derivative(s), 0.0}; }
  /// value and first derivative in W lanes at once (point_lanes.hpp).
  template <int W>
  void first_jet(const double (&s)[W], double (&v)[W], double (&d)[W]) const {
    HOM_LANES
    for (int l = 0; l < W; ++l) {
      v[l] = s[l] > 0.0 ? s[l] : 0.0;
      d[l] = s[l] > 0.0 ? 1.0 : 0.0;
    }
  }
};

/// |sigma|: eq 3.2 exactly as printed. An inverted element whose |J| is conformal
/// scores eta = 1, so this policy is for reproducing figure 4.5(a)/(c) only.
struct AbsoluteDeterminant {
  [[nodiscard]] double value(double s) const { return std::abs(s); }
  [[nodiscard]] double derivative(double s) const { return s > 0.0 ? 1.0 : (s < 0.0 ? -1.0 : 0.0); }
  [[nodiscard]] double second_derivative(double) const { return 0.0; }
  [[nodiscard]] DeterminantJet jet(double s) const { return {value(s), derivative(s), 0.0}; }
};

static_assert(DeterminantRegularization<RegularizedDeterminant>);
static_assert(DeterminantRegularization<ClampedDeterminant>);
static_assert(DeterminantRegularization<AbsoluteDeterminant>);

/// alpha of eq 4.13: tau = alpha |sigma*|; the thesis uses 1e-3 for every example.
inline constexpr double thesis_regularization_alpha = 1e-3;

/// delta(sigma*) = |sigma*| sqrt(alpha^2 + alpha), eqs 4.12-4.14.
///
/// sigma* < 0 is a reference negative determinant; delta is chosen so that
/// sigma_delta(sigma*) = tau = alpha |sigma*| > 0 (eq 4.12 with eq 4.13), hence,
/// sigma_delta being increasing, sigma_delta > tau for every sigma > sigma*, and
/// sigma_delta(0) = delta. sigma* must be in the units of the sigma that is
/// regularized (see element_regularization()).
[[nodiscard]] inline double regularization_delta(double sigma_star,
                                                 double alpha = thesis_regularization_alpha) {
  return std::abs(sigma_star) * std::sqrt(alpha * alpha + alpha);
}

/// The thesis's element-wise regularization (section 4.2.2) for measures
/// evaluated, as all of hom's are, at J = D phi_E = D phi_P (D phi_I)^{-1}.
///
/// What sigma* is. Section 4.2.2 sets sigma* = -det D phi_I, minus the determinant
/// of the straight-sided ideal's map from the master element: a master-frame
/// quantity, the scale of sigma_P = det D phi_P. The determinant the measure
/// sees is sigma = det D phi_E = sigma_P / det D phi_I, so in these units the same
/// reference value is sigma* = -det D phi_I / det D phi_I = -1: minus the
/// determinant of the ideal element mapped to itself. Both readings give the
/// same regularized measure, because sigma_delta is positively homogeneous,
///   sigma_{g delta}(g s) = g sigma_delta(s)   for g = det D phi_I > 0,
/// so regularizing sigma_P with delta_P = |det D phi_I| sqrt(alpha^2 + alpha) and
/// dividing by det D phi_I is regularizing sigma with
///   delta = sqrt(alpha^2 + alpha) ~= 0.0316   (alpha = 1e-3),
/// the same constant for every element, independent of its size. (Plugging the
/// master-frame delta_P into sigma = det D phi_E instead would make the
/// regularization depend on the element's size: about 2e-8 for a regular tetrahedron of
/// edge 0.01, which hardly regularizes at all.) The thesis regularizes only
/// elements that are invalid and uses delta = 0 (ClampedDeterminant) once every
/// element is valid; that choice belongs to the caller.
[[nodiscard]] inline RegularizedDeterminant element_regularization(
    double alpha = thesis_regularization_alpha) {
  return {regularization_delta(-1.0, alpha)};
}

}  // namespace hom
