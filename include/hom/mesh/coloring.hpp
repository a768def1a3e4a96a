#pragma once
/// @file coloring.hpp
/// Greedy colorings for parallel sweeps (appendix B: non-linear Gauss-Seidel
/// updates nodes one at a time; nodes of one color can be updated
/// concurrently because no element contains two of them).
///
///   - color_nodes:    no two nodes of one color share an element;
///   - color_elements: no two elements of one color share a node (so
///                     per-element work of one color can scatter into nodes
///                     without races).
///
/// Greedy first-fit in the given order: every item gets the smallest color
/// not used by an already-colored conflicting item, so the number of colors is
/// at most (maximum number of conflicts of an item) + 1.

#include <span>
#include <vector>

#include "hom/mesh/topology.hpp"

namespace hom {

/// groups[c] lists the items (node or element ids) of color c, in the order they were colored.
struct Coloring {
  std::vector<std::vector<int>> groups;
  int num_colors() const { return static_cast<int>(groups.size()); }
};

/// Colors the given nodes (ids into the mesh) so that no element contains two
/// nodes of one color. Nodes not listed get no color (e.g. fixed nodes).
template <class MeshT>
Coloring color_nodes(const MeshT& mesh, const Topology<typename MeshT::family>& topo, std::span<const int> nodes) {
  std::vector<int> color(mesh.num_nodes(), -1);  // -1: not colored yet (local bookkeeping only)
  std::vector<int> stamp;                         // stamp[c] == node + 1: color c is taken for node
  Coloring out;
  const auto& conn = mesh.elements();
  for (int n : nodes) {
    for (int e : topo.node_elements(n))
      for (Eigen::Index i = 0; i < conn.rows(); ++i) {
        const int c = color[conn(i, e)];
        if (c >= 0) stamp[c] = n + 1;
      }
    int c = 0;
    while (c < int(stamp.size()) && stamp[c] == n + 1) ++c;
    if (c == int(stamp.size())) {
      stamp.push_back(0);
      out.groups.emplace_back();
    }
    color[n] = c;
    out.groups[c].push_back(n);
  }
  return out;
}

/// All nodes.
template <class MeshT>
Coloring color_nodes(const MeshT& mesh, const Topology<typename MeshT::family>& topo) {
  std::vector<int> all(mesh.num_nodes());
  for (int i = 0; i < mesh.num_nodes(); ++i) all[i] = i;
  return color_nodes(mesh, topo, all);
}

/// Colors all elements so that no two elements of one color share a node.
/// (In a conforming mesh two elements share a node iff they share a vertex,
/// so only vertices are looked at.)
template <class MeshT>
Coloring color_elements(const MeshT& mesh, const Topology<typename MeshT::family>& topo) {
  std::vector<int> color(mesh.num_elements(), -1);
  std::vector<int> stamp;
  Coloring out;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    for (int v = 0; v < MeshT::num_vertices; ++v)
      for (int o : topo.node_elements(mesh.vertex(e, v)))
        if (color[o] >= 0) stamp[color[o]] = e + 1;
    int c = 0;
    while (c < int(stamp.size()) && stamp[c] == e + 1) ++c;
    if (c == int(stamp.size())) {
      stamp.push_back(0);
      out.groups.emplace_back();
    }
    color[e] = c;
    out.groups[c].push_back(e);
  }
  return out;
}

}  // namespace hom
