#pragma once
/// @file surface_geometry.hpp
/// Concept SurfaceGeometry: a parametric surface S(u, v) in R^3 that the
/// boundary faces of a volume mesh (or the elements of a surface mesh) lie on.
///
/// A model G provides
///   - `evaluate(uv)`: S(u, v), uv an Eigen::Vector2d;
///   - `derivatives(uv)`: the 3 x 2 matrix [S_u S_v] (the surface Jacobian
///     that chapter 5 composes with, eq 5.5);
///   - `second_derivatives(uv)`: S_uu, S_uv, S_vv (SurfaceSecondDerivatives);
///   - `project(x)`: the parameters of a closest point of S to x (periodic
///     parameters in their range; any one where the closest point is not
///     unique, e.g. the centre of a sphere);
///   - `range(k)`, k = 0, 1: the ParameterRange of u and of v.
///
/// Models: Plane, Sphere, Cylinder, Torus (geometry/*.hpp); OpenCASCADE faces
/// (src/cad) model it too.

#include <concepts>

#include <Eigen/Core>

#include "hom/geometry/parameter_range.hpp"

namespace hom {

struct SurfaceSecondDerivatives {
  Eigen::Vector3d uu = Eigen::Vector3d::Zero();
  Eigen::Vector3d uv = Eigen::Vector3d::Zero();
  Eigen::Vector3d vv = Eigen::Vector3d::Zero();
};

template <class G>
concept SurfaceGeometry = requires(const G& g, const Eigen::Vector2d& uv, const Eigen::Vector3d& x, int k) {
  { g.evaluate(uv) } -> std::convertible_to<Eigen::Vector3d>;
  { g.derivatives(uv) } -> std::convertible_to<Eigen::Matrix<double, 3, 2>>;
  { g.second_derivatives(uv) } -> std::convertible_to<SurfaceSecondDerivatives>;
  { g.project(x) } -> std::convertible_to<Eigen::Vector2d>;
  { g.range(k) } -> std::convertible_to<ParameterRange>;
};

}  // namespace hom
