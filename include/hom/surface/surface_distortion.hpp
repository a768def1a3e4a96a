#pragma once
/// @file surface_distortion.hpp
/// The point-wise distortion of a map between surfaces (section 5.2.2):
///
///   M phi = eta_delta( J-bar(D phi_I, D phi_P) )                        (eq 5.6)
///
/// any planar DistortionMeasure (shape, Oddy) with any determinant
/// regularization (sigma_delta for optimization, sigma_0 for validation, as
/// in the planar case) evaluated on the 2 x 2 J-bar of eq 5.5
/// (surface_jacobian.hpp), and its first and second derivatives with respect
/// to B = D phi_P (3 x 2), the chain rule through J-bar:
///
///   d eta / d vec(B)     = Jb^T g,                                 g = d eta / d vec(J-bar),
///   d^2 eta / d vec(B)^2 = Jb^T H Jb + sum_i g_i d^2 vec(J-bar)_i / d vec(B)^2,
///
/// Jb = d vec(J-bar) / d vec(B) (4 x 6), H the measure's Hessian in J-bar.
/// With the nodes on a parameterized surface, B = sum_i phi(u_i) grad N_i^T
/// (eq 5.9, 5.20), so d B / d u_i = D phi(u_i) (x) grad N_i and the derivatives
/// in the nodes' parameters follow (surface_element_quality.hpp,
/// parameter_gradient); the second derivatives add D^2 phi (eqs 5.21-5.23).
///
/// K = (A~^T A)^{-1}, the ideal's factor of eq 5.5, is an argument: it is fixed
/// for an element (the ideal does not move) and computed once per point.

#include <Eigen/Core>

#include "hom/measure/distortion_measure.hpp"
#include "hom/measure/regularization.hpp"
#include "hom/surface/surface_jacobian.hpp"

namespace hom {

/// The ideal's side of eq 5.5 at one point: K = (A~^T A)^{-1} for the ideal
/// tangents A oriented by `normal`.
inline Eigen::Matrix2d ideal_factor_inverse(const SurfaceTangents& A, const Eigen::Vector3d& normal) {
  return tangent_plane_coordinates(A, normal).inverse();
}

/// eta(J-bar) for the physical tangents B oriented by `normal`.
template <class Measure, DeterminantRegularization Reg>
double surface_distortion(const Measure& measure, const Eigen::Matrix2d& ideal_inverse, const SurfaceTangents& B,
                          const Eigen::Vector3d& normal, const Reg& reg) {
  return measure.value(Eigen::Matrix2d(tangent_plane_coordinates(B, normal) * ideal_inverse), reg);
}

/// eta and d eta / d B (3 x 2). The gradient is NaN where eta is not finite.
template <class Measure, DeterminantRegularization Reg>
double surface_distortion_gradient(const Measure& measure, const Eigen::Matrix2d& ideal_inverse,
                                   const SurfaceTangents& B, const Eigen::Vector3d& normal, const Reg& reg,
                                   SurfaceTangents& grad) {
  const SurfaceJacobianJet j = surface_jacobian_jet(ideal_inverse, B, normal, false);
  Eigen::Matrix2d g;
  const double eta = measure.value_gradient(j.value, reg, g);
  const Eigen::Matrix<double, 6, 1> gb = j.first.transpose() * Eigen::Map<const Eigen::Vector4d>(g.data());
  grad = Eigen::Map<const SurfaceTangents>(gb.data());
  return eta;
}

/// eta, d eta / d B (3 x 2) and d^2 eta / d vec(B)^2 (6 x 6, vec column-major).
template <class Measure, DeterminantRegularization Reg>
double surface_distortion_hessian(const Measure& measure, const Eigen::Matrix2d& ideal_inverse,
                                  const SurfaceTangents& B, const Eigen::Vector3d& normal, const Reg& reg,
                                  SurfaceTangents& grad, Eigen::Matrix<double, 6, 6>& hess) {
  const SurfaceJacobianJet j = surface_jacobian_jet(ideal_inverse, B, normal, true);
  Eigen::Matrix2d g;
  Eigen::Matrix4d h;
  const double eta = measure.value_gradient_hessian(j.value, reg, g, h);
  const Eigen::Map<const Eigen::Vector4d> gv(g.data());
  const Eigen::Matrix<double, 6, 1> gb = j.first.transpose() * gv;
  grad = Eigen::Map<const SurfaceTangents>(gb.data());
  hess = j.first.transpose() * h * j.first;
  for (int i = 0; i < 4; ++i) hess += gv[i] * j.second[i];
  return eta;
}

}  // namespace hom
