#pragma once
/// @file sub_mesh.hpp
/// The linear sub-mesh of a high-order mesh and the recovery of the
/// high-order mesh from it (appendix C, p-continuation).
///
/// Every degree-p element is split into its linear sub-elements
/// (element/sub_elements.hpp: p^2 triangles, p^3 tetrahedra, p^Dim cells),
/// applied mesh-wide: the sub-mesh has exactly the high-order mesh's nodes
/// (same ids, same coordinates, same classification), so sub-elements of
/// neighbouring elements share nodes.
///
/// Ideal: "the ideal element associated to each sub-element is the
/// corresponding sub-element of the ideal high-order element" (appendix C).
/// The ideal high-order element has its nodes at the Nodes reference points
/// mapped by the straight-sided map; neighbouring ideal elements agree on
/// shared nodes (a node set's edge and face nodes depend only on the edge or
/// face, and the straight-sided map restricted to them only on their
/// vertices), so the sub-mesh's ideal is stored per node like any mesh's:
/// its ideal coordinates are the ideal high-order node positions.
///
/// Recovery: the sub-mesh nodes are the high-order nodes, so after the
/// sub-mesh is moved (optimized), `recover_from_sub_mesh` copies its node
/// coordinates back; nothing is interpolated.

#include <stdexcept>
#include <vector>

#include "hom/element/sub_elements.hpp"
#include "hom/mesh/mesh.hpp"

namespace hom {

template <ElementFamily Family, NodeSet Nodes, int SpaceDim>
struct LinearSubMesh {
  /// Degree 1, same nodes as the high-order mesh.
  Mesh<Family, Nodes, SpaceDim> mesh;
  /// High-order element of each sub-element.
  std::vector<int> parent;
  /// Index of each sub-element in its parent's linear_sub_elements(p) list.
  std::vector<int> local;
};

template <ElementFamily Family, NodeSet Nodes, int SpaceDim>
LinearSubMesh<Family, Nodes, SpaceDim> linear_sub_mesh(const Mesh<Family, Nodes, SpaceDim>& high) {
  using M = Mesh<Family, Nodes, SpaceDim>;
  const int p = high.degree();
  const auto split = linear_sub_elements<Family>(p);
  const int ns = static_cast<int>(split.size());
  typename M::Connectivity conn(Family::num_vertices, Eigen::Index(ns) * high.num_elements());
  LinearSubMesh<Family, Nodes, SpaceDim> out;
  out.parent.resize(conn.cols());
  out.local.resize(conn.cols());
  typename M::Coordinates ideal = high.nodes();
  for (int e = 0; e < high.num_elements(); ++e) {
    const auto ideal_nodes = high.ideal_element_coordinates(e);
    for (int s = 0; s < ns; ++s) {
      const int col = e * ns + s;
      for (int k = 0; k < Family::num_vertices; ++k) conn(k, col) = high.element(e)[split[s][k]];
      out.parent[col] = e;
      out.local[col] = s;
    }
    for (int i = 0; i < high.nodes_per_element(); ++i) ideal.col(high.element(e)[i]) = ideal_nodes.col(i);
  }
  out.mesh = M(1, high.nodes(), std::move(conn));
  out.mesh.node_classes() = high.node_classes();
  std::vector<int> entities(out.parent.size());
  for (std::size_t s = 0; s < entities.size(); ++s) entities[s] = high.element_entities()[out.parent[s]];
  out.mesh.element_entities() = std::move(entities);
  out.mesh.entities() = high.entities();
  out.mesh.physical_groups() = high.physical_groups();
  out.mesh.set_ideal_coordinates(std::move(ideal));
  return out;
}

/// Copies the (moved) sub-mesh node coordinates back into the high-order mesh.
template <ElementFamily Family, NodeSet Nodes, int SpaceDim>
void recover_from_sub_mesh(const LinearSubMesh<Family, Nodes, SpaceDim>& sub, Mesh<Family, Nodes, SpaceDim>& high) {
  if (sub.mesh.num_nodes() != high.num_nodes())
    throw std::invalid_argument("hom::recover_from_sub_mesh: the sub-mesh does not belong to this mesh");
  high.nodes() = sub.mesh.nodes();
}

}  // namespace hom
