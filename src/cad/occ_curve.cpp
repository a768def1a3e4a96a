// OccCurve: an OpenCASCADE edge as a hom CurveGeometry<3> with arc length
// (occ_curve.hpp).

#include "occ_curve.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <BRep_Tool.hxx>
#include <GCPnts_AbscissaPoint.hxx>
#include <GeomAPI_ProjectPointOnCurve.hxx>
#include <GeomAdaptor_Curve.hxx>
#include <Standard_Failure.hxx>
#include <gp_Pnt.hxx>
#include <gp_Vec.hxx>

#include "occ_data.hpp"

namespace hom::cad {

namespace {

Eigen::Vector3d to_eigen(const gp_XYZ& p) { return {p.X(), p.Y(), p.Z()}; }

std::string curve_type_name(GeomAbs_CurveType t) {
  switch (t) {
    case GeomAbs_Line: return "line";
    case GeomAbs_Circle: return "circle";
    case GeomAbs_Ellipse: return "ellipse";
    case GeomAbs_Hyperbola: return "hyperbola";
    case GeomAbs_Parabola: return "parabola";
    case GeomAbs_BezierCurve: return "bezier";
    case GeomAbs_BSplineCurve: return "bspline";
    case GeomAbs_OffsetCurve: return "offset";
    default: return "other";
  }
}

constexpr int num_samples = 64;

}  // namespace

namespace detail {

std::shared_ptr<const OccCurveData> make_curve_data(const TopoDS_Edge& edge) {
  if (BRep_Tool::Degenerated(edge)) return nullptr;
  auto d = std::make_shared<OccCurveData>();
  d->edge = edge;
  d->curve = BRep_Tool::Curve(edge, d->first, d->last);
  if (d->curve.IsNull()) return nullptr;
  if (d->curve->IsPeriodic()) {
    const double period = d->curve->Period();
    d->periodic = std::abs((d->last - d->first) - period) <= 1e-9 * period;
  }
  const GeomAdaptor_Curve adaptor(d->curve, d->first, d->last);
  d->type = curve_type_name(adaptor.GetType());
  d->length = GCPnts_AbscissaPoint::Length(adaptor, d->first, d->last, 1e-12);
  for (int i = 0; i <= num_samples; ++i)
    d->samples.push_back(to_eigen(d->curve->Value(d->first + (d->last - d->first) * i / num_samples).XYZ()));
  return d;
}

}  // namespace detail

OccCurve::OccCurve(std::shared_ptr<const detail::OccCurveData> data) : data_(std::move(data)) {}

OccCurve::Point OccCurve::evaluate(double u) const { return to_eigen(data_->curve->Value(u).XYZ()); }

OccCurve::Point OccCurve::derivative(double u) const { return to_eigen(data_->curve->DN(u, 1).XYZ()); }

OccCurve::Point OccCurve::second_derivative(double u) const { return to_eigen(data_->curve->DN(u, 2).XYZ()); }

ParameterRange OccCurve::range() const { return {data_->first, data_->last, data_->periodic}; }

double OccCurve::project(const Point& x) const {
  const auto& d = *data_;
  const ParameterRange r = range();
  auto dist2 = [&](double u) { return (evaluate(u) - x).squaredNorm(); };
  int best = 0;
  for (int i = 1; i <= num_samples; ++i)
    if ((d.samples[i] - x).squaredNorm() < (d.samples[best] - x).squaredNorm()) best = i;
  double u = d.first + (d.last - d.first) * best / num_samples;
  // Newton on f(u) = |C(u) - x|^2 / 2: f' = C'.(C - x), f'' = C'.C' + C''.(C - x)
  // (Gauss-Newton where f'' <= 0), with backtracking; clamped to the edge
  // unless it is a whole period.
  double f = dist2(u);
  for (int it = 0; it < 50; ++it) {
    const Point c1 = derivative(u), r0 = evaluate(u) - x;
    const double g = c1.dot(r0);
    double h = c1.squaredNorm() + second_derivative(u).dot(r0);
    if (!(h > 0)) h = c1.squaredNorm();
    if (!(h > 0)) break;
    double step = -g / h, next = 0, fn = 0;
    for (int k = 0; k < 40; ++k, step *= 0.5) {
      next = r.periodic ? u + step : std::clamp(u + step, d.first, d.last);
      fn = dist2(next);
      if (fn <= f * (1 + 1e-14)) break;
    }
    if (!(fn <= f * (1 + 1e-14))) break;
    const double moved = std::abs(next - u);
    u = next;
    f = std::min(f, fn);
    if (moved <= 1e-15 * (1 + std::abs(u))) break;
  }
  if (std::sqrt(f) > 1e-9 * std::max(d.length, 1e-300)) {
    // Compare with the ends and OpenCASCADE's extrema on the edge.
    for (double end : {d.first, d.last})
      if (dist2(end) < f) {
        f = dist2(end);
        u = end;
      }
    try {
      GeomAPI_ProjectPointOnCurve proj(gp_Pnt(x[0], x[1], x[2]), d.curve, d.first, d.last);
      if (proj.NbPoints() > 0 && proj.LowerDistance() * proj.LowerDistance() < f) u = proj.LowerDistanceParameter();
    } catch (const Standard_Failure&) {  // keep the best so far
    }
  }
  if (!r.periodic) return std::clamp(u, d.first, d.last);
  const double t = r.normalize(u);  // which can round a u just below lo up to hi
  return t >= r.hi ? r.lo : t;
}

double OccCurve::arc_length(double u0, double u1, double tolerance) const {
  if (u0 == u1) return 0.0;
  const GeomAdaptor_Curve adaptor(data_->curve);
  const double s = GCPnts_AbscissaPoint::Length(adaptor, std::min(u0, u1), std::max(u0, u1), tolerance);
  return u1 > u0 ? s : -s;
}

double OccCurve::length() const { return data_->length; }

double OccCurve::parameter_at_length(double u0, double s, double tolerance) const {
  if (s == 0.0) return u0;
  const GeomAdaptor_Curve adaptor(data_->curve);
  const GCPnts_AbscissaPoint a(tolerance, adaptor, s, u0);
  if (!a.IsDone()) throw std::runtime_error("OccCurve::parameter_at_length: OpenCASCADE found no point at that length");
  // Polish with Newton's method on L(u) = arc_length(u0, u) - s, L' = |C'(u)|,
  // so the result matches arc_length() to its own tolerance.
  double u = a.Parameter();
  for (int it = 0; it < 4; ++it) {
    const double speed = derivative(u).norm();
    if (!(speed > 0)) break;
    const double step = (arc_length(u0, u, tolerance) - s) / speed;
    u -= step;
    if (std::abs(step) <= 1e-15 * (1 + std::abs(u))) break;
  }
  return u;
}

std::string OccCurve::type() const { return data_->type; }

}  // namespace hom::cad
