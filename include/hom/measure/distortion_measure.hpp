#pragma once
/// @file distortion_measure.hpp
/// The DistortionMeasure concept: a Jacobian-based distortion measure of a
/// linear element (section 3.1.1), eta(J) in [1, inf) for valid J, with J = D phi_E
/// the Jacobian of the map from the ideal element to the physical one
/// (phi_E = phi_P o phi_I^{-1}, eq A.2). q = 1/eta (eq 3.1).
///
/// Every measure takes the determinant regularization as a policy object
/// (concept DeterminantRegularization, regularization.hpp): sigma = det J is
/// replaced by reg(sigma) in the denominator, giving eta (eqs 3.2, 3.3) for
/// sigma > 0, eta_delta (eqs 3.5, 3.6) with RegularizedDeterminant and eta_0
/// (eq 3.7) with ClampedDeterminant.
///
/// Required of a measure type M, for Dim = 2 and 3, with
///   J    : const Eigen::Matrix<double, Dim, Dim>&
///   reg  : const Reg& (a DeterminantRegularization)
///   grad : Eigen::Matrix<double, Dim, Dim>&              (d eta / dJ_ij at (i, j))
///   hess : Eigen::Matrix<double, Dim*Dim, Dim*Dim>&      (d^2 eta / dJ_ij dJ_kl)
/// members
///   - `M::name`: std::string_view naming the measure ("shape", "oddy") for tables and reports;
///   - `m.value(J, reg) -> double`;
///   - `m.value_gradient(J, reg, grad) -> double` (eta);
///   - `m.value_gradient_hessian(J, reg, grad, hess) -> double` (eta).
/// The Hessian is with respect to J flattened column-major: entry (i, j) of J has
/// index i + Dim * j, so hess(i + Dim*j, k + Dim*l) = d^2 eta / dJ_ij dJ_kl; this is
/// Eigen's storage order, so Eigen::Map<Matrix<double, Dim*Dim, 1>>(J.data())
/// is the flattened J.
///
/// Contract:
///   - value, gradient and Hessian are analytic (no finite differences), fixed-size,
///     allocation-free; they are called at every quadrature point of every element;
///   - eta = +infinity, q = 0, exactly when reg(sigma) = 0 (with ClampedDeterminant:
///     sigma <= 0); the derivatives do not exist there and are set to NaN;
///   - for reg(sigma) = sigma > 0: eta >= 1, eta = 1 exactly when J = c R (c > 0, R a
///     rotation), eta -> inf as sigma -> 0+, eta(Q1 J Q2) = eta(J) for orthogonal Q1, Q2
///     with det(Q1 Q2) = 1, and eta(c J) = eta(J);
///   - with RegularizedDeterminant (delta > 0) eta_delta is finite and smooth for every J
///     and keeps the rotation invariances (not the scaling one: delta is fixed).
///
/// Optional member, used when present (see value_gradient_directional_hessian below):
///   - `m.value_gradient_directional_hessian(J, reg, w, grad, hw) -> double`: the Hessian
///     contracted with the rank-one directions e_a w^T, hw(a, b) = sum_{k,m} hess(a + Dim k,
///     b + Dim m) w_k w_m, the only part a one-node Newton step needs.
///
///   - `m.value_lanes<Dim, W>(J, reg, eta)` and `m.value_gradient_lanes<Dim, W>(J, reg, grad,
///     eta)`: value and value_gradient at W points at once, in the structure-of-arrays form
///     of point_lanes.hpp (concept BatchedMeasureFor); the optimizer's value and gradient
///     evaluations use them when the measure and the regularization policy (its
///     `first_jet`) have them.
///
/// Models: ShapeMeasure (shape_measure.hpp, eq 3.2), OddyMeasure (oddy_measure.hpp, eq 3.3).
///
/// Surfaces (chapter 5) reuse the Dim = 2 measures on the 2x2 matrix J-bar of eq 5.5
/// (eq 5.6); nothing surface-specific lives here.

#include <concepts>
#include <string_view>

#include <Eigen/Core>

#include "hom/detail/point_lanes.hpp"
#include "hom/measure/regularization.hpp"

namespace hom {

/// The requirements for one dimension and one regularization policy.
template <class M, int Dim, class Reg>
concept DistortionMeasureFor =
    DeterminantRegularization<Reg> &&
    requires(const M& m, const Eigen::Matrix<double, Dim, Dim>& J, const Reg& reg,
             Eigen::Matrix<double, Dim, Dim>& grad, Eigen::Matrix<double, Dim * Dim, Dim * Dim>& hess) {
      { m.value(J, reg) } -> std::same_as<double>;
      { m.value_gradient(J, reg, grad) } -> std::same_as<double>;
      { m.value_gradient_hessian(J, reg, grad, hess) } -> std::same_as<double>;
    };

template <class M>
concept DistortionMeasure =
    requires { { M::name } -> std::convertible_to<std::string_view>; } &&
    DistortionMeasureFor<M, 2, RegularizedDeterminant> && DistortionMeasureFor<M, 3, RegularizedDeterminant> &&
    DistortionMeasureFor<M, 2, ClampedDeterminant> && DistortionMeasureFor<M, 3, ClampedDeterminant>;

/// M evaluates value and value_gradient on detail::point_lanes points at once.
template <class M, int Dim, class Reg>
concept BatchedMeasureFor =
    requires(const M& m, const double (&J)[Dim * Dim][detail::point_lanes], const Reg& reg,
             double (&grad)[Dim * Dim][detail::point_lanes], double (&eta)[detail::point_lanes]) {
      m.template value_lanes<Dim, detail::point_lanes>(J, reg, eta);
      m.template value_gradient_lanes<Dim, detail::point_lanes>(J, reg, grad, eta);
    };

/// eta, d eta / dJ and the Hessian along the rank-one directions J + u w^T:
/// hw(a, b) = d^2 eta(J + u w^T) / du_a du_b at u = 0. Moving one node of an
/// element by u moves each point Jacobian that way (eq B.4), so non-linear
/// Gauss-Seidel needs only this Dim x Dim matrix. The measure's own member
/// is used when it has one; otherwise the full Hessian is contracted.
template <class M, int Dim, class Reg>
double value_gradient_directional_hessian(const M& m, const Eigen::Matrix<double, Dim, Dim>& J, const Reg& reg,
                                          const Eigen::Matrix<double, Dim, 1>& w,
                                          Eigen::Matrix<double, Dim, Dim>& grad,
                                          Eigen::Matrix<double, Dim, Dim>& hw) {
  if constexpr (requires { m.value_gradient_directional_hessian(J, reg, w, grad, hw); }) {
    return m.value_gradient_directional_hessian(J, reg, w, grad, hw);
  } else {
    Eigen::Matrix<double, Dim * Dim, Dim * Dim> hess;
    const double eta = m.value_gradient_hessian(J, reg, grad, hess);
    for (int a = 0; a < Dim; ++a)
      for (int b = 0; b < Dim; ++b) {
        double sum = 0.0;
        for (int k = 0; k < Dim; ++k)
          for (int l = 0; l < Dim; ++l) sum += hess(a + Dim * k, b + Dim * l) * w[k] * w[l];
        hw(a, b) = sum;
      }
    return eta;
  }
}

}  // namespace hom
