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
/// whichever element it is taken from. At a cone's apex (the tip of a
/// fuselage of revolution) it is not: the normal turns with the angle around
/// the axis, the parameter whose derivative vanishes there, so the node's
/// own value of it (arbitrary: every value gives the apex) is replaced by
/// the mean of the element's other nodes' (free_parameters,
/// parameters_at_poles). Otherwise a fan element at the apex is oriented by
/// the normal of the cone's far side and scores folded however fine the mesh.

#include <algorithm>
#include <array>
#include <vector>

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

namespace detail {

/// Which parameters are free at u: those whose derivative vanishes there
/// (|S_k| <= 1e-8 |S_other|), so that changing them does not move the point.
template <SurfaceGeometry Surface>
std::array<bool, 2> free_parameters(const Surface& surface, const Eigen::Vector2d& u) {
  const Eigen::Matrix<double, 3, 2> d = surface.derivatives(u);
  const double su = d.col(0).norm(), sv = d.col(1).norm();
  return {su <= 1e-8 * sv, sv <= 1e-8 * su};
}

}  // namespace detail

/// unit_normal at u, or at a degenerate point its limit from the direction
/// of `inside` (parameters inside the element); zero if that is degenerate too.
/// The free parameters of a degenerate point are inside's (the same point),
/// so the limit is taken along the element, not along the node's arbitrary
/// value of them. Periodic parameters of `inside` are taken next to u's, so
/// the step does not run the long way round a seam.
template <SurfaceGeometry Surface>
Eigen::Vector3d unit_normal_from(const Surface& surface, const Eigen::Vector2d& u, const Eigen::Vector2d& inside) {
  const Eigen::Vector3d n = unit_normal(surface, u);
  if (n.squaredNorm() > 0.0) return n;
  const auto free = detail::free_parameters(surface, u);
  Eigen::Vector2d from = u, towards;
  for (int k = 0; k < 2; ++k) {
    const double target = surface.range(k).unwrap(inside[k], u[k]);
    if (free[k]) from[k] = target;
    towards[k] = target - from[k];
  }
  constexpr double step = 1e-6;  // of the way to `inside`: far above round-off, a negligible tilt of the normal
  return unit_normal(surface, Eigen::Vector2d(from + step * towards));
}

/// The mean of an element's node parameters UV (2 x n), periodic ones
/// unwrapped next to the first counted node's: a point inside the element
/// even when its nodes straddle a seam. Only the nodes where `counted` is
/// true count (all when none is).
template <SurfaceGeometry Surface>
Eigen::Vector2d mean_parameters(const Surface& surface, const Eigen::Ref<const Eigen::Matrix2Xd>& UV,
                                const std::vector<bool>& counted) {
  const bool any = std::find(counted.begin(), counted.end(), true) != counted.end();
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  int n = 0, first = -1;
  for (Eigen::Index i = 0; i < UV.cols(); ++i) {
    if (any && !counted[std::size_t(i)]) continue;
    if (first < 0) first = int(i);
    for (int k = 0; k < 2; ++k) mean[k] += surface.range(k).unwrap(UV(k, i), UV(k, first));
    ++n;
  }
  return n > 0 ? Eigen::Vector2d(mean / double(n)) : mean;
}

/// mean_parameters over all the nodes.
template <SurfaceGeometry Surface>
Eigen::Vector2d mean_parameters(const Surface& surface, const Eigen::Ref<const Eigen::Matrix2Xd>& UV) {
  return mean_parameters(surface, UV, std::vector<bool>(std::size_t(UV.cols()), true));
}

/// unit_normal at each node of an element with parameters UV (2 x n): zero
/// at the nodes at a degenerate point (fill_degenerate_normals completes them).
template <SurfaceGeometry Surface>
Eigen::Matrix3Xd nodal_unit_normals(const Surface& surface, const Eigen::Ref<const Eigen::Matrix2Xd>& UV) {
  Eigen::Matrix3Xd nu(3, UV.cols());
  for (Eigen::Index i = 0; i < UV.cols(); ++i) nu.col(i) = unit_normal(surface, Eigen::Vector2d(UV.col(i)));
  return nu;
}

/// Which columns of nu (3 x n, nodal_unit_normals) are normals, not the zero
/// of a degenerate point.
inline std::vector<bool> nodes_with_normal(const Eigen::Ref<const Eigen::Matrix3Xd>& nu) {
  std::vector<bool> regular(std::size_t(nu.cols()));
  for (Eigen::Index i = 0; i < nu.cols(); ++i) regular[std::size_t(i)] = nu.col(i).squaredNorm() > 0.0;
  return regular;
}

/// UV (2 x n) with the free parameters of each node at a degenerate point (a
/// pole, a cone's apex; `regular` false there, nodes_with_normal) set to the
/// mean of the regular nodes', and periodic parameters unwrapped next to the
/// first regular node: the same points, but parameters that follow the
/// element, so that interpolating them (the normals at the quadrature points)
/// does. (An unwrapping next to the pole node's arbitrary angle could send
/// the element the long way round.) UV itself where every node or none is regular.
template <SurfaceGeometry Surface>
Eigen::Matrix2Xd parameters_at_poles(const Surface& surface, const Eigen::Ref<const Eigen::Matrix2Xd>& UV,
                                     const std::vector<bool>& regular) {
  Eigen::Matrix2Xd U = UV;
  const auto first = std::find(regular.begin(), regular.end(), true);
  const bool all_regular = std::find(regular.begin(), regular.end(), false) == regular.end();
  if (first == regular.end() || all_regular) return U;
  const Eigen::Vector2d ref = UV.col(first - regular.begin());
  const Eigen::Vector2d mean = mean_parameters(surface, UV, regular);
  for (Eigen::Index i = 0; i < UV.cols(); ++i) {
    const auto free = regular[std::size_t(i)] ? std::array<bool, 2>{false, false}
                                              : detail::free_parameters(surface, Eigen::Vector2d(UV.col(i)));
    for (int k = 0; k < 2; ++k) U(k, i) = surface.range(k).unwrap(free[k] ? mean[k] : UV(k, i), ref[k]);
  }
  return U;
}

/// Replaces the zero columns of nu (3 x n, the normals at the nodes of an
/// element with parameters UV; `regular` = nodes_with_normal(nu)) by the
/// limit from inside the element (unit_normal_from), in the direction of
/// the mean parameters of its regular nodes.
template <SurfaceGeometry Surface>
void fill_degenerate_normals(const Surface& surface, const Eigen::Ref<const Eigen::Matrix2Xd>& UV,
                             const std::vector<bool>& regular, Eigen::Matrix3Xd& nu) {
  if (std::find(regular.begin(), regular.end(), false) == regular.end()) return;
  const Eigen::Vector2d mean = mean_parameters(surface, UV, regular);
  for (Eigen::Index i = 0; i < UV.cols(); ++i)
    if (!regular[std::size_t(i)]) nu.col(i) = unit_normal_from(surface, Eigen::Vector2d(UV.col(i)), mean);
}

/// unit_normal_from at each node of an element with parameters UV (2 x n),
/// from the direction of the mean parameters of its nodes with a normal.
template <SurfaceGeometry Surface>
Eigen::Matrix3Xd element_unit_normals(const Surface& surface, const Eigen::Ref<const Eigen::Matrix2Xd>& UV) {
  Eigen::Matrix3Xd nu = nodal_unit_normals(surface, UV);
  fill_degenerate_normals(surface, UV, nodes_with_normal(nu), nu);
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
