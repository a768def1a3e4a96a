#pragma once
/// @file measure_chain_rule.hpp
/// The chain rule shared by hom's Jacobian-based distortion measures, which all
/// have the form
///
///   eta(J) = offset + phi(J) g(sigma),   g(sigma) = reg(sigma)^(-P/Dim),   sigma = det J,
///
/// with phi a polynomial in J (shape: ||J||^2 / d, P = 2; Oddy: P = 4). With
/// C = cof J = d sigma / dJ and H_det = d^2 sigma / dJ^2:
///
///   d eta   = g grad(phi) + phi g' C
///   d^2 eta = g hess(phi) + g' (grad(phi) (x) C + C (x) grad(phi)) + phi g'' C (x) C + phi g' H_det
///
/// where g' and g'' are derivatives in sigma through the regularization policy:
///   g'  = -k g reg'/reg,   g'' = k g ((k + 1) (reg'/reg)^2 - reg''/reg),   k = P / Dim.

#include <cmath>
#include <limits>

#include <Eigen/Core>

#include "hom/detail/determinant.hpp"
#include "hom/measure/regularization.hpp"

namespace hom::detail {

/// s^(P/Dim) for s >= 0, with a cube root instead of pow in 3D (exact for perfect cubes
/// up to rounding, and several times faster).
template <int Dim, int P>
double root_power(double s) {
  static_assert(Dim == 2 || Dim == 3, "hom: Jacobian-based measures exist for Dim = 2 and 3");
  static_assert(P == 2 || P == 4, "hom::detail::root_power: only the powers 2/Dim and 4/Dim are used");
  if constexpr (Dim == 2) {
    return P == 2 ? s : s * s;
  } else {
    const double c = std::cbrt(s);
    const double c2 = c * c;
    return P == 2 ? c2 : c2 * c2;
  }
}

/// g(sigma) = reg(sigma)^(-P/Dim) with its first and second sigma-derivatives.
struct InversePowerJet {
  double value, first, second;
};

/// Requires s.value > 0.
template <int Dim, int P>
InversePowerJet inverse_power_jet(const DeterminantJet& s) {
  constexpr double k = double(P) / Dim;
  const double g = 1.0 / root_power<Dim, P>(s.value);
  const double r1 = s.first / s.value;
  const double r2 = s.second / s.value;
  return {g, -k * g * r1, k * g * ((k + 1.0) * r1 * r1 - r2)};
}

/// grad = d(phi g)/dJ.
template <int Dim>
void compose_gradient(double phi, const SquareMatrix<Dim>& grad_phi, const InversePowerJet& g,
                      const SquareMatrix<Dim>& cof, SquareMatrix<Dim>& grad) {
  grad = g.value * grad_phi + (phi * g.first) * cof;
}

/// On entry hess holds hess(phi); on exit d^2(phi g)/dJ^2 (column-major flattening).
template <int Dim>
void compose_hessian(double phi, const SquareMatrix<Dim>& grad_phi, const InversePowerJet& g,
                     const SquareMatrix<Dim>& J, const SquareMatrix<Dim>& cof, FlatHessian<Dim>& hess) {
  using Flat = Eigen::Matrix<double, Dim * Dim, 1>;
  const Eigen::Map<const Flat> vphi(grad_phi.data());
  const Eigen::Map<const Flat> vcof(cof.data());
  hess *= g.value;
  hess.noalias() += g.first * (vphi * vcof.transpose() + vcof * vphi.transpose());
  hess.noalias() += (phi * g.second) * (vcof * vcof.transpose());
  add_determinant_hessian<Dim>(J, phi * g.first, hess);
}

/// The Hessian contracted with a rank-one direction: J(u) = J + u w^T, u in R^Dim,
/// which is how J_q moves when one node moves (d J / dx_a = e_a w^T with
/// w = A^T grad N, see GaussSeidel, eq B.4). On entry hw holds the contraction of
/// hess(phi); on exit d^2(phi g)/du^2 at u = 0, a Dim x Dim matrix. With
/// p = grad(phi) w and c = cof(J) w (det(J + u w^T) = det J + c . u, the matrix
/// determinant lemma, so the H_det term vanishes along these directions):
///   hw = g hess_w(phi) + g' (p c^T + c p^T) + phi g'' c c^T.
template <int Dim>
void compose_directional_hessian(double phi, const SquareMatrix<Dim>& grad_phi, const InversePowerJet& g,
                                 const SquareMatrix<Dim>& cof, const Eigen::Matrix<double, Dim, 1>& w,
                                 SquareMatrix<Dim>& hw) {
  const Eigen::Matrix<double, Dim, 1> p = grad_phi * w;
  const Eigen::Matrix<double, Dim, 1> c = cof * w;
  hw *= g.value;
  hw.noalias() += g.first * (p * c.transpose() + c * p.transpose());
  hw.noalias() += (phi * g.second) * (c * c.transpose());
}

/// Where reg(sigma) = 0 the measure is +infinity and has no derivatives: they are
/// set to NaN so that a caller who uses them anyway notices.
template <int Dim>
double undefined_gradient(SquareMatrix<Dim>& grad) {
  grad.setConstant(std::numeric_limits<double>::quiet_NaN());
  return std::numeric_limits<double>::infinity();
}

template <int Dim>
double undefined_gradient_hessian(SquareMatrix<Dim>& grad, FlatHessian<Dim>& hess) {
  hess.setConstant(std::numeric_limits<double>::quiet_NaN());
  return undefined_gradient<Dim>(grad);
}

}  // namespace hom::detail
