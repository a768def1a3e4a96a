#pragma once
/// @file occ_curve.hpp
/// OccCurve: the 3D curve of one OpenCASCADE edge behind hom's
/// CurveGeometry<3> concept (geometry/curve_geometry.hpp), with arc length,
/// which chapter 6 (section 6.1, step 2) needs to put the high-order nodes
/// of a CAD edge at Gauss-Lobatto positions in arc length. Compiled in
/// src/cad; this header needs only Eigen and hom's headers.
///
/// The parameter is the edge's own (BRep_Tool::Curve with the edge's
/// location, the t Gmsh's OCC kernel uses), range [first, last] of the edge;
/// periodic only if the curve is periodic and the edge is a whole period (a
/// full circle). Evaluation goes through Geom_Curve (no cache), so an
/// OccCurve may be evaluated from several threads.
///
/// Closest point (`project`): the nearest of Newton's method from the best
/// of 64 samples, the edge's two ends and OpenCASCADE's extrema
/// (GeomAPI_ProjectPointOnCurve on [first, last]); the extrema are only
/// computed when the Newton point is farther from x than 1e-9 times the
/// edge's length.
///
/// Arc length: GCPnts_AbscissaPoint (adaptive Gauss-Legendre integration of
/// |C'|, relative tolerance `1e-12` by default).

#include <memory>
#include <string>

#include <Eigen/Core>

#include "hom/geometry/curve_geometry.hpp"
#include "hom/geometry/parameter_range.hpp"

namespace hom::cad {

namespace detail {
struct OccCurveData;
}  // namespace detail

class OccCurve {
 public:
  static constexpr int space_dim = 3;
  using Point = Eigen::Vector3d;

  /// Made by CadModel::curve(tag).
  explicit OccCurve(std::shared_ptr<const detail::OccCurveData> data);

  Point evaluate(double u) const;
  Point derivative(double u) const;
  Point second_derivative(double u) const;
  double project(const Point& x) const;
  ParameterRange range() const;

  /// Arc length of the curve between parameters u0 and u1 (negative if
  /// u1 < u0).
  double arc_length(double u0, double u1, double tolerance = 1e-12) const;
  /// Length of the whole edge.
  double length() const;
  /// The parameter u with arc_length(u0, u) = s (s may be negative; beyond
  /// the edge's ends the curve is followed as far as it extends).
  double parameter_at_length(double u0, double s, double tolerance = 1e-12) const;
  /// "line", "circle", "ellipse", "hyperbola", "parabola", "bezier",
  /// "bspline", "offset" or "other".
  std::string type() const;

  const detail::OccCurveData& data() const { return *data_; }

 private:
  std::shared_ptr<const detail::OccCurveData> data_;
};

static_assert(CurveGeometry<OccCurve>);

}  // namespace hom::cad
