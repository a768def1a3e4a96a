#pragma once
/// @file oddy_measure.hpp
/// The Oddy distortion measure (Oddy et al. 1988; thesis eqs 3.3 and 3.6),
/// normalized so that eta = 1 at the ideal:
///
///   eta(J) = 1 + 2 ||J^T J - (||J||_F^2 / d) I||_F^2 / reg(sigma)^(4/d)
///          = 1 + 2 (||J^T J||_F^2 - (1/d) ||J||_F^4) / reg(sigma)^(4/d),   sigma = det J, d = Dim.
///
/// Why this normalization. Oddy's original quantity
///   D(J) = (||J^T J||^2 - (1/d) ||J||^4) / sigma^(4/d)
/// is the squared deviation of the metric tensor G = J^T J from its isotropic part
/// (tr G / d) I, scaled by det G^(2/d): it is 0 for J = c R and grows without
/// bound as sigma -> 0+. The "1/3" of eq 3.3 is the 1/d that makes it vanish for a
/// conformal J in 3D; in 2D it must be 1/2. Eq 3.3 as printed,
///   3 (||J^T J||^2 - (1/3) ||J||^4) / (d sigma^(4/d)),
/// is D itself for d = 3 (0, not 1, at the ideal), while for d = 2 it equals
/// 1 + 2 D exactly: with lambda_1, lambda_2 the eigenvalues of G, ||J||^4 - ||J^T J||^2
/// = 2 lambda_1 lambda_2 = 2 sigma^2, so (3||G||^2 - ||J||^4) / (2 sigma^2) = 1 + 2 D =
/// lambda_1/lambda_2 + lambda_2/lambda_1 - 1, a function of the condition number of G.
/// hom therefore uses eta = 1 + 2 D for both dimensions:
///   - d = 2, sigma > 0: identical to eq 3.3 as printed, the formula behind the thesis's
///     figures 3.4-3.6 and D.3 (all planar); it also equals 4 eta_shape^2 - 3;
///   - d = 3: the printed formula shifted by 1 and with the same factor 2 as in 2D;
///   - both: eta = 1 exactly for J = c R, eta >= 1, eta -> inf as sigma -> 0+,
///     invariant under rotations and scaling, q = 1/eta in [0, 1], and eta >= eta_shape
///     (checked on random metrics), i.e. Oddy is the stricter measure, as section 3.3.1
///     observes ("tends to zero faster than the shape quality measure").
/// With delta > 0 (eq 3.6) sigma is replaced by sigma_delta in the denominator only;
/// for d = 2 this differs from the printed eq 3.6 ((3||G||^2 - ||J||^4)/(2 sigma_delta^2) =
/// sigma^2/sigma_delta^2 + 2 D_delta) by keeping the additive constant 1. The thesis never
/// optimizes the Oddy measure (chapter 4 uses the shape measure), so nothing
/// reproduced depends on that choice.
///
/// The numerator is evaluated as ||G - (tr G / d) I||^2, a sum of squares, so that eta >= 1
/// holds in floating point too (the printed difference cancels near the ideal).
///
/// Derivatives, with phi = 2 N, N = ||G^||^2, G^ = J^T J - (||J||^2/d) I, g = reg^(-4/d):
///   dN/dJ = 4 J G^,
///   d^2 N / dJ_ij dJ_kl = 4 (delta_ik G^_lj + J_il J_kj + delta_jl (J J^T)_ik) - (8/d) J_ij J_kl,
/// composed with g(sigma) as in detail/measure_chain_rule.hpp.

#include <limits>
#include <string_view>

#include <Eigen/Core>

#include "hom/detail/determinant.hpp"
#include "hom/detail/measure_chain_rule.hpp"
#include "hom/measure/distortion_measure.hpp"
#include "hom/measure/regularization.hpp"

namespace hom {

struct OddyMeasure {
  static constexpr std::string_view name = "oddy";

  /// eta = 1 + scale * D: the factor that reproduces eq 3.3 in 2D (see above).
  static constexpr double scale = 2.0;

