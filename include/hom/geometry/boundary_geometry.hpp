#pragma once
/// @file boundary_geometry.hpp
/// Concept BoundaryGeometry: what a geometric entity a mesh boundary is
/// classified on must model, a curve (CurveGeometry) or a surface
/// (SurfaceGeometry). `parametric_dim<G>` is 1 or 2 accordingly.

#include "hom/geometry/curve_geometry.hpp"
#include "hom/geometry/surface_geometry.hpp"

namespace hom {

template <class G>
concept BoundaryGeometry = CurveGeometry<G> || SurfaceGeometry<G>;

template <BoundaryGeometry G>
inline constexpr int parametric_dim = CurveGeometry<G> ? 1 : 2;

}  // namespace hom
