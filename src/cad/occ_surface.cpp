// OccSurface: an OpenCASCADE face as a hom SurfaceGeometry (occ_surface.hpp).

#include "occ_surface.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <BRepBndLib.hxx>
#include <BRepTools.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <GeomAPI_ProjectPointOnSurf.hxx>
#include <GeomAdaptor_Surface.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_BezierSurface.hxx>
#include <Precision.hxx>
#include <gp_Pnt.hxx>
#include <gp_Pnt2d.hxx>
#include <gp_Vec.hxx>

#include "hom/detail/surface_projection.hpp"
#include "occ_data.hpp"

namespace hom::cad {

namespace {

Eigen::Vector3d to_eigen(const gp_XYZ& p) { return {p.X(), p.Y(), p.Z()}; }

// The representative of a periodic u in [lo, hi): ParameterRange::normalize
// can round a u just below lo up to exactly hi.
double wrap(const ParameterRange& r, double u) {
  const double t = r.normalize(u);
  return t >= r.hi ? r.lo : t;
}

std::string surface_type_name(GeomAbs_SurfaceType t) {
  switch (t) {
    case GeomAbs_Plane: return "plane";
    case GeomAbs_Cylinder: return "cylinder";
    case GeomAbs_Cone: return "cone";
    case GeomAbs_Sphere: return "sphere";
    case GeomAbs_Torus: return "torus";
    case GeomAbs_BezierSurface: return "bezier";
    case GeomAbs_BSplineSurface: return "bspline";
    case GeomAbs_SurfaceOfRevolution: return "revolution";
    case GeomAbs_SurfaceOfExtrusion: return "extrusion";
    case GeomAbs_OffsetSurface: return "offset";
    default: return "other";
  }
}

}  // namespace

namespace detail {

std::shared_ptr<const OccSurfaceData> make_surface_data(const TopoDS_Face& face) {
  auto d = std::make_shared<OccSurfaceData>();
  d->face = face;
  d->surface = BRep_Tool::Surface(face);
  if (d->surface.IsNull()) return nullptr;
  BRepTools::UVBounds(face, d->u0, d->u1, d->v0, d->v1);
  // A parameter is periodic for the face only if the face closes around it
  // (it spans a whole period); otherwise the face's UV box bounds it.
  // A surface that is closed but not periodic in a parameter (a B-spline
  // loft through closed, non-periodic sections: S(U1, v) = S(U2, v) along a
  // seam edge, often a crease such as a trailing edge) is treated as periodic
  // with period U2 - U1 too, so that the elements beside the seam take
  // parameters next to each other instead of spanning the whole range.
  double bounds[2][2];
  d->surface->Bounds(bounds[0][0], bounds[0][1], bounds[1][0], bounds[1][1]);
  const bool native[2] = {bool(d->surface->IsUPeriodic()), bool(d->surface->IsVPeriodic())};
  const bool closed[2] = {bool(d->surface->IsUClosed()), bool(d->surface->IsVClosed())};
  const double lo[2] = {d->u0, d->v0}, hi[2] = {d->u1, d->v1};
  for (int k = 0; k < 2; ++k) {
    if (native[k])
      d->period[k] = k == 0 ? d->surface->UPeriod() : d->surface->VPeriod();
    else if (closed[k] && std::isfinite(bounds[k][1] - bounds[k][0]))
      d->period[k] = bounds[k][1] - bounds[k][0];
    else
      continue;
    d->periodic[k] = std::abs((hi[k] - lo[k]) - d->period[k]) <= 1e-9 * d->period[k];
    d->closed_only[k] = d->periodic[k] && !native[k];
  }
  Bnd_Box box;
  BRepBndLib::Add(face, box);
  if (!box.IsVoid()) d->size = std::sqrt(box.SquareExtent());
  const GeomAdaptor_Surface adaptor(d->surface);
  d->type = surface_type_name(adaptor.GetType());

  // Projection start grid: 16 x 16 for analytic surfaces, about 4 samples per
  // knot span (up to 64) for B-splines, whose patches can fold.
  d->grid_u = d->grid_v = 16;
  if (adaptor.GetType() == GeomAbs_BSplineSurface) {
    const auto bs = adaptor.BSpline();
    d->grid_u = std::clamp(4 * (bs->NbUKnots() - 1) * std::max(1, bs->UDegree() / 2), 16, 64);
    d->grid_v = std::clamp(4 * (bs->NbVKnots() - 1) * std::max(1, bs->VDegree() / 2), 16, 64);
  } else if (adaptor.GetType() == GeomAbs_BezierSurface) {
    d->grid_u = d->grid_v = 24;
  }
  d->grid.reserve(std::size_t(d->grid_u) * d->grid_v);
  for (int j = 0; j < d->grid_v; ++j)
    for (int i = 0; i < d->grid_u; ++i) {
      const double u = d->u0 + (d->u1 - d->u0) * (i + 0.5) / d->grid_u;
      const double v = d->v0 + (d->v1 - d->v0) * (j + 0.5) / d->grid_v;
      d->grid.push_back(to_eigen(d->surface->Value(u, v).XYZ()));
    }
  d->classifier = std::make_unique<BRepTopAdaptor_FClass2d>(face, BRep_Tool::Tolerance(face));
  return d;
}

}  // namespace detail

OccSurface::OccSurface(std::shared_ptr<const detail::OccSurfaceData> data) : data_(std::move(data)) {}

Eigen::Vector2d OccSurface::for_occ(const Eigen::Vector2d& uv) const {
  Eigen::Vector2d p = uv;
  for (int k = 0; k < 2; ++k) {
    if (!data_->closed_only[k]) continue;
    // The surface need not be smooth across its seam (a trailing edge): a
    // parameter at either end of the range stays at that end, so that the
    // derivatives there are its own side's; only one beyond is wrapped.
    const ParameterRange r = range(k);
    const double slack = 1e-9 * r.length();
    p[k] = p[k] >= r.lo - slack && p[k] <= r.hi + slack ? std::clamp(p[k], r.lo, r.hi) : wrap(r, p[k]);
  }
  return p;
}

Eigen::Vector3d OccSurface::evaluate(const Eigen::Vector2d& uv) const {
  const Eigen::Vector2d q = for_occ(uv);
  return to_eigen(data_->surface->Value(q[0], q[1]).XYZ());
}

Eigen::Matrix<double, 3, 2> OccSurface::derivatives(const Eigen::Vector2d& uv) const {
  const Eigen::Vector2d q = for_occ(uv);
  gp_Pnt p;
  gp_Vec du, dv;
  data_->surface->D1(q[0], q[1], p, du, dv);
  Eigen::Matrix<double, 3, 2> d;
  d.col(0) = to_eigen(du.XYZ());
  d.col(1) = to_eigen(dv.XYZ());
  return d;
}

SurfaceSecondDerivatives OccSurface::second_derivatives(const Eigen::Vector2d& uv) const {
  gp_Pnt p;
  gp_Vec du, dv, duu, dvv, duv;
  const Eigen::Vector2d q = for_occ(uv);
  data_->surface->D2(q[0], q[1], p, du, dv, duu, dvv, duv);
  SurfaceSecondDerivatives s;
  s.uu = to_eigen(duu.XYZ());
  s.uv = to_eigen(duv.XYZ());
  s.vv = to_eigen(dvv.XYZ());
  return s;
}

ParameterRange OccSurface::range(int k) const {
  const auto& d = *data_;
  const double lo = k == 0 ? d.u0 : d.v0, hi = k == 0 ? d.u1 : d.v1;
  if (d.periodic[k]) return {lo, lo + d.period[k], true};
  return {lo, hi, false};
}

Eigen::Vector2d OccSurface::project(const Eigen::Vector3d& x) const {
  const auto& d = *data_;
  // Start: the nearest grid point (a point in the right basin on any face
  // the grid resolves).
  std::size_t best = 0;
  double best_d = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < d.grid.size(); ++k) {
    const double dist = (d.grid[k] - x).squaredNorm();
    if (dist < best_d) {
      best_d = dist;
      best = k;
    }
  }
  const int i = static_cast<int>(best % d.grid_u), j = static_cast<int>(best / d.grid_u);
  const Eigen::Vector2d start(d.u0 + (d.u1 - d.u0) * (i + 0.5) / d.grid_u, d.v0 + (d.v1 - d.v0) * (j + 0.5) / d.grid_v);
  Eigen::Vector2d uv = ::hom::detail::closest_point_newton(*this, x, start);
  for (int k = 0; k < 2; ++k)
    if (d.periodic[k]) uv[k] = wrap(range(k), uv[k]);
  double dist = (evaluate(uv) - x).norm();
  if (dist > 1e-7 * d.size) {
    // Off the surface, or Newton stopped early (a pole, a fold): compare with
    // OpenCASCADE's global extrema over the UV box.
    try {
      GeomAPI_ProjectPointOnSurf proj(gp_Pnt(x[0], x[1], x[2]), d.surface, d.u0, d.u1, d.v0, d.v1);
      if (proj.IsDone() && proj.NbPoints() > 0 && proj.LowerDistance() < dist) {
        double u = 0, v = 0;
        proj.LowerDistanceParameters(u, v);
        uv = ::hom::detail::clamp_to_ranges(*this, Eigen::Vector2d(u, v));
        for (int k = 0; k < 2; ++k)
          if (d.periodic[k]) uv[k] = wrap(range(k), uv[k]);
      }
    } catch (const Standard_Failure&) {  // keep Newton's point
    }
  }
  return uv;
}

bool OccSurface::contains(const Eigen::Vector2d& uv) const {
  Eigen::Vector2d p = uv;
  for (int k = 0; k < 2; ++k)
    if (data_->periodic[k]) p[k] = wrap(range(k), p[k]);
  return data_->classifier->Perform(gp_Pnt2d(p[0], p[1]), Standard_True) != TopAbs_OUT;
}

bool OccSurface::reversed() const { return data_->face.Orientation() == TopAbs_REVERSED; }

std::string OccSurface::type() const { return data_->type; }

double OccSurface::size() const { return data_->size; }

}  // namespace hom::cad
