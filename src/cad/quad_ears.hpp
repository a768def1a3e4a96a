#pragma once
/// @file quad_ears.hpp
/// Quadrilateral "ears" of a linear 2D mesh and their repair. An ear is a
/// quadrilateral with a corner on a CAD curve (not on a CAD vertex) whose two
/// edges at that corner both lie on that curve: the corner is the only one of
/// the element there, its straight-sided angle is nearly pi, and once the
/// edges are curved onto the smooth curve it is exactly pi, so det(D phi)
/// vanishes at the corner whatever the free nodes do (appendix D's tensor
/// map: at a corner, D phi is spanned by the two edge tangents). Gmsh's
/// blossom recombination followed by its quad subdivision makes them where a
/// triangle or quad had two edges along one curve; no node movement can
/// repair them, so the linear mesh is changed: each ear is split into five
/// quadrilaterals (an inner quad whose corners lie between the ear's corners
/// and its centre, and four around it), which gives the corner two
/// elements and keeps the mesh conforming (the ear's edges are not split).

#include <functional>

#include <Eigen/Core>

#include "hom/io/msh_data.hpp"

namespace hom::cad {

/// Where a point of face `face` projects, as parameters (u, v), and the
/// surface point of parameters (u, v).
struct FaceGeometry {
  std::function<Eigen::Vector2d(int face, const Eigen::Vector3d& x)> project;
  std::function<Eigen::Vector3d(int face, const Eigen::Vector2d& uv)> evaluate;
};

/// Splits every ear (see above) among the 4-node quadrilaterals of `d` (Gmsh
/// type 3, on face entities; their boundary edges are the 2-node lines, type
/// 1, on curve entities). The new nodes lie on the ear's face, with their
/// (u, v); the five quads keep the ear's orientation and entity. Returns the
/// number of ears split.
int split_quad_ears(io::MshData& d, const FaceGeometry& faces);

}  // namespace hom::cad
