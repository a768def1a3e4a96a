#pragma once
/// @file ears.hpp
/// "Ears" of a linear 2D mesh from CAD and their repair. An ear is an
/// element with a corner on a CAD curve (or on the vertex of a closed curve)
/// whose two edges at that corner both lie on that curve: the corner is the
/// only one of the element there, its straight-sided angle is below pi, and
/// once the edges are curved onto the smooth curve it is exactly pi, so
/// det(D phi) vanishes at the corner whatever the free nodes do (at a corner
/// D phi is spanned by the two edge tangents, for the triangle's Lagrange map
/// as for appendix D's tensor map). No node movement can repair them, so the
/// linear mesh is changed, inside the ear only (its edges are not split, so
/// the mesh stays conforming and the curves keep their segments):
/// - a quadrilateral ear (Gmsh's blossom recombination and quad subdivision
///   make them where a triangle or quad had two edges along one curve) is
///   split into five: an inner quad whose corners lie between the ear's
///   corners and its centre, and four around it;
/// - a triangle ear (Gmsh's surface meshers make them at the ends of thin
///   faces and where a curve turns sharply) is split at its centre into
///   three, so that the corner gets an edge to the new interior node.
/// The corner may also be a model vertex where two curves meet tangentially
/// (G1: a fillet's arc and the line it rounds off), given the curves'
/// tangents: the element's two edges there then leave the corner within
/// flat_corner_max_angle of opposite directions along the curves, and once
/// curved its angle there is (nearly) pi, as on one curve.
/// Planar triangle meshes get the same repair later, from the mesh's own
/// boundary (hom/mesh/flat_corners.hpp, which also covers tetrahedra).

#include <Eigen/Core>
#include <functional>

#include "hom/geometry/geometry_model.hpp"
#include "hom/io/msh_data.hpp"

namespace hom::cad {

/// Where a point of face `face` projects, as parameters (u, v), and the
/// surface point of parameters (u, v).
struct FaceGeometry {
  std::function<Eigen::Vector2d(int face, const Eigen::Vector3d& x)> project;
  std::function<Eigen::Vector3d(int face, const Eigen::Vector2d& uv)> evaluate;
  /// A tangent of curve `curve` at its point x (either sense, any length).
  /// Empty: corners where two curves meet are never ears.
  std::function<Eigen::Vector3d(int curve, const Eigen::Vector3d& x)> curve_tangent = {};
};

/// The FaceGeometry of a CAD model's geometry (projection and evaluation on
/// its surfaces, tangents of its curves). It refers to `geometry`, which
/// must outlive it.
FaceGeometry face_geometry(const GeometryModel<3>& geometry);

/// Splits every ear (see above) among the 4-node quadrilaterals of `d` (Gmsh
/// type 3, on face entities; their boundary edges are the 2-node lines, type
/// 1, on curve entities). The new nodes lie on the ear's face, with their
/// (u, v); the five quads keep the ear's orientation and entity. Returns the
/// number of ears split.
int split_quad_ears(io::MshData& d, const FaceGeometry& faces);

/// The same for the 3-node triangles of `d` (Gmsh type 2, on face entities):
/// each ear becomes three triangles around a new node at its centre,
/// projected onto its face, with the ear's orientation and entity. A
/// 4-node tetrahedron of `d` (type 4) with the ear as a face becomes three at
/// the same node, each with one of the ear's edges, the tetrahedron's
/// orientation and entity (in a volume mesh the corner's two edges on the
/// curve, curved, leave it in opposite directions, so det D phi = 0 there
/// for the tetrahedron too, and the ear's third edge, on the boundary, is
/// not one the flat-corner split of hom/mesh/flat_corners.hpp may split).
/// An ear whose projected centre would invert one of those pieces (a face
/// that bends more across the ear than a tetrahedron on it is tall) is kept.
/// Returns the number of ears split.
int split_triangle_ears(io::MshData& d, const FaceGeometry& faces);

}  // namespace hom::cad
