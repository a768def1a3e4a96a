#pragma once
/// @file hyperbolic_paraboloid.hpp
/// Hyperbolic paraboloid (saddle), the graph over the (e1, e2) plane through
/// the origin o with axis e3:
///     S(u, v) = o + u e1 + v e2 + (u^2 / a^2 - v^2 / b^2) e3,
/// u, v unbounded (lengths along e1, e2). At the saddle point o its principal
/// curvatures are 2/a^2 and -2/b^2; a = b gives the surface of appendix F
/// (figures F.3, F.4). S_u x S_v has a positive e3 component everywhere.
/// Closest point: Newton's method (detail/surface_projection.hpp) started from
/// the orthogonal projection onto the (e1, e2) plane. Models SurfaceGeometry.

#include <cmath>
#include <stdexcept>

#include <Eigen/Core>

#include "hom/detail/orthonormal_frame.hpp"
#include "hom/detail/surface_projection.hpp"
#include "hom/geometry/surface_geometry.hpp"

namespace hom {

class HyperbolicParaboloid {
 public:
  HyperbolicParaboloid(const Eigen::Vector3d& origin = Eigen::Vector3d::Zero(),
                       const Eigen::Vector3d& axis = Eigen::Vector3d::UnitZ(), double a = 1.0, double b = 1.0,
                       const Eigen::Vector3d& u_direction = Eigen::Vector3d::Zero())
      : origin_(origin), ka_(1.0 / (a * a)), kb_(1.0 / (b * b)), frame_(axis, u_direction) {
    if (!(a > 0.0) || !(b > 0.0) || !std::isfinite(a) || !std::isfinite(b))
      throw std::invalid_argument("hom::HyperbolicParaboloid: a and b must be positive");
  }

  const Eigen::Vector3d& origin() const { return origin_; }
  const Eigen::Vector3d& axis() const { return frame_.e3; }

  Eigen::Vector3d evaluate(const Eigen::Vector2d& uv) const {
    return origin_ + uv[0] * frame_.e1 + uv[1] * frame_.e2 + height(uv) * frame_.e3;
  }
  Eigen::Matrix<double, 3, 2> derivatives(const Eigen::Vector2d& uv) const {
    Eigen::Matrix<double, 3, 2> d;
    d.col(0) = frame_.e1 + 2.0 * ka_ * uv[0] * frame_.e3;
    d.col(1) = frame_.e2 - 2.0 * kb_ * uv[1] * frame_.e3;
    return d;
  }
  SurfaceSecondDerivatives second_derivatives(const Eigen::Vector2d&) const {
    SurfaceSecondDerivatives s;
    s.uu = 2.0 * ka_ * frame_.e3;
    s.vv = -2.0 * kb_ * frame_.e3;
    return s;
  }
  Eigen::Vector2d project(const Eigen::Vector3d& x) const {
    const Eigen::Vector3d d = frame_.local(x - origin_);
    return detail::closest_point_newton(*this, x, Eigen::Vector2d(d[0], d[1]));
  }
  ParameterRange range(int) const { return unbounded_range(); }

 private:
  double height(const Eigen::Vector2d& uv) const { return ka_ * uv[0] * uv[0] - kb_ * uv[1] * uv[1]; }

  Eigen::Vector3d origin_;
  double ka_, kb_;  ///< 1/a^2, 1/b^2
  detail::OrthonormalFrame frame_;
};

static_assert(SurfaceGeometry<HyperbolicParaboloid>);

}  // namespace hom
