#pragma once
/// @file test_meshes.hpp
/// Meshes and probes that several optimizer tests share: the structured unit
/// box elevated to degree p, and the optimizer's view of a mesh (MeshState:
/// inverted elements, qualities) against an ideal mesh.

#include <array>

#include "hom/mesh/elevate.hpp"
#include "hom/mesh/structured.hpp"
#include "hom/nodes/warp_blend.hpp"
#include "hom/optimize/mesh_problem.hpp"

namespace hom::testing {

template <class F>
using TestMesh = Mesh<F, WarpBlend>;

/// Unit box with n cells per axis, elevated to degree p.
template <class F>
TestMesh<F> box_mesh(int n, int p) {
  std::array<int, F::dim> cells;
  cells.fill(n);
  return elevate(structured_mesh<F, WarpBlend>(cells), p);
}

/// The optimizer's evaluation of `mesh` against `ideal`.
template <class MeshT>
MeshState mesh_state(const MeshT& mesh, const IdealMesh<typename MeshT::family>& ideal) {
  const auto problem = make_problem(mesh, ideal);
  return problem.status(problem.coordinates());
}

/// ... against its straight-sided counterpart.
template <class MeshT>
MeshState mesh_state(const MeshT& mesh) {
  return mesh_state(mesh, make_ideal_mesh(mesh, IdealKind::straight_sided));
}

}  // namespace hom::testing
