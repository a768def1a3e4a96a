#pragma once
/// @file parameter_range.hpp
/// The range of one parametric coordinate of a curve or surface, and how to
/// bring a periodic parameter next to another one.
///
/// A periodic parameter (the angle of a circle, the longitude of a sphere)
/// names the same point for u and u + k * period. Projections return the
/// representative in [lo, hi); nodes of one element that straddle the seam
/// need `unwrap` so that interpolating their parameters does not run the long
/// way round.

#include <cmath>
#include <limits>

namespace hom {

struct ParameterRange {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool periodic = false;

  /// hi - lo (the period of a periodic parameter).
  double length() const { return hi - lo; }
  bool bounded() const { return std::isfinite(lo) && std::isfinite(hi); }
  /// Whether u lies in [lo, hi] (a periodic parameter is always in range).
  bool contains(double u) const { return periodic || (u >= lo && u <= hi); }
  /// The representative of u in [lo, hi) for a periodic parameter; u clamped
  /// to [lo, hi] otherwise.
  double normalize(double u) const {
    if (periodic) {
      const double t = lo + std::fmod(u - lo, length());
      return t < lo ? t + length() : (t >= hi ? t - length() : t);
    }
    return u < lo ? lo : (u > hi ? hi : u);
  }
  /// For a periodic parameter, u + k * period for the integer k that brings it
  /// closest to `near`; u itself otherwise.
  double unwrap(double u, double near) const {
    if (!periodic) return u;
    return u - length() * std::round((u - near) / length());
  }
};

/// An unbounded, non-periodic parameter (a line, a plane).
inline constexpr ParameterRange unbounded_range() { return {}; }

}  // namespace hom
