#pragma once
/// @file torus.hpp
/// Ring torus (major radius R > minor radius r > 0) around the axis e3
/// through c, parameterized by u in [-pi, pi) around the axis and v in
/// [-pi, pi) around the tube, both periodic:
///     S(u, v) = c + (R + r cos v)(cos u e1 + sin u e2) + r sin v e3.
/// Closest point of x: u is the angle of x around the axis, then the closest
/// point of the tube circle in the half-plane of angle u (v = angle of x from
/// the tube centre). Points on the axis or on the tube's centre circle have
/// several closest points; project returns one. Models SurfaceGeometry.

#include <cmath>
#include <numbers>
#include <stdexcept>

#include <Eigen/Core>

#include "hom/detail/orthonormal_frame.hpp"
#include "hom/geometry/surface_geometry.hpp"

namespace hom {

class Torus {
 public:
  Torus(const Eigen::Vector3d& center, const Eigen::Vector3d& axis, double major_radius, double minor_radius,
        const Eigen::Vector3d& u_direction = Eigen::Vector3d::Zero())
      : center_(center), R_(major_radius), r_(minor_radius), frame_(axis, u_direction) {
    if (!(minor_radius > 0.0) || !(major_radius > minor_radius) || !std::isfinite(major_radius))
      throw std::invalid_argument("hom::Torus: needs major radius > minor radius > 0");
  }

  const Eigen::Vector3d& center() const { return center_; }
  double major_radius() const { return R_; }
  double minor_radius() const { return r_; }

  Eigen::Vector3d evaluate(const Eigen::Vector2d& uv) const {
    return center_ + (R_ + r_ * std::cos(uv[1])) * radial(uv[0]) + r_ * std::sin(uv[1]) * frame_.e3;
  }
  Eigen::Matrix<double, 3, 2> derivatives(const Eigen::Vector2d& uv) const {
    Eigen::Matrix<double, 3, 2> d;
    d.col(0) = (R_ + r_ * std::cos(uv[1])) * tangential(uv[0]);
    d.col(1) = -r_ * std::sin(uv[1]) * radial(uv[0]) + r_ * std::cos(uv[1]) * frame_.e3;
    return d;
  }
  SurfaceSecondDerivatives second_derivatives(const Eigen::Vector2d& uv) const {
    SurfaceSecondDerivatives s;
    s.uu = -(R_ + r_ * std::cos(uv[1])) * radial(uv[0]);
    s.uv = -r_ * std::sin(uv[1]) * tangential(uv[0]);
    s.vv = -r_ * std::cos(uv[1]) * radial(uv[0]) - r_ * std::sin(uv[1]) * frame_.e3;
    return s;
  }
  Eigen::Vector2d project(const Eigen::Vector3d& x) const {
    const Eigen::Vector3d d = frame_.local(x - center_);
    const double rho = std::hypot(d[0], d[1]);
    const double u = rho == 0.0 ? 0.0 : range(0).normalize(std::atan2(d[1], d[0]));
    const double a = rho - R_, b = d[2];
    const double v = a == 0.0 && b == 0.0 ? 0.0 : range(1).normalize(std::atan2(b, a));
    return {u, v};
  }
  ParameterRange range(int) const { return {-std::numbers::pi, std::numbers::pi, true}; }

 private:
  Eigen::Vector3d radial(double u) const { return std::cos(u) * frame_.e1 + std::sin(u) * frame_.e2; }
  Eigen::Vector3d tangential(double u) const { return -std::sin(u) * frame_.e1 + std::cos(u) * frame_.e2; }

  Eigen::Vector3d center_;
  double R_, r_;
  detail::OrthonormalFrame frame_;
};

static_assert(SurfaceGeometry<Torus>);

}  // namespace hom
