#pragma once
/// @file cylinder.hpp
/// Infinite circular cylinder of radius r around the axis through c with unit
/// direction e3, parameterized by angle u in [-pi, pi) (periodic) and height
/// v (unbounded, a length along the axis):
///     S(u, v) = c + r (cos u e1 + sin u e2) + v e3.
/// S_u x S_v points outward. Closest-point projection is radial from the
/// axis (u = 0 on the axis itself). Models SurfaceGeometry.

#include <cmath>
#include <numbers>
#include <stdexcept>

#include <Eigen/Core>

#include "hom/detail/orthonormal_frame.hpp"
#include "hom/geometry/surface_geometry.hpp"

namespace hom {

class Cylinder {
 public:
  Cylinder(const Eigen::Vector3d& axis_point, const Eigen::Vector3d& axis, double radius,
           const Eigen::Vector3d& u_direction = Eigen::Vector3d::Zero())
      : center_(axis_point), radius_(radius), frame_(axis, u_direction) {
    if (!(radius > 0.0) || !std::isfinite(radius)) throw std::invalid_argument("hom::Cylinder: radius must be positive");
  }

  const Eigen::Vector3d& axis_point() const { return center_; }
  const Eigen::Vector3d& axis() const { return frame_.e3; }
  double radius() const { return radius_; }

  Eigen::Vector3d evaluate(const Eigen::Vector2d& uv) const {
    return center_ + radius_ * (std::cos(uv[0]) * frame_.e1 + std::sin(uv[0]) * frame_.e2) + uv[1] * frame_.e3;
  }
  Eigen::Matrix<double, 3, 2> derivatives(const Eigen::Vector2d& uv) const {
    Eigen::Matrix<double, 3, 2> d;
    d.col(0) = radius_ * (-std::sin(uv[0]) * frame_.e1 + std::cos(uv[0]) * frame_.e2);
    d.col(1) = frame_.e3;
    return d;
  }
  SurfaceSecondDerivatives second_derivatives(const Eigen::Vector2d& uv) const {
    SurfaceSecondDerivatives s;
    s.uu = -radius_ * (std::cos(uv[0]) * frame_.e1 + std::sin(uv[0]) * frame_.e2);
    return s;
  }
  Eigen::Vector2d project(const Eigen::Vector3d& x) const {
    const Eigen::Vector3d d = frame_.local(x - center_);
    const double u = d[0] == 0.0 && d[1] == 0.0 ? 0.0 : range(0).normalize(std::atan2(d[1], d[0]));
    return {u, d[2]};
  }
  ParameterRange range(int k) const {
    return k == 0 ? ParameterRange{-std::numbers::pi, std::numbers::pi, true} : unbounded_range();
  }

 private:
  Eigen::Vector3d center_;
  double radius_;
  detail::OrthonormalFrame frame_;
};

static_assert(SurfaceGeometry<Cylinder>);

}  // namespace hom
