#pragma once
/// @file curve_models.hpp
/// CAD models built with OpenCASCADE in code for chapter 6's cases where the
/// thesis's originals are not public (bench_curve, test_curve), and the
/// placement of a planar model in the plane z = 0 that hom's planar meshes
/// live in. Compiled in src/curve (hom_curve); this header needs only Eigen
/// and hom's headers.
///
///   auto part = hom::cad::plate_with_holes_model();   // one planar face, z = 0
///   auto gear = hom::cad::gear_model();                // extruded toothed wheel
///   auto prop = hom::cad::propeller_model();           // twisted blades on a hub
///   auto wing = hom::cad::wing_domain_model();         // box around a half-wing

#include <optional>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "cad_model.hpp"

namespace hom::cad {

/// A planar bracket in z = 0 (the "Barcelona harbor" / motorbike brake style
/// 2D case, thesis 6.3.1 and D.2): an L-shaped plate 10 x 8 with its convex
/// corners rounded (fillet radius 1), its re-entrant corner rounded (0.8),
/// three circular holes and a stadium-shaped slot. One face; its boundary has
/// lines, circular arcs and full circles.
CadModel plate_with_holes_model();

/// A gear-like part (section 5.5.2.2's gear-box component): a wheel of
/// `teeth` teeth, outer radius `radius`, tooth height 0.2 radius, thickness
/// `thickness` along z, with a centre bore of radius 0.3 radius. The tooth
/// profile is a smooth periodic B-spline through points of an involute-like
/// tooth (flanks that widen towards the root, rounded tip and root), extruded
/// along z: one B-spline extrusion face for the teeth, a cylinder for the
/// bore, two planar faces with a B-spline and a circular boundary.
CadModel gear_model(int teeth = 12, double radius = 1.0, double thickness = 0.4);

/// A propeller-like part (the propeller of section 5.5.1.3 and table 5.3 is
/// not public): a cylindrical hub of radius 0.3 and length 0.6 along z, and
/// `blades` twisted blades along the radial directions, each lofted through
/// four elliptic sections (thickness 18 % of the chord) from radius 0.15,
/// inside the hub, to the tip at 1.3, the chord shrinking from 0.5 to 0.22 and
/// the pitch from 60 to 24 degrees; blades fused to the hub. One solid whose
/// faces are B-spline loft surfaces, the cylinder and planes.
CadModel propeller_model(int blades = 3);

/// The exterior domain of a wing (section 6.3.2): a NACA 00tt half-wing
/// (`thickness` 0.12: NACA 0012) lofted from its root (chord 1, leading edge
/// at the origin, in the symmetry plane z = 0) to a flat tip at z = 1.5 (chord
/// 0.6, leading edge swept back by 0.3), cut from the box [-1.5, 3] x [-1.5,
/// 1.5] x [0, 2.5]. One solid; the wing's upper and lower sides are B-spline
/// loft surfaces that meet at the leading edge and at the sharp trailing edge.
CadModel wing_domain_model(double thickness = 0.12);

/// A solid cone along z with its base of radius `radius` at z = 0 and its
/// apex at z = `height` (a fuselage's tail tip, sharp): a conical face, whose
/// parameterization is degenerate at the apex, and a disk.
CadModel cone_model(double radius = 3.0, double height = 10.0);

/// If every face of the model is planar and they lie in one plane, the model
/// moved rigidly into z = 0 with that plane's normal along +z (a no-op for a
/// model already there) and the transformation's description; std::nullopt
/// if the model is not planar.
struct PlanarPlacement {
  CadModel model;
  bool moved = false;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  ///< x_new = rotation * x + translation
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
};
std::optional<PlanarPlacement> place_in_xy_plane(const CadModel& cad, double tolerance = 1e-9);

}  // namespace hom::cad
