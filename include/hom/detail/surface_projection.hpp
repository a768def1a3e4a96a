#pragma once
/// @file surface_projection.hpp
/// Closest-point projection onto a parametric surface by Newton's method on
///     f(u) = |S(u) - x|^2 / 2,
///     grad f = DS^T (S - x),   Hess f = DS^T DS + sum_ab (S - x) . S_ab,
/// for the models that have no closed form (hyperbolic paraboloid, surfaces
/// built from lambdas). Where the Hessian is not positive definite (far from
/// the surface, near a focal point) the step falls back to Gauss-Newton
/// (DS^T DS); a backtracking line search keeps f decreasing; bounded
/// non-periodic parameters are clamped to their range (projected Newton), so
/// a point beyond the patch's border projects onto the border.

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Dense>

#include "hom/geometry/parameter_range.hpp"
#include "hom/geometry/surface_geometry.hpp"

namespace hom::detail {

template <class G>
Eigen::Vector2d clamp_to_ranges(const G& g, Eigen::Vector2d uv) {
  for (int k = 0; k < 2; ++k) {
    const ParameterRange r = g.range(k);
    if (!r.periodic) uv[k] = std::clamp(uv[k], r.lo, r.hi);
  }
  return uv;
}

/// Parameters of a closest point of S to x, starting from uv0 (a local
/// minimum of the distance near uv0; callers pick a good start). Periodic
/// parameters are returned in their range.
template <class G>
Eigen::Vector2d closest_point_newton(const G& g, const Eigen::Vector3d& x, Eigen::Vector2d uv0, int max_iterations = 60) {
  auto half_distance2 = [&](const Eigen::Vector2d& uv) { return 0.5 * (g.evaluate(uv) - x).squaredNorm(); };
  Eigen::Vector2d uv = clamp_to_ranges(g, uv0);
  double f = half_distance2(uv);
  for (int it = 0; it < max_iterations; ++it) {
    const Eigen::Vector3d r = g.evaluate(uv) - x;
    const Eigen::Matrix<double, 3, 2> d = g.derivatives(uv);
    const SurfaceSecondDerivatives s = g.second_derivatives(uv);
    const Eigen::Vector2d grad = d.transpose() * r;
    const Eigen::Matrix2d gn = d.transpose() * d;
    Eigen::Matrix2d h = gn;
    h(0, 0) += r.dot(s.uu);
    h(0, 1) += r.dot(s.uv);
    h(1, 0) += r.dot(s.uv);
    h(1, 1) += r.dot(s.vv);
    Eigen::LLT<Eigen::Matrix2d> llt(h);
    if (llt.info() != Eigen::Success) llt.compute(gn);
    if (llt.info() != Eigen::Success) break;  // degenerate parameterization at uv
    const Eigen::Vector2d step = -llt.solve(grad);
    // Backtracking on f, the step clamped to the ranges. Near the solution f
    // changes by less than its rounding error, so a full step that does not
    // increase f beyond that is taken (Newton converges quadratically there).
    const double noise = 1e-12 * f + 1e-300;
    double a = 1.0;
    Eigen::Vector2d next = clamp_to_ranges(g, uv + step);
    double fn = half_distance2(next);
    if (fn <= f + noise) fn = std::min(fn, f);
    while (fn > f && a > 1e-10) {
      a *= 0.5;
      next = clamp_to_ranges(g, uv + a * step);
      fn = half_distance2(next);
    }
    if (!(fn <= f)) break;
    const double moved = (next - uv).norm();
    uv = next;
    f = fn;
    if (moved <= 1e-15 * (1.0 + uv.norm())) break;
  }
  for (int k = 0; k < 2; ++k) {
    const ParameterRange r = g.range(k);
    if (r.periodic) uv[k] = r.normalize(uv[k]);
  }
  return uv;
}

/// Closest point with the start chosen as the best of an n x n sample of the
/// parameter box (bounded or periodic ranges; an unbounded range is sampled on
/// [-1, 1]), so that the Newton iteration starts in the right basin.
template <class G>
Eigen::Vector2d closest_point_sampled(const G& g, const Eigen::Vector3d& x, int n = 16) {
  double lo[2], hi[2];
  for (int k = 0; k < 2; ++k) {
    const ParameterRange r = g.range(k);
    lo[k] = r.bounded() ? r.lo : -1.0;
    hi[k] = r.bounded() ? r.hi : 1.0;
  }
  Eigen::Vector2d best = Eigen::Vector2d::Zero();
  double best_d = std::numeric_limits<double>::infinity();
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector2d uv(lo[0] + (hi[0] - lo[0]) * (i + 0.5) / n, lo[1] + (hi[1] - lo[1]) * (j + 0.5) / n);
      const double d = (g.evaluate(uv) - x).squaredNorm();
      if (d < best_d) {
        best_d = d;
        best = uv;
      }
    }
  return closest_point_newton(g, x, best);
}

}  // namespace hom::detail
