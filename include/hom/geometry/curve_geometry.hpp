#pragma once
/// @file curve_geometry.hpp
/// Concept CurveGeometry: a parametric curve C(u) in R^SpaceDim that a mesh
/// boundary (2D meshes) or a mesh edge (3D meshes, a CAD edge) lies on.
///
/// A model G provides
///   - `static constexpr int space_dim` (2 or 3) and `using Point =
///     Eigen::Matrix<double, space_dim, 1>`;
///   - `evaluate(u)`: C(u);
///   - `derivative(u)`, `second_derivative(u)`: C'(u), C''(u);
///   - `project(x)`: the parameter u* of a closest point of the curve to x,
///     i.e. argmin_u |C(u) - x| (for a periodic parameter the representative
///     in range(); where the closest point is not unique, for example the
///     centre of a circle, any one of them);
///   - `range()`: the ParameterRange of u (bounds, periodicity).
///
/// Models: Line, Circle (geometry/line.hpp, circle.hpp); OpenCASCADE edges
/// (src/cad) model it too.

#include <concepts>

#include <Eigen/Core>

#include "hom/geometry/parameter_range.hpp"

namespace hom {

template <class G>
concept CurveGeometry = requires(const G& g, double u, const typename G::Point& x) {
  requires G::space_dim == 2 || G::space_dim == 3;
  requires std::same_as<typename G::Point, Eigen::Matrix<double, G::space_dim, 1>>;
  { g.evaluate(u) } -> std::convertible_to<typename G::Point>;
  { g.derivative(u) } -> std::convertible_to<typename G::Point>;
  { g.second_derivative(u) } -> std::convertible_to<typename G::Point>;
  { g.project(x) } -> std::convertible_to<double>;
  { g.range() } -> std::convertible_to<ParameterRange>;
};

}  // namespace hom
