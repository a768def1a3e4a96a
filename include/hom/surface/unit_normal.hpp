#pragma once
/// @file unit_normal.hpp
/// The unit normal S_u x S_v / |S_u x S_v| of a parameterized surface at the
/// nodes of an element, as the surface measure (eq 5.5, its sign gamma) and
/// the surface certificate (certified_surface.hpp) orient elements by it.
///
/// Degenerate points. Where the parameterization degenerates (a pole of a
/// sphere, the collapsed edge of a NURBS patch: S_u or S_v vanishes), the
/// cross product is zero or round-off, and its direction means nothing,
/// although the surface itself may be smooth there. A node at such a point
/// takes the normal's limit from inside its element: the normal at the
/// parameters moved a small fraction of the way towards the element's mean
/// parameters. On a smooth surface this limit is the surface's normal,
/// whichever element it is taken from.

#include <Eigen/Core>

#include "hom/geometry/surface_geometry.hpp"

namespace hom {

/// Unit S_u x S_v at u; zero where the parameterization degenerates there
/// (|S_u x S_v| <= 1e-12 (|S_u|^2 + |S_v|^2): a cross product of round-off size).
template <SurfaceGeometry Surface>
Eigen::Vector3d unit_normal(const Surface& surface, const Eigen::Vector2d& u) {
  const Eigen::Matrix<double, 3, 2> d = surface.derivatives(u);
  const Eigen::Vector3d c = d.col(0).cross(d.col(1));
  const double l = c.norm();
  return l > 1e-12 * d.squaredNorm() ? Eigen::Vector3d(c / l) : Eigen::Vector3d::Zero();
}

/// unit_normal at u, or at a degenerate point its limit from the direction
/// of `inside` (parameters inside the element); zero if that is degenerate too.
/// Periodic parameters of `inside` are taken next to u's, so the step does
/// not run the long way round a seam.
template <SurfaceGeometry Surface>
Eigen::Vector3d unit_normal_from(const Surface& surface, const Eigen::Vector2d& u, const Eigen::Vector2d& inside) {
  const Eigen::Vector3d n = unit_normal(surface, u);
  if (n.squaredNorm() > 0.0) return n;
  Eigen::Vector2d towards;
  for (int k = 0; k < 2; ++k) towards[k] = surface.range(k).unwrap(inside[k], u[k]) - u[k];
  constexpr double step = 1e-6;  // of the way to `inside`: far above round-off, a negligible tilt of the normal
  return unit_normal(surface, Eigen::Vector2d(u + step * towards));
}

/// The mean of an element's node parameters UV (2 x n), periodic ones
/// unwrapped next to node 0's: a point inside the element even when its
/// nodes straddle a seam.
template <SurfaceGeometry Surface>
Eigen::Vector2d mean_parameters(const Surface& surface, const Eigen::Ref<const Eigen::Matrix2Xd>& UV) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (int k = 0; k < 2; ++k) {
    const ParameterRange range = surface.range(k);
    for (Eigen::Index i = 0; i < UV.cols(); ++i) mean[k] += range.unwrap(UV(k, i), UV(k, 0));
  }
  return mean / double(UV.cols());
}

/// unit_normal_from at each node of an element with parameters UV (2 x n),
/// from the direction of the element's mean parameters.
template <SurfaceGeometry Surface>
Eigen::Matrix3Xd element_unit_normals(const Surface& surface, const Eigen::Ref<const Eigen::Matrix2Xd>& UV) {
  const Eigen::Vector2d mean = mean_parameters(surface, UV);
  Eigen::Matrix3Xd nu(3, UV.cols());
  for (Eigen::Index i = 0; i < UV.cols(); ++i) nu.col(i) = unit_normal_from(surface, UV.col(i), mean);
  return nu;
}

/// Each column of n (3 x m, interpolated nodal normals) scaled to unit
/// length, or zero where it vanishes.
inline void normalize_or_zero(Eigen::Matrix3Xd& n) {
  for (Eigen::Index q = 0; q < n.cols(); ++q) {
    const double l = n.col(q).norm();
    n.col(q) = l > 0.0 ? Eigen::Vector3d(n.col(q) / l) : Eigen::Vector3d::Zero();
  }
}

}  // namespace hom
