#pragma once
/// @file mesh_problem.hpp
/// Building an OptimizationProblem from a Mesh: the free nodes are the nodes
/// classified NodeKind::free (fixed = every other node: fixed ones and those
/// on a geometric entity, which chapter 4 holds at their curved positions),
/// each element's ideal is tabulated at the quadrature points of the rule
/// the quadrature policy prescribes for the mesh's degree.

#include <stdexcept>
#include <vector>

#include "hom/measure/shape_measure.hpp"
#include "hom/mesh/mesh.hpp"
#include "hom/optimize/element_objective.hpp"
#include "hom/optimize/problem.hpp"
#include "hom/quadrature/quadrature_policy.hpp"
#include "hom/quality/ideal.hpp"
#include "hom/quality/tabulation.hpp"

namespace hom {

/// The ideal mesh of `kind` for a planar / volume mesh: straight-sided (each
/// element's snapshot vertices, Mesh::ideal_vertices) or regular.
template <ElementFamily Family, NodeSet Nodes, int SpaceDim>
IdealMesh<Family> make_ideal_mesh(const Mesh<Family, Nodes, SpaceDim>& mesh, IdealKind kind) {
  static_assert(SpaceDim == Family::dim, "hom::make_ideal_mesh: surface meshes are optimized in parametric space (chapter 5)");
  return kind == IdealKind::regular ? IdealMesh<Family>::regular(mesh.num_elements()) : mesh.straight_sided_ideal();
}

/// Free-node mask of a mesh: NodeKind::free moves, everything else is fixed.
template <class MeshT>
std::vector<bool> free_node_mask(const MeshT& mesh) {
  std::vector<bool> free(mesh.num_nodes());
  for (int i = 0; i < mesh.num_nodes(); ++i) free[i] = mesh.node_class(i).kind == NodeKind::free;
  return free;
}

/// The problem of eq 4.11 for `mesh` (its current coordinates) against `ideal`.
template <class Measure = ShapeMeasure, QuadraturePolicy Q = DefaultExactness, ElementFamily Family, NodeSet Nodes,
          int SpaceDim>
OptimizationProblem<Family, Measure> make_problem(const Mesh<Family, Nodes, SpaceDim>& mesh, const IdealMesh<Family>& ideal,
                                                  const Measure& measure = {}) {
  static_assert(SpaceDim == Family::dim, "hom::make_problem: surface meshes are optimized in parametric space (chapter 5)");
  if (ideal.size() != mesh.num_elements())
    throw std::invalid_argument("hom::make_problem: the ideal mesh has " + std::to_string(ideal.size()) + " elements, the mesh " +
                                std::to_string(mesh.num_elements()));
  const int p = mesh.degree();
  const Tabulation<Family>& tab = tabulation<Family, Nodes>(p, quadrature_for<Family, Q>(p));
  std::vector<IdealAtPoints<Family::dim>> ideals(mesh.num_elements());
  for (int e = 0; e < mesh.num_elements(); ++e) ideals[e] = ideal_at_points<Family>(tab, ideal.vertices(e));
  return OptimizationProblem<Family, Measure>(tab, mesh.nodes(), mesh.elements(), free_node_mask(mesh), std::move(ideals),
                                              measure);
}

}  // namespace hom
