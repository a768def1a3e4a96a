#pragma once
/// @file line.hpp
/// Straight line C(u) = a + u t in R^SpaceDim, t the unit direction, so u is
/// arc length from a. Models CurveGeometry with an unbounded parameter (the
/// straight edges of a box, straight boundaries of planar domains).

#include <cmath>
#include <stdexcept>

#include <Eigen/Core>

#include "hom/geometry/curve_geometry.hpp"

namespace hom {

template <int SpaceDim>
class Line {
  static_assert(SpaceDim == 2 || SpaceDim == 3, "hom::Line: SpaceDim must be 2 or 3");

 public:
  static constexpr int space_dim = SpaceDim;
  using Point = Eigen::Matrix<double, SpaceDim, 1>;

  /// The line through a and b (a != b), parameterized by arc length from a.
  Line(const Point& a, const Point& b) : origin_(a), direction_(b - a) {
    const double n = direction_.norm();
    if (!(n > 0.0)) throw std::invalid_argument("hom::Line: the two points must differ");
    direction_ /= n;
  }

  const Point& origin() const { return origin_; }
  const Point& direction() const { return direction_; }

  Point evaluate(double u) const { return origin_ + u * direction_; }
  Point derivative(double) const { return direction_; }
  Point second_derivative(double) const { return Point::Zero(); }
  double project(const Point& x) const { return (x - origin_).dot(direction_); }
  ParameterRange range() const { return unbounded_range(); }

 private:
  Point origin_;
  Point direction_;
};

static_assert(CurveGeometry<Line<2>>);
static_assert(CurveGeometry<Line<3>>);

}  // namespace hom
