#pragma once
/// @file plane.hpp
/// Plane S(u, v) = o + u e1 + v e2 with (e1, e2, n) a right-handed orthonormal
/// frame, so the parameters are lengths and S_u x S_v = n. Models
/// SurfaceGeometry; both parameters are unbounded.

#include <Eigen/Core>

#include "hom/detail/orthonormal_frame.hpp"
#include "hom/geometry/surface_geometry.hpp"

namespace hom {

class Plane {
 public:
  /// The plane through `origin` with normal `normal` (any length > 0); the u
  /// axis is `u_direction` projected onto the plane (a default one if zero).
  Plane(const Eigen::Vector3d& origin, const Eigen::Vector3d& normal,
        const Eigen::Vector3d& u_direction = Eigen::Vector3d::Zero())
      : origin_(origin), frame_(normal, u_direction) {}

  const Eigen::Vector3d& origin() const { return origin_; }
  const Eigen::Vector3d& normal() const { return frame_.e3; }

  Eigen::Vector3d evaluate(const Eigen::Vector2d& uv) const { return origin_ + uv[0] * frame_.e1 + uv[1] * frame_.e2; }
  Eigen::Matrix<double, 3, 2> derivatives(const Eigen::Vector2d&) const {
    Eigen::Matrix<double, 3, 2> d;
    d << frame_.e1, frame_.e2;
    return d;
  }
  SurfaceSecondDerivatives second_derivatives(const Eigen::Vector2d&) const { return {}; }
  /// Orthogonal projection: the in-plane coordinates of x - o.
  Eigen::Vector2d project(const Eigen::Vector3d& x) const {
    const Eigen::Vector3d d = x - origin_;
    return {d.dot(frame_.e1), d.dot(frame_.e2)};
  }
  ParameterRange range(int) const { return unbounded_range(); }

 private:
  Eigen::Vector3d origin_;
  detail::OrthonormalFrame frame_;
};

static_assert(SurfaceGeometry<Plane>);

}  // namespace hom
