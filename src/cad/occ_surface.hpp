#pragma once
/// @file occ_surface.hpp
/// OccSurface: the surface of one OpenCASCADE face behind hom's
/// SurfaceGeometry concept (geometry/surface_geometry.hpp), so chapter 5's
/// surface optimizer and chapter 6's pipeline treat a CAD face like any
/// analytic surface. Compiled in src/cad (libhom_cad); this header needs only
/// Eigen and hom's headers (OpenCASCADE stays in occ_surface.cpp).
///
/// Parameters are the face's own: those of its 3D surface
/// (BRep_Tool::Surface, with the face's location applied), the same (u, v)
/// that Gmsh's OCC kernel and BRepAdaptor_Surface use. Ranges:
///   - a parameter in which the surface is periodic *and* the face spans a
///     whole period (a full cylinder, a sphere's longitude; the face has a
///     seam edge) is periodic, range [lo, lo + period) with lo the face's
///     lower UV bound. A surface that is only closed in the parameter
///     (S(U1, v) = S(U2, v): a B-spline loft through closed sections, its
///     seam often a crease) counts as periodic with period U2 - U1, and is
///     evaluated at the representative in [lo, lo + period);
///   - any other parameter is bounded by the face's UV box
///     (BRepTools::UVBounds), not periodic. The box contains the trimmed
///     face; `contains` tells whether a (u, v) is inside the trimming.
/// Evaluation goes through Geom_Surface::D0/D1/D2, which keep no cache in
/// OpenCASCADE 7.x, so one OccSurface may be evaluated from several threads.
///
/// Closest point (`project`): Newton's method on |S(u, v) - x|^2 / 2
/// (detail/surface_projection.hpp) started from the best point of a sample
/// grid of the UV box taken at construction (denser for B-spline surfaces
/// with many knot spans). If the Newton point is farther from x than
/// 1e-7 times the face's size (x is off the surface, or Newton stalled at a
/// pole or a seam), OpenCASCADE's global extrema (GeomAPI_ProjectPointOnSurf
/// over the UV box) are computed too and the nearer point wins. Periodic
/// parameters are returned in their range; bounded ones are clamped to the
/// UV box. At a pole (a degenerate side of the parameterization, S_u = 0)
/// any u is a closest point and one of them is returned.

#include <memory>
#include <string>

#include <Eigen/Core>

#include "hom/geometry/parameter_range.hpp"
#include "hom/geometry/surface_geometry.hpp"

namespace hom::cad {

namespace detail {
struct OccSurfaceData;
}  // namespace detail

class OccSurface {
 public:
  /// Made by CadModel::surface(tag); `data` holds the OpenCASCADE objects.
  explicit OccSurface(std::shared_ptr<const detail::OccSurfaceData> data);

  Eigen::Vector3d evaluate(const Eigen::Vector2d& uv) const;
  /// [S_u S_v], 3 x 2.
  Eigen::Matrix<double, 3, 2> derivatives(const Eigen::Vector2d& uv) const;
  SurfaceSecondDerivatives second_derivatives(const Eigen::Vector2d& uv) const;
  Eigen::Vector2d project(const Eigen::Vector3d& x) const;
  ParameterRange range(int k) const;

  /// Whether (u, v) lies inside the trimmed face or on its boundary within
  /// the face's tolerance (OpenCASCADE's BRepTopAdaptor_FClass2d; periodic
  /// parameters are brought into range first).
  bool contains(const Eigen::Vector2d& uv) const;
  /// Whether the face is reversed in its shell: its outward normal is then
  /// -(S_u x S_v) instead of S_u x S_v.
  bool reversed() const;
  /// The surface kind: "plane", "cylinder", "cone", "sphere", "torus",
  /// "bezier", "bspline", "revolution", "extrusion", "offset" or "other".
  std::string type() const;
  /// Diagonal of the face's bounding box (the length scale of tolerances).
  double size() const;

  const detail::OccSurfaceData& data() const { return *data_; }

 private:
  /// uv with each closed-only periodic parameter brought into its range.
  Eigen::Vector2d for_occ(const Eigen::Vector2d& uv) const;

  std::shared_ptr<const detail::OccSurfaceData> data_;
};

static_assert(SurfaceGeometry<OccSurface>);

}  // namespace hom::cad
