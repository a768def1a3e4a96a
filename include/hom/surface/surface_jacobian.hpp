#pragma once
/// @file surface_jacobian.hpp
/// The planar Jacobian J-bar of a linear map between two planes in R^3
/// (section 5.2.1), the point-wise ingredient of every surface measure:
///
///   J-bar(A, B) = B~^T B (A~^T A)^{-1}                                  (eq 5.5)
///
/// A = [a1 a2], B = [b1 b2] (3 x 2) span the tangent planes of the ideal and of
/// the physical element at corresponding points: for a surface element with
/// map phi_E = phi_P o phi_I^{-1} (section 5.2.2), A = D phi_I and B = D phi_P,
/// the derivatives of the ideal's and of the physical element's maps from the
/// reference element (surface_element_quality.hpp). A~ = [a~1 a~2] is the
/// oriented Gram-Schmidt basis of span(A):
///
///   a~1 = a1 / |a1|,   a~2 = gamma (a2 - (a2 . a~1) a~1) / |a2 - (a2 . a~1) a~1|,
///
/// gamma = +1 when (a1, a2) turn counter-clockwise seen from the side a
/// reference normal n points to, i.e. gamma = sign((a1 x a2) . n), and -1 when
/// clockwise. n is the surface's orientation (S_u x S_v, or the normal of the
/// element's straight-sided facet when no geometry is at hand); it is what
/// makes an element folded over the surface score det J-bar < 0.
///
/// Closed form. A~^T A is upper triangular and depends on A only through its
/// Gram matrix G = A^T A and gamma (it is the R of A = Q R with det Q-frame
/// oriented by n):
///
///   A~^T A = [ r  s ]     r = |a1|,  s = a1 . a2 / |a1|,
///            [ 0  t ]     t = gamma |a1 x a2| / |a1|,      det = gamma |a1 x a2|,
///
/// so J-bar is invariant under rigid motions of A and of B separately, and a
/// planar element in z = 0 (n = e3) has J-bar = Q1 (D phi_P D phi_I^{-1}) Q2 with
/// rotations Q1, Q2: the planar measure exactly (consistency, section 5.5.1.1).
/// Degenerate tangents: gamma = 0 when (a1 x a2) . n = 0 (t = 0, det = 0: the
/// measure is +inf under sigma_0); a1 = 0 gives r = s = 0, t = 0 as well.
///
/// Derivatives in B (for the optimizer, eqs 5.19-5.23). With vec(B) = (b1; b2)
/// (column-major, index a + 3 k for B(a, k)) and g = (g11, g12, g22) the Gram
/// entries, Delta = |b1 x b2| = sqrt(g11 g22 - g12^2):
///   r = g11^(1/2),  s = g12 g11^(-1/2),  t = gamma Delta g11^(-1/2);
///   d g11 = 2 b1 . db1,  d g12 = b2 . db1 + b1 . db2,  d g22 = 2 b2 . db2;
///   d^2 g11 = 2 I (b1 b1),  d^2 g12 = I (b1 b2 and b2 b1),  d^2 g22 = 2 I (b2 b2);
/// and the chain rule d^2 F = sum_ij F_ij dg_i dg_j + sum_i F_i d^2 g_i. gamma is
/// locally constant (the derivatives exist where Delta > 0 and |b1| > 0). In the
/// frame (b~1, b~2) the first derivatives read dr = b~1 . db1, ds = b~1 . db2 +
/// (t/r) b~2 . db1, dt = b~2 . db2 - (s/r) b~2 . db1. J-bar = B-bar K with K =
/// (A~^T A)^{-1} is linear in (r, s, t).

#include <array>
#include <cmath>

#include <Eigen/Dense>

