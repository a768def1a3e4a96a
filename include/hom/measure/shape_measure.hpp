#pragma once
/// @file shape_measure.hpp
/// The shape distortion measure of Knupp (2001), eq 3.2, and its regularized
/// form eq 3.5:
///
///   eta(J) = ||J||_F^2 / (d reg(sigma)^(2/d)),   sigma = det J,  d = Dim.
///
/// With reg(sigma) = sigma > 0 it is the ratio of the arithmetic to the geometric
/// mean of the eigenvalues of the metric J^T J, hence eta >= 1 with equality exactly
/// for J = c R (R a rotation): it measures the deviation of the physical element's
/// shape from the ideal's, ignoring size and orientation.
///
/// Derivatives (phi = ||J||^2 / d, g = reg^(-2/d), see detail/measure_chain_rule.hpp):
///   d phi / dJ = (2/d) J,   d^2 phi / dJ^2 = (2/d) I,
///   d eta / dJ = g (2/d) J + phi g'(sigma) cof(J).

#include <limits>
#include <string_view>

#include <Eigen/Core>

#include "hom/detail/determinant.hpp"
#include "hom/detail/measure_chain_rule.hpp"
#include "hom/measure/distortion_measure.hpp"
#include "hom/measure/regularization.hpp"

namespace hom {

struct ShapeMeasure {
  static constexpr std::string_view name = "shape";

  template <int Dim, DeterminantRegularization Reg>
  [[nodiscard]] double value(const Eigen::Matrix<double, Dim, Dim>& J, const Reg& reg) const {
    static_assert(Dim == 2 || Dim == 3, "hom::ShapeMeasure: J must be 2x2 or 3x3");
    const double s = reg.value(detail::determinant<Dim>(J));
    if (s <= 0.0) return std::numeric_limits<double>::infinity();
    return J.squaredNorm() / (Dim * detail::root_power<Dim, 2>(s));
  }

  template <int Dim, DeterminantRegularization Reg>
  double value_gradient(const Eigen::Matrix<double, Dim, Dim>& J, const Reg& reg,
                        Eigen::Matrix<double, Dim, Dim>& grad) const {
    static_assert(Dim == 2 || Dim == 3, "hom::ShapeMeasure: J must be 2x2 or 3x3");
    const Eigen::Matrix<double, Dim, Dim> cof = detail::cofactor<Dim>(J);
    const DeterminantJet s = reg.jet(detail::determinant_from_cofactor<Dim>(J, cof));
    if (s.value <= 0.0) return detail::undefined_gradient<Dim>(grad);
    const detail::InversePowerJet g = detail::inverse_power_jet<Dim, 2>(s);
    const double phi = J.squaredNorm() / Dim;
    detail::compose_gradient<Dim>(phi, (2.0 / Dim) * J, g, cof, grad);
    return phi * g.value;
  }

  template <int Dim, DeterminantRegularization Reg>
  double value_gradient_hessian(const Eigen::Matrix<double, Dim, Dim>& J, const Reg& reg,
                                Eigen::Matrix<double, Dim, Dim>& grad,
                                Eigen::Matrix<double, Dim * Dim, Dim * Dim>& hess) const {
    static_assert(Dim == 2 || Dim == 3, "hom::ShapeMeasure: J must be 2x2 or 3x3");
    const Eigen::Matrix<double, Dim, Dim> cof = detail::cofactor<Dim>(J);
    const DeterminantJet s = reg.jet(detail::determinant_from_cofactor<Dim>(J, cof));
    if (s.value <= 0.0) return detail::undefined_gradient_hessian<Dim>(grad, hess);
    const detail::InversePowerJet g = detail::inverse_power_jet<Dim, 2>(s);
    const double phi = J.squaredNorm() / Dim;
    const Eigen::Matrix<double, Dim, Dim> grad_phi = (2.0 / Dim) * J;
    detail::compose_gradient<Dim>(phi, grad_phi, g, cof, grad);
    hess.setIdentity();
    hess *= 2.0 / Dim;
    detail::compose_hessian<Dim>(phi, grad_phi, g, J, cof, hess);
    return phi * g.value;
  }

  /// Value, gradient and the Hessian contracted with a rank-one direction,
  /// hw(a, b) = sum_{k,m} d^2 eta / dJ_ak dJ_bm w_k w_m: what a one-node
  /// Newton step needs (Gauss-Seidel, eq B.4) at a fraction of the full
  /// Dim^2 x Dim^2 Hessian's cost. hess(phi) = (2/d) I contracts to (2/d)|w|^2 I.
  template <int Dim, DeterminantRegularization Reg>
  double value_gradient_directional_hessian(const Eigen::Matrix<double, Dim, Dim>& J, const Reg& reg,
                                            const Eigen::Matrix<double, Dim, 1>& w,
                                            Eigen::Matrix<double, Dim, Dim>& grad,
                                            Eigen::Matrix<double, Dim, Dim>& hw) const {
    static_assert(Dim == 2 || Dim == 3, "hom::ShapeMeasure: J must be 2x2 or 3x3");
    const Eigen::Matrix<double, Dim, Dim> cof = detail::cofactor<Dim>(J);
    const DeterminantJet s = reg.jet(detail::determinant_from_cofactor<Dim>(J, cof));
    if (s.value <= 0.0) {
      hw.setConstant(std::numeric_limits<double>::quiet_NaN());
      return detail::undefined_gradient<Dim>(grad);
    }
    const detail::InversePowerJet g = detail::inverse_power_jet<Dim, 2>(s);
    const double phi = J.squaredNorm() / Dim;
    const Eigen::Matrix<double, Dim, Dim> grad_phi = (2.0 / Dim) * J;
    detail::compose_gradient<Dim>(phi, grad_phi, g, cof, grad);
    hw = Eigen::Matrix<double, Dim, Dim>::Identity() * ((2.0 / Dim) * w.squaredNorm());
    detail::compose_directional_hessian<Dim>(phi, grad_phi, g, cof, w, hw);
    return phi * g.value;
  }
};

static_assert(DistortionMeasure<ShapeMeasure>);

}  // namespace hom
