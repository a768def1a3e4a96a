#pragma once
/// @file vtk_cells.hpp
/// VTK's Lagrange cells (VTK >= 9, XML file version 2.2) and their local node
/// order, derived algorithmically (test/check_vtu.py compares with
/// vtkLagrange*::GetParametricCoords for every order 1..10 and reads written
/// files back with VTK).
///
/// VTK's reference elements are the unit simplex and [0, 1]^Dim, with hom's
/// vertex order, and the nodes are equispaced, so a VTK node has the same
/// lattice index as hom's. Order:
///   - triangle (69):      as Gmsh's (vertices, edges (0,1), (1,2), (2,0), the
///                         interior recursively as a triangle of order p - 3);
///   - quadrilateral (70): vertices; edges (0,1), (1,2), (3,2), (0,3), each
///                         along its axis; interior with x fastest;
///   - tetrahedron (71):   vertices; edges (0,1), (1,2), (2,0), (0,3), (1,3),
///                         (2,3); faces (0,1,3), (2,3,1), (0,3,2), (0,2,1), each
///                         face interior recursively as a triangle of order
///                         p - 3 on that vertex order; the interior recursively
///                         as a tetrahedron of order p - 4;
///   - hexahedron (72):    vertices; edges (0,1), (1,2), (3,2), (0,3), (4,5),
///                         (5,6), (7,6), (4,7), (0,4), (1,5), (2,6), (3,7) (the
///                         order of the last four changed in VTK 9 / file
///                         version 2.2); faces x = 0, x = 1, y = 0, y = 1,
///                         z = 0, z = 1, each with its first free axis fastest;
///                         interior x fastest, then y, then z.

#include <map>
#include <mutex>
#include <vector>

#include "hom/element/node_layout.hpp"
#include "hom/io/gmsh_elements.hpp"

namespace hom::io {

template <ElementFamily F>
inline constexpr int vtk_lagrange_cell_type = F::is_simplex ? (F::dim == 2 ? 69 : 71) : (F::dim == 2 ? 70 : 72);

/// VTK's local node order of the Lagrange cell of order p as hom lattice indices.
template <ElementFamily F>
std::vector<Lattice<F::dim>> vtk_node_lattice(int p) {
  constexpr int D = F::dim;
  using L = Lattice<D>;
  if constexpr (F::is_simplex && D == 2) {
    return gmsh_node_lattice<F>(p);
  } else if constexpr (F::is_simplex) {
    if (p == 0) return {L{}};
    std::vector<L> out;
    for (int v = 0; v < 4; ++v) out.push_back(F::vertex_lattice(v, p));
    detail::gmsh_edges<F>(p, {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}}, out);
    if (p >= 3)
      detail::gmsh_faces<F>(p, {{0, 1, 3}, {2, 3, 1}, {0, 3, 2}, {0, 2, 1}}, 2, vtk_node_lattice<Simplex<2>>(p - 3), out);
    if (p >= 4)
      for (auto l : vtk_node_lattice<F>(p - 4)) {
        for (int& c : l) ++c;
        out.push_back(l);
      }
    return out;
  } else {
    std::vector<L> out;
    for (int v = 0; v < F::num_vertices; ++v) out.push_back(F::vertex_lattice(v, p));
    if constexpr (D == 2) {
      detail::gmsh_edges<F>(p, {{0, 1}, {1, 2}, {3, 2}, {0, 3}}, out);
      for (int j = 1; j < p; ++j)
        for (int i = 1; i < p; ++i) out.push_back({i, j});
    } else {
      detail::gmsh_edges<F>(
          p, {{0, 1}, {1, 2}, {3, 2}, {0, 3}, {4, 5}, {5, 6}, {7, 6}, {4, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}}, out);
      // Faces normal to axis a at 0 then p, free axes in increasing order.
      for (int a = 0; a < 3; ++a)
        for (int side : {0, p}) {
          const int u = a == 0 ? 1 : 0, v = a == 2 ? 1 : 2;
          for (int j = 1; j < p; ++j)
            for (int i = 1; i < p; ++i) {
              L l{};
              l[a] = side;
              l[u] = i;
              l[v] = j;
              out.push_back(l);
            }
        }
      for (int k = 1; k < p; ++k)
        for (int j = 1; j < p; ++j)
          for (int i = 1; i < p; ++i) out.push_back({i, j, k});
    }
    return out;
  }
}

/// perm[k] = hom local node of VTK local node k; cached.
template <ElementFamily F>
const std::vector<int>& vtk_to_hom(int p) {
  static std::mutex mutex;
  static std::map<int, std::vector<int>> cache;
  const std::lock_guard lock(mutex);
  auto it = cache.find(p);
  if (it == cache.end()) {
    const auto& layout = node_layout<F>(p);
    std::vector<int> perm;
    for (const auto& l : vtk_node_lattice<F>(p)) perm.push_back(layout.index_of(l));
    it = cache.emplace(p, std::move(perm)).first;
  }
  return it->second;
}

}  // namespace hom::io