namespace hom {

/// Two tangent vectors as the columns of a 3 x 2 matrix.
using SurfaceTangents = Eigen::Matrix<double, 3, 2>;

namespace detail {

inline double orientation_sign(const Eigen::Vector3d& cross, const Eigen::Vector3d& normal) {
  const double d = cross.dot(normal);
  return d > 0.0 ? 1.0 : (d < 0.0 ? -1.0 : 0.0);
}

}  // namespace detail

/// gamma of section 5.2.1: +1 (counter-clockwise seen from `normal`), -1
/// (clockwise) or 0 (T's plane contains the normal, or T is degenerate).
inline double tangent_orientation(const SurfaceTangents& T, const Eigen::Vector3d& normal) {
  return detail::orientation_sign(T.col(0).cross(T.col(1)), normal);
}

/// T~^T T of eqs 5.2-5.3: the tangent vectors in their oriented orthonormal
/// basis, [[r, s], [0, t]] (see the file comment).
inline Eigen::Matrix2d tangent_plane_coordinates(const SurfaceTangents& T, const Eigen::Vector3d& normal) {
  const Eigen::Vector3d c = T.col(0).cross(T.col(1));
  const double r = T.col(0).norm();
  Eigen::Matrix2d R = Eigen::Matrix2d::Zero();
  if (!(r > 0.0)) return R;
  R(0, 0) = r;
  R(0, 1) = T.col(0).dot(T.col(1)) / r;
  R(1, 1) = detail::orientation_sign(c, normal) * c.norm() / r;
  return R;
}

/// The oriented orthonormal basis T~ = [t~1 t~2] of section 5.2.1 (t~2 = 0
/// where gamma = 0). T = T~ (T~^T T) whenever gamma != 0.
inline SurfaceTangents oriented_orthonormal_basis(const SurfaceTangents& T, const Eigen::Vector3d& normal) {
  SurfaceTangents Q = SurfaceTangents::Zero();
  const double r = T.col(0).norm();
  if (!(r > 0.0)) return Q;
  Q.col(0) = T.col(0) / r;
  const Eigen::Vector3d w = T.col(1) - T.col(1).dot(Q.col(0)) * Q.col(0);
  const double wn = w.norm();
  if (wn > 0.0) Q.col(1) = tangent_orientation(T, normal) * w / wn;
  return Q;
}

/// J-bar(A, B) of eq 5.5, A oriented by normal_a and B by normal_b.
inline Eigen::Matrix2d surface_jacobian(const SurfaceTangents& A, const Eigen::Vector3d& normal_a,
                                        const SurfaceTangents& B, const Eigen::Vector3d& normal_b) {
  return tangent_plane_coordinates(B, normal_b) * tangent_plane_coordinates(A, normal_a).inverse();
}

/// A 2 x 2 function of B with its first and second derivatives in vec(B):
/// first(i, j) = d vec(F)_i / d vec(B)_j, second[i](j, k) = d^2 vec(F)_i / d vec(B)_j d vec(B)_k,
/// vec column-major on both sides (vec(F) index i + 2 j for F(i, j); vec(B)
/// index a + 3 k for B(a, k)), the flattening of DistortionMeasure's Hessian.
struct SurfaceJacobianJet {
  Eigen::Matrix2d value = Eigen::Matrix2d::Zero();
  Eigen::Matrix<double, 4, 6> first = Eigen::Matrix<double, 4, 6>::Zero();
  std::array<Eigen::Matrix<double, 6, 6>, 4> second{};
};

/// B-bar = B~^T B with its derivatives in B (the file comment's formulas).
/// `second_order` = false skips the second derivatives (left zero).
inline SurfaceJacobianJet tangent_plane_coordinates_jet(const SurfaceTangents& B, const Eigen::Vector3d& normal,
                                                        bool second_order = true) {
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  SurfaceJacobianJet jet;
  for (auto& s : jet.second) s.setZero();
  const Eigen::Vector3d b1 = B.col(0), b2 = B.col(1);
  const Eigen::Vector3d c = b1.cross(b2);
  const double g11 = b1.squaredNorm(), g12 = b1.dot(b2);
  const double r = std::sqrt(g11);
  if (!(r > 0.0)) return jet;
  const double gamma = detail::orientation_sign(c, normal);
  const double delta = c.norm();
  const double s = g12 / r, t = gamma * delta / r;
  jet.value << r, s, 0.0, t;

  // dg_i / d vec(B), rows g11, g12, g22.
  Eigen::Matrix<double, 3, 6> dg;
  dg.row(0) << 2.0 * b1.transpose(), Eigen::RowVector3d::Zero();
  dg.row(1) << b2.transpose(), b1.transpose();
  dg.row(2) << Eigen::RowVector3d::Zero(), 2.0 * b2.transpose();

  // Partial derivatives of r, s, t in (g11, g12, g22).
  const double r3 = r * r * r;
  Eigen::Matrix3d F1 = Eigen::Matrix3d::Zero();  // F1(m, i) = dF_m / dg_i
  std::array<Eigen::Matrix3d, 3> F2{Eigen::Matrix3d::Zero(), Eigen::Matrix3d::Zero(), Eigen::Matrix3d::Zero()};
  F1(0, 0) = 0.5 / r;
  F2[0](0, 0) = -0.25 / r3;
  F1(1, 0) = -0.5 * g12 / r3;
  F1(1, 1) = 1.0 / r;
  F2[1](0, 0) = 0.75 * g12 / (r3 * r * r);
  F2[1](0, 1) = F2[1](1, 0) = -0.5 / r3;
  if (gamma != 0.0 && delta > 0.0) {
    // t = gamma Delta w, Delta = sqrt(D), D = g11 g22 - g12^2, w = g11^(-1/2).
    const double g22 = b2.squaredNorm();
    const Eigen::Vector3d dD(g22, -2.0 * g12, g11);
    Eigen::Matrix3d ddD = Eigen::Matrix3d::Zero();
    ddD(0, 2) = ddD(2, 0) = 1.0;
    ddD(1, 1) = -2.0;
    const Eigen::Vector3d dDelta = dD / (2.0 * delta);
    const Eigen::Matrix3d ddDelta = ddD / (2.0 * delta) - dD * dD.transpose() / (4.0 * delta * delta * delta);
    const double w = 1.0 / r;
    const Eigen::Vector3d dw(-0.5 / r3, 0.0, 0.0);
    Eigen::Matrix3d ddw = Eigen::Matrix3d::Zero();
    ddw(0, 0) = 0.75 / (r3 * r * r);
    F1.row(2) = gamma * (dDelta * w + delta * dw).transpose();
    F2[2] = gamma * (ddDelta * w + dDelta * dw.transpose() + dw * dDelta.transpose() + delta * ddw);
  }
  const Eigen::Matrix<double, 3, 6> dF = F1 * dg;  // rows r, s, t
  // vec(B-bar) = (r, 0, s, t).
  jet.first.row(0) = dF.row(0);
  jet.first.row(2) = dF.row(1);
  jet.first.row(3) = dF.row(2);
  if (!second_order) return jet;
  // d^2 g_i / d vec(B)^2.
  std::array<Mat6, 3> ddg{Mat6::Zero(), Mat6::Zero(), Mat6::Zero()};
  ddg[0].topLeftCorner<3, 3>() = 2.0 * Eigen::Matrix3d::Identity();
  ddg[1].topRightCorner<3, 3>() = Eigen::Matrix3d::Identity();
  ddg[1].bottomLeftCorner<3, 3>() = Eigen::Matrix3d::Identity();
  ddg[2].bottomRightCorner<3, 3>() = 2.0 * Eigen::Matrix3d::Identity();
  const int slot[3] = {0, 2, 3};
  for (int m = 0; m < 3; ++m) {
    Mat6 h = dg.transpose() * F2[m] * dg;
    for (int i = 0; i < 3; ++i) h += F1(m, i) * ddg[i];
    jet.second[slot[m]] = h;
  }
  return jet;
}

namespace detail {

/// J-bar = B-bar K from a B-bar jet (vec(J-bar) = L vec(B-bar), K fixed).
inline SurfaceJacobianJet right_multiply_jet(const SurfaceJacobianJet& b, const Eigen::Matrix2d& K, bool second_order) {
  Eigen::Matrix4d L = Eigen::Matrix4d::Zero();
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i)
      for (int k = 0; k < 2; ++k) L(i + 2 * j, i + 2 * k) = K(k, j);
  SurfaceJacobianJet jet;
  jet.value = b.value * K;
  jet.first = L * b.first;
  for (int i = 0; i < 4; ++i) {
    jet.second[i].setZero();
    if (!second_order) continue;
    for (int m = 0; m < 4; ++m)
      if (L(i, m) != 0.0) jet.second[i] += L(i, m) * b.second[m];
  }
  return jet;
}

}  // namespace detail

/// J-bar(A, B) = B-bar K (eq 5.5), K = (A~^T A)^{-1} fixed (the ideal's), with
/// its derivatives in B: J-bar is linear in B-bar, vec(J-bar) = (K^T (x) I) vec(B-bar).
inline SurfaceJacobianJet surface_jacobian_jet(const Eigen::Matrix2d& ideal_inverse, const SurfaceTangents& B,
                                               const Eigen::Vector3d& normal_b, bool second_order = true) {
  return detail::right_multiply_jet(tangent_plane_coordinates_jet(B, normal_b, second_order), ideal_inverse,
                                    second_order);
}

}  // namespace hom
