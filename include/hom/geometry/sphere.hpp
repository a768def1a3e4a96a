#pragma once
/// @file sphere.hpp
/// Sphere of centre c and radius r, parameterized by longitude u in
/// [-pi, pi) (periodic) and latitude v in [-pi/2, pi/2]:
///     S(u, v) = c + r (cos v cos u e1 + cos v sin u e2 + sin v e3),
/// with (e1, e2, e3) a right-handed orthonormal frame, e3 the polar axis
/// (z by default). S_u x S_v points outward; the map is singular at the poles
/// v = +-pi/2 (S_u = 0), where project returns u = 0. Closest-point
/// projection is radial. Models SurfaceGeometry.

#include <cmath>
#include <numbers>
#include <stdexcept>

#include <Eigen/Core>

#include "hom/detail/orthonormal_frame.hpp"
#include "hom/geometry/surface_geometry.hpp"

namespace hom {

class Sphere {
 public:
  Sphere(const Eigen::Vector3d& center, double radius, const Eigen::Vector3d& axis = Eigen::Vector3d::UnitZ(),
         const Eigen::Vector3d& u_direction = Eigen::Vector3d::Zero())
      : center_(center), radius_(radius), frame_(axis, u_direction) {
    if (!(radius > 0.0) || !std::isfinite(radius)) throw std::invalid_argument("hom::Sphere: radius must be positive");
  }

  const Eigen::Vector3d& center() const { return center_; }
  double radius() const { return radius_; }

  Eigen::Vector3d evaluate(const Eigen::Vector2d& uv) const { return center_ + radius_ * direction(uv[0], uv[1]); }

  Eigen::Matrix<double, 3, 2> derivatives(const Eigen::Vector2d& uv) const {
    const double cu = std::cos(uv[0]), su = std::sin(uv[0]), cv = std::cos(uv[1]), sv = std::sin(uv[1]);
    Eigen::Matrix<double, 3, 2> d;
    d.col(0) = radius_ * cv * (-su * frame_.e1 + cu * frame_.e2);
    d.col(1) = radius_ * (-sv * cu * frame_.e1 - sv * su * frame_.e2 + cv * frame_.e3);
    return d;
  }

  SurfaceSecondDerivatives second_derivatives(const Eigen::Vector2d& uv) const {
    const double cu = std::cos(uv[0]), su = std::sin(uv[0]), cv = std::cos(uv[1]), sv = std::sin(uv[1]);
    SurfaceSecondDerivatives s;
    s.uu = -radius_ * cv * (cu * frame_.e1 + su * frame_.e2);
    s.uv = radius_ * sv * (su * frame_.e1 - cu * frame_.e2);
    s.vv = -radius_ * direction(uv[0], uv[1]);
    return s;
  }

  /// Radial projection: the parameters of the direction of x - c (u = v = 0
  /// at the centre, where every point is closest).
  Eigen::Vector2d project(const Eigen::Vector3d& x) const {
    const Eigen::Vector3d d = frame_.local(x - center_);
    const double rho = std::hypot(d[0], d[1]);
    if (rho == 0.0 && d[2] == 0.0) return Eigen::Vector2d::Zero();
    const double u = rho == 0.0 ? 0.0 : range(0).normalize(std::atan2(d[1], d[0]));
    return {u, std::atan2(d[2], rho)};
  }

  ParameterRange range(int k) const {
    return k == 0 ? ParameterRange{-std::numbers::pi, std::numbers::pi, true}
                  : ParameterRange{-std::numbers::pi / 2, std::numbers::pi / 2, false};
  }

 private:
  Eigen::Vector3d direction(double u, double v) const {
    return std::cos(v) * (std::cos(u) * frame_.e1 + std::sin(u) * frame_.e2) + std::sin(v) * frame_.e3;
  }

  Eigen::Vector3d center_;
  double radius_;
  detail::OrthonormalFrame frame_;
};

static_assert(SurfaceGeometry<Sphere>);

}  // namespace hom