  template <int Dim, DeterminantRegularization Reg>
  [[nodiscard]] double value(const Eigen::Matrix<double, Dim, Dim>& J, const Reg& reg) const {
    static_assert(Dim == 2 || Dim == 3, "hom::OddyMeasure: J must be 2x2 or 3x3");
    const double s = reg.value(detail::determinant<Dim>(J));
    if (s <= 0.0) return std::numeric_limits<double>::infinity();
    return 1.0 + scale * deviatoric_metric(J).squaredNorm() / detail::root_power<Dim, 4>(s);
  }

  template <int Dim, DeterminantRegularization Reg>
  double value_gradient(const Eigen::Matrix<double, Dim, Dim>& J, const Reg& reg,
                        Eigen::Matrix<double, Dim, Dim>& grad) const {
    static_assert(Dim == 2 || Dim == 3, "hom::OddyMeasure: J must be 2x2 or 3x3");
    const Eigen::Matrix<double, Dim, Dim> cof = detail::cofactor<Dim>(J);
    const DeterminantJet s = reg.jet(detail::determinant_from_cofactor<Dim>(J, cof));
    if (s.value <= 0.0) return detail::undefined_gradient<Dim>(grad);
    const detail::InversePowerJet g = detail::inverse_power_jet<Dim, 4>(s);
    const Eigen::Matrix<double, Dim, Dim> Gd = deviatoric_metric(J);
    const double phi = scale * Gd.squaredNorm();
    detail::compose_gradient<Dim>(phi, (4.0 * scale) * (J * Gd), g, cof, grad);
    return 1.0 + phi * g.value;
  }

  template <int Dim, DeterminantRegularization Reg>
  double value_gradient_hessian(const Eigen::Matrix<double, Dim, Dim>& J, const Reg& reg,
                                Eigen::Matrix<double, Dim, Dim>& grad,
                                Eigen::Matrix<double, Dim * Dim, Dim * Dim>& hess) const {
    static_assert(Dim == 2 || Dim == 3, "hom::OddyMeasure: J must be 2x2 or 3x3");
    const Eigen::Matrix<double, Dim, Dim> cof = detail::cofactor<Dim>(J);
    const DeterminantJet s = reg.jet(detail::determinant_from_cofactor<Dim>(J, cof));
    if (s.value <= 0.0) return detail::undefined_gradient_hessian<Dim>(grad, hess);
    const detail::InversePowerJet g = detail::inverse_power_jet<Dim, 4>(s);
    const Eigen::Matrix<double, Dim, Dim> Gd = deviatoric_metric(J);
    const double phi = scale * Gd.squaredNorm();
    const Eigen::Matrix<double, Dim, Dim> grad_phi = (4.0 * scale) * (J * Gd);
    detail::compose_gradient<Dim>(phi, grad_phi, g, cof, grad);

    // hess(phi) = scale * d^2 N / dJ^2 (formula in the file comment).
    const Eigen::Matrix<double, Dim, Dim> JJt = J * J.transpose();
    for (int l = 0; l < Dim; ++l)
      for (int k = 0; k < Dim; ++k)
        for (int j = 0; j < Dim; ++j)
          for (int i = 0; i < Dim; ++i) {
            double h = J(i, l) * J(k, j) - (2.0 / Dim) * J(i, j) * J(k, l);
            if (i == k) h += Gd(l, j);
            if (j == l) h += JJt(i, k);
            hess(detail::flat_index<Dim>(i, j), detail::flat_index<Dim>(k, l)) = 4.0 * scale * h;
          }
    detail::compose_hessian<Dim>(phi, grad_phi, g, J, cof, hess);
    return 1.0 + phi * g.value;
  }

 private:
  /// G^ = J^T J - (||J||^2 / d) I: the metric minus its isotropic part.
  template <int Dim>
  static Eigen::Matrix<double, Dim, Dim> deviatoric_metric(const Eigen::Matrix<double, Dim, Dim>& J) {
    Eigen::Matrix<double, Dim, Dim> G = J.transpose() * J;
    G.diagonal().array() -= G.trace() / Dim;
    return G;
  }
};

static_assert(DistortionMeasure<OddyMeasure>);

}  // namespace hom
