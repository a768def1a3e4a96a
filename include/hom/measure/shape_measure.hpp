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
#include "hom/detail/point_lanes.hpp"
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

  /// value at W points at once (point_lanes.hpp): J is Dim^2 x W (row
  /// i + Dim j is entry (i, j) of every lane); eta = +inf in a lane where
  /// reg(sigma) = 0, as value.
  template <int Dim, int W, DeterminantRegularization Reg>
  void value_lanes(const double (&J)[Dim * Dim][W], const Reg& reg, double (&eta)[W]) const {
    double sigma[W], s[W], ds[W], g[W], phi[W];
    detail::determinant_lanes<Dim, W>(J, sigma);
    value_lanes_from_determinant<Dim, W>(J, sigma, reg, s, ds, g, phi, eta);
  }

  /// value_gradient at W points at once (point_lanes.hpp), J and grad as in
  /// value_lanes; the gradient is undefined in a lane where eta = +inf. The
  /// same formulas: sigma from the cofactors of row 0, g = reg^(-2/d) (a
  /// Newton cube root in 3D), and d eta / dJ = g (2/d) J + phi g' cof J with
  /// g' = -(2/d) g reg' / reg.
  template <int Dim, int W, DeterminantRegularization Reg>
  void value_gradient_lanes(const double (&J)[Dim * Dim][W], const Reg& reg, double (&grad)[Dim * Dim][W],
                            double (&eta)[W]) const {
    constexpr double k = 2.0 / Dim;
    double C[Dim * Dim][W], sigma[W] = {}, s[W], ds[W], g[W], phi[W], dg[W];
    detail::cofactor_lanes<Dim, W>(J, C);
    for (int j = 0; j < Dim; ++j) {
      HOM_LANES
      for (int l = 0; l < W; ++l) sigma[l] += J[Dim * j][l] * C[Dim * j][l];
    }
    value_lanes_from_determinant<Dim, W>(J, sigma, reg, s, ds, g, phi, eta);
    HOM_LANES
    for (int l = 0; l < W; ++l) dg[l] = -k * g[l] * ds[l] / s[l];
    for (int i = 0; i < Dim * Dim; ++i) {
      HOM_LANES
      for (int l = 0; l < W; ++l) grad[i][l] = g[l] * k * J[i][l] + phi[l] * dg[l] * C[i][l];
    }
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

 private:
  /// The lanes' s = reg(sigma), ds = reg'(sigma), g = s^(-2/d), phi = ||J||^2 / d
  /// and eta = phi g (+inf where s = 0). Loops over the lanes innermost, one
  /// statement each, and selects on computed values: what vectorizes.
  template <int Dim, int W, DeterminantRegularization Reg>
  static void value_lanes_from_determinant(const double (&J)[Dim * Dim][W], const double (&sigma)[W], const Reg& reg,
                                           double (&s)[W], double (&ds)[W], double (&g)[W], double (&phi)[W],
                                           double (&eta)[W]) {
    static_assert(Dim == 2 || Dim == 3, "hom::ShapeMeasure: J must be 2x2 or 3x3");
    reg.template first_jet<W>(sigma, s, ds);
    if constexpr (Dim == 3) {
      detail::inverse_cube_root<W>(s, g);
      HOM_LANES
      for (int l = 0; l < W; ++l) g[l] *= g[l];
    } else {
      HOM_LANES
      for (int l = 0; l < W; ++l) g[l] = 1.0 / s[l];
    }
    HOM_LANES
    for (int l = 0; l < W; ++l) phi[l] = 0.0;
    for (int i = 0; i < Dim * Dim; ++i) {
      HOM_LANES
      for (int l = 0; l < W; ++l) phi[l] += J[i][l] * J[i][l] * (1.0 / Dim);
    }
    HOM_LANES
    for (int l = 0; l < W; ++l) eta[l] = phi[l] * g[l];
    HOM_LANES
    for (int l = 0; l < W; ++l) eta[l] = s[l] > 0.0 ? eta[l] : std::numeric_limits<double>::infinity();
  }
};

static_assert(DistortionMeasure<ShapeMeasure>);

}  // namespace hom
