#pragma once
/// @file parametric_surface.hpp
/// A surface given by its parameterization as callables: S(u, v), its 3 x 2
/// Jacobian [S_u S_v] and its second derivatives, with the ranges of u and v.
/// For test parameterizations (the thesis's phi^1, phi^2 of section 5.5.1.2,
/// thesis_parameterizations.hpp) and any analytic surface a user writes down
/// without a class of its own:
///
///     hom::ParametricSurface s(
///         [](const Eigen::Vector2d& p) { return Eigen::Vector3d(p[0], p[1], p[0] * p[1]); },
///         [](const Eigen::Vector2d& p) { Eigen::Matrix<double, 3, 2> d; d << 1, 0, 0, 1, p[1], p[0]; return d; },
///         [](const Eigen::Vector2d&) { hom::SurfaceSecondDerivatives s; s.uv = Eigen::Vector3d::UnitZ(); return s; },
///         {-1, 1, false}, {-1, 1, false});
///
/// The derivatives are the caller's responsibility (check them with finite
/// differences: test/test_surface_quality.cpp does for the thesis's models).
/// Closest point: the best sample of a 16 x 16 grid over the parameter box
/// (an unbounded range is sampled on [-1, 1]), refined by Newton's method
/// (detail/surface_projection.hpp), clamped to bounded ranges. Models
/// SurfaceGeometry.

#include <functional>
#include <utility>

#include <Eigen/Core>

#include "hom/detail/surface_projection.hpp"
#include "hom/geometry/parameter_range.hpp"
#include "hom/geometry/surface_geometry.hpp"

namespace hom {

class ParametricSurface {
 public:
  using Value = std::function<Eigen::Vector3d(const Eigen::Vector2d&)>;
  using Derivatives = std::function<Eigen::Matrix<double, 3, 2>(const Eigen::Vector2d&)>;
  using SecondDerivatives = std::function<SurfaceSecondDerivatives(const Eigen::Vector2d&)>;

  ParametricSurface(Value value, Derivatives derivatives, SecondDerivatives second_derivatives, ParameterRange u_range,
                    ParameterRange v_range)
      : value_(std::move(value)),
        derivatives_(std::move(derivatives)),
        second_(std::move(second_derivatives)),
        range_{u_range, v_range} {}

  Eigen::Vector3d evaluate(const Eigen::Vector2d& uv) const { return value_(uv); }
  Eigen::Matrix<double, 3, 2> derivatives(const Eigen::Vector2d& uv) const { return derivatives_(uv); }
  SurfaceSecondDerivatives second_derivatives(const Eigen::Vector2d& uv) const { return second_(uv); }
  Eigen::Vector2d project(const Eigen::Vector3d& x) const { return detail::closest_point_sampled(*this, x); }
  ParameterRange range(int k) const { return range_[k]; }

 private:
  Value value_;
  Derivatives derivatives_;
  SecondDerivatives second_;
  ParameterRange range_[2];
};

static_assert(SurfaceGeometry<ParametricSurface>);

}  // namespace hom
