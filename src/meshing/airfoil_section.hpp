#pragma once
/// @file airfoil_section.hpp
/// The wing section of thesis section 6.3.3.2 (table 6.5, figure 6.11): an
/// airfoil profile extruded in z through a box, built with Gmsh's
/// OpenCASCADE kernel and written as a BREP file, so that hom's CAD layer
/// (src/cad: read_cad, mesh_cad, OccSurface) meshes it and curves onto the
/// very B-spline surfaces of the model.
///
///   auto profile = hom::meshing::read_selig_airfoil("sd7003.dat");  // or naca_00xx(0.12)
///   hom::meshing::write_airfoil_section_brep({.profile = profile, .span = 0.2}, "wing.brep");
///   auto cad = hom::cad::read_cad("wing.brep");
///
/// Geometry: the box [lo, hi] x [0, span] minus the profile's cylinder,
/// built as the planar face (rectangle minus profile) extruded by `span`
/// (no boolean operation). The profile is two interpolating splines
/// (OpenCASCADE B-splines through the points): the upper surface from the
/// trailing edge to the leading edge (the point of smallest x) and the lower
/// one back; a profile whose ends do not meet (blunt trailing edge) is
/// closed by a straight segment. So the wall is two (or three) extruded
/// B-spline faces meeting the planes z = 0 and z = span at right angles.

#include <string>
#include <vector>

#include <Eigen/Core>

namespace hom::meshing {

/// Points of a Selig-format airfoil file (a name line, then "x y" lines from
/// the trailing edge over the upper surface to the leading edge and back).
/// Throws std::runtime_error naming the file and line when it is missing or
/// malformed (fewer than 8 points).
std::vector<Eigen::Vector2d> read_selig_airfoil(const std::string& path);

/// The symmetric NACA 00tt profile of relative thickness `thickness` (0.12
/// for NACA 0012) with the closed trailing-edge coefficient (-0.1036), in
/// Selig order, `points_per_side` points per side, cosine-spaced in x.
std::vector<Eigen::Vector2d> naca_00xx(double thickness = 0.12, int points_per_side = 61);

struct AirfoilSectionOptions {
  std::vector<Eigen::Vector2d> profile;          ///< Selig order, chord about 1
  double span = 0.2;                             ///< extent in z
  Eigen::Vector2d lo = Eigen::Vector2d(-1.5, -1.5);  ///< box corner (x, y)
  Eigen::Vector2d hi = Eigen::Vector2d(2.5, 1.5);    ///< box corner (x, y)
  bool verbose = false;
};

/// Builds the section (file comment) in its own Gmsh model and writes the
/// OpenCASCADE shape to `path` (a .brep file). Throws std::invalid_argument
/// for a profile of fewer than 8 points or outside the box, std::runtime_error
/// if Gmsh fails.
void write_airfoil_section_brep(const AirfoilSectionOptions& options, const std::string& path);

}  // namespace hom::meshing
