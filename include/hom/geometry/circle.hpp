#pragma once
/// @file circle.hpp
/// Circle C(u) = c + r (cos u e1 + sin u e2), u in [-pi, pi) periodic: in
/// the plane (SpaceDim = 2, e1 = x, e2 = y, counter-clockwise) or in space
/// (SpaceDim = 3, (e1, e2) spanning the plane orthogonal to a given normal).
/// Models CurveGeometry; u is the angle, so |C'(u)| = r.

#include <cmath>
#include <numbers>
#include <stdexcept>

#include <Eigen/Core>

#include "hom/detail/orthonormal_frame.hpp"
#include "hom/geometry/curve_geometry.hpp"

namespace hom {

template <int SpaceDim = 2>
class Circle {
  static_assert(SpaceDim == 2 || SpaceDim == 3, "hom::Circle: SpaceDim must be 2 or 3");

 public:
  static constexpr int space_dim = SpaceDim;
  using Point = Eigen::Matrix<double, SpaceDim, 1>;

  /// Planar circle (SpaceDim = 2).
  Circle(const Point& center, double radius)
    requires(SpaceDim == 2)
      : center_(center), radius_(radius), e1_(Point::UnitX()), e2_(Point::UnitY()) {
    check_radius();
  }
  /// Circle in space around `normal` (right-handed: u increases
  /// counter-clockwise seen from the tip of the normal); u = 0 towards
  /// `u_direction` projected onto the circle's plane (a default one if zero).
  Circle(const Point& center, double radius, const Eigen::Vector3d& normal,
         const Eigen::Vector3d& u_direction = Eigen::Vector3d::Zero())
    requires(SpaceDim == 3)
      : center_(center), radius_(radius) {
    check_radius();
    const detail::OrthonormalFrame f(normal, u_direction);
    e1_ = f.e1;
    e2_ = f.e2;
  }

  const Point& center() const { return center_; }
  double radius() const { return radius_; }

  Point evaluate(double u) const { return center_ + radius_ * (std::cos(u) * e1_ + std::sin(u) * e2_); }
  Point derivative(double u) const { return radius_ * (-std::sin(u) * e1_ + std::cos(u) * e2_); }
  Point second_derivative(double u) const { return -radius_ * (std::cos(u) * e1_ + std::sin(u) * e2_); }
  /// The angle of x's component in the circle's plane (0 at the centre or on
  /// the axis, where every point of the circle is closest).
  double project(const Point& x) const {
    const Point d = x - center_;
    const double a = d.dot(e1_), b = d.dot(e2_);
    if (a == 0.0 && b == 0.0) return 0.0;
    return range().normalize(std::atan2(b, a));
  }
  ParameterRange range() const { return {-std::numbers::pi, std::numbers::pi, true}; }

 private:
  void check_radius() const {
    if (!(radius_ > 0.0) || !std::isfinite(radius_)) throw std::invalid_argument("hom::Circle: radius must be positive");
  }

  Point center_;
  double radius_;
  Point e1_, e2_;
};

static_assert(CurveGeometry<Circle<2>>);
static_assert(CurveGeometry<Circle<3>>);

}  // namespace hom
