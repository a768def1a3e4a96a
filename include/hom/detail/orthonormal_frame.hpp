#pragma once
/// @file orthonormal_frame.hpp
/// A right-handed orthonormal frame (e1, e2, axis) around a given axis, used
/// by the analytic geometries (plane, circle in 3D, sphere, cylinder, torus)
/// to place their parameterizations in space.

#include <cmath>
#include <stdexcept>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace hom::detail {

struct OrthonormalFrame {
  Eigen::Vector3d e1 = Eigen::Vector3d::UnitX();
  Eigen::Vector3d e2 = Eigen::Vector3d::UnitY();
  Eigen::Vector3d e3 = Eigen::Vector3d::UnitZ();

  OrthonormalFrame() = default;

  /// e3 = axis / |axis|; e1 is `reference` made orthogonal to e3 (or, if
  /// reference is (nearly) parallel to the axis or zero, the unit coordinate
  /// vector least aligned with the axis, made orthogonal); e2 = e3 x e1.
  explicit OrthonormalFrame(const Eigen::Vector3d& axis, const Eigen::Vector3d& reference = Eigen::Vector3d::Zero()) {
    const double n = axis.norm();
    if (!(n > 0.0) || !std::isfinite(n)) throw std::invalid_argument("hom: geometry axis must be a non-zero vector");
    e3 = axis / n;
    Eigen::Vector3d r = reference - reference.dot(e3) * e3;
    if (!(r.norm() > 1e-8 * std::max(1.0, reference.norm()))) {
      Eigen::Index k = 0;
      e3.cwiseAbs().minCoeff(&k);
      r = Eigen::Vector3d::Unit(k);
      r -= r.dot(e3) * e3;
    }
    e1 = r.normalized();
    e2 = e3.cross(e1);
  }

  /// Coordinates of a vector d in the frame.
  Eigen::Vector3d local(const Eigen::Vector3d& d) const { return {d.dot(e1), d.dot(e2), d.dot(e3)}; }
};

}  // namespace hom::detail
