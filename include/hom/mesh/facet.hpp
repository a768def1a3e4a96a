#pragma once
/// @file facet.hpp
/// Facets of a reference element (edges in 2D, faces in 3D) and the local
/// nodes that lie on them, in the facet's own node order.
///
/// A facet's own node order is the order its lower-dimensional element would
/// list them in hom's layout:
///   - 2D (a line a -> b):   a, b, then the interior nodes from a to b;
///   - 3D (a face):          node_layout<Simplex<2>> or node_layout<Cube<2>>
///                           with the face's vertices taken in the given order.
/// The facet lattice maps into the element lattice affinely: with the facet's
/// vertices (a0, a1, ...) in the element, facet lattice index (s, t) is element
/// lattice index L(a0) + s (L(a_s) - L(a0)) / p + t (L(a_t) - L(a0)) / p, where
/// a_s = a1 and a_t = a2 on a triangle, a_t = a3 on a quadrilateral (the
/// vertices adjacent to a0 along the facet's two axes).

#include <array>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <vector>

#include "hom/element/node_layout.hpp"

namespace hom {

/// The reference family of a 3D element's faces.
template <ElementFamily Family>
using FaceFamily = std::conditional_t<Family::is_simplex, Simplex<2>, Cube<2>>;

/// Number of vertices of a facet: 2 (edge of a 2D element), 3 or 4 (face).
template <ElementFamily Family>
inline constexpr int facet_num_vertices = Family::dim == 2 ? 2 : (Family::is_simplex ? 3 : 4);

template <ElementFamily Family>
using FacetVertices = std::array<int, facet_num_vertices<Family>>;

/// Number of facets of the element: 3, 4 (2D) or 4, 6 (3D).
template <ElementFamily Family>
inline constexpr int num_facets = Family::dim == 2 ? Family::num_vertices : (Family::is_simplex ? 4 : 6);

/// Nodes of a facet of degree p: p + 1 (edge) or the face family's n_p.
template <ElementFamily Family>
constexpr int facet_num_nodes(int p) {
  if constexpr (Family::dim == 2)
    return p + 1;
  else
    return FaceFamily<Family>::num_nodes(p);
}

/// Local vertices of facet f, oriented outward: in 2D the boundary is
/// traversed counter-clockwise (interior on the left), in 3D `Family::faces()`
/// is already outward (right-hand rule).
template <ElementFamily Family>
constexpr FacetVertices<Family> facet_vertices(int f) {
  if constexpr (Family::dim == 2) {
    // Counter-clockwise boundary cycle 0 -> 1 -> 2 (-> 3) -> 0.
    return {f, (f + 1) % Family::num_vertices};
  } else {
    const auto faces = Family::faces();
    FacetVertices<Family> v{};
    for (int k = 0; k < facet_num_vertices<Family>; ++k) v[k] = faces[f][k];
    return v;
  }
}

/// Local element nodes on the facet whose vertices, in the wanted order, are
/// the local vertices `verts` (any rotation or reflection of a facet's vertex
/// cycle), listed in the facet's own node order (see the file comment).
/// Throws std::invalid_argument if `verts` is not a facet in cyclic order.
template <ElementFamily Family>
std::vector<int> facet_nodes(int p, const FacetVertices<Family>& verts) {
  constexpr int D = Family::dim;
  const auto& layout = node_layout<Family>(p);
  auto L = [&](int v) { return Family::vertex_lattice(v, p); };
  auto to_element = [&](const std::array<int, D - 1>& lf) {
    Lattice<D> l = L(verts[0]);
    int axis_vertex[2] = {verts[1], 0};
    if constexpr (D == 3) axis_vertex[1] = Family::is_simplex ? verts[2] : verts[3];
    for (int k = 0; k < D - 1; ++k) {
      const auto la = L(axis_vertex[k]);
      for (int a = 0; a < D; ++a) l[a] += lf[k] * (la[a] - L(verts[0])[a]) / p;
    }
    const int i = layout.index_of(l);
    if (i < 0) throw std::invalid_argument("hom::facet_nodes: vertices do not form a facet of the element");
    return i;
  };
  if constexpr (!Family::is_simplex) {
    // A cube facet's axes run along reference axes: one lattice direction each.
    const int axis_vertex[2] = {verts[1], D == 3 ? verts[D == 3 ? 3 : 1] : verts[1]};
    for (int k = 0; k < D - 1; ++k) {
      int moved = 0;
      for (int a = 0; a < D; ++a) moved += L(axis_vertex[k])[a] != L(verts[0])[a];
      if (moved != 1) throw std::invalid_argument("hom::facet_nodes: vertices do not form a facet of the element");
    }
  }
  std::vector<int> out;
  if constexpr (D == 2) {
    out.reserve(p + 1);
    out.push_back(to_element({0}));
    out.push_back(to_element({p}));
    for (int i = 1; i < p; ++i) out.push_back(to_element({i}));
  } else {
    const auto& fl = node_layout<FaceFamily<Family>>(p);
    out.reserve(fl.size());
    for (int i = 0; i < fl.size(); ++i) out.push_back(to_element(fl.lattice(i)));
  }
  // The corners must be the requested vertices (a non-facet tuple would map
  // some corner elsewhere or off the lattice).
  for (int k = 0; k < facet_num_vertices<Family>; ++k)
    if (out[k] != verts[k]) throw std::invalid_argument("hom::facet_nodes: vertices do not form a facet of the element");
  return out;
}

/// facet_nodes for facet f in its outward orientation, cached.
template <ElementFamily Family>
const std::vector<int>& facet_nodes(int p, int f) {
  static std::mutex mutex;
  static std::map<std::pair<int, int>, std::vector<int>> cache;
  const std::lock_guard lock(mutex);
  auto it = cache.find({p, f});
  if (it == cache.end()) it = cache.emplace(std::pair{p, f}, facet_nodes<Family>(p, facet_vertices<Family>(f))).first;
  return it->second;
}

}  // namespace hom
