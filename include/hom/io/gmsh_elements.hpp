#pragma once
/// @file gmsh_elements.hpp
/// Gmsh element types and Gmsh's local node order of complete Lagrange
/// elements, derived algorithmically (test/check_gmsh_ordering.py compares
/// every type with gmsh.model.mesh.getElementProperties).
///
/// Gmsh's reference elements: triangle / tetrahedron with vertices 0, e1, e2
/// (, e3) and quadrilateral / hexahedron [-1, 1]^Dim with the same vertex order
/// as hom's, so a Gmsh node has the same lattice index in both. Nodes are
/// equispaced. Order (recursive):
///   - line:          the two vertices, then the interior nodes from v0 to v1;
///   - triangle:      vertices; edges (0,1), (1,2), (2,0), each from its first
///                    vertex; the interior as a triangle of order p - 3 on the
///                    lattice shifted by (1, 1);
///   - quadrilateral: vertices; edges (0,1), (1,2), (2,3), (3,0); the interior
///                    as a quadrilateral of order p - 2 shifted by (1, 1);
///   - tetrahedron:   vertices; edges (0,1), (1,2), (2,0), (3,0), (3,2), (3,1);
///                    faces (0,2,1), (0,1,3), (0,3,2), (3,1,2), each face's
///                    interior a triangle of order p - 3 whose vertices sit
///                    one lattice step inside the face's (f0, f1, f2); the
///                    interior a tetrahedron of order p - 4 shifted by (1,1,1);
///   - hexahedron:    vertices; edges (0,1), (0,3), (0,4), (1,2), (1,5),
///                    (2,3), (2,6), (3,7), (4,5), (4,7), (5,6), (6,7); faces
///                    (0,3,2,1), (0,1,5,4), (0,4,7,3), (1,2,6,5), (2,3,7,6),
///                    (4,5,6,7), each face's interior a quadrilateral of order
///                    p - 2 along f0 -> f1 and f0 -> f3; the interior a
///                    hexahedron of order p - 2 shifted by (1,1,1).
/// An element of order 0 is its single (centre) node.

#include <array>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "hom/element/node_layout.hpp"
#include "hom/io/error.hpp"

namespace hom::io {

enum class GmshShape { point, line, triangle, quadrilateral, tetrahedron, hexahedron };

struct GmshElementInfo {
  int type = 0;
  GmshShape shape = GmshShape::point;
  int dim = 0;
  int order = 0;
  int num_nodes = 0;
};

namespace detail {

inline constexpr int kMaxGmshOrder = 10;
// Gmsh type numbers of the complete Lagrange elements of order 1..10 (0: none).
inline constexpr int kLineTypes[kMaxGmshOrder] = {1, 8, 26, 27, 28, 62, 63, 64, 65, 66};
inline constexpr int kTriangleTypes[kMaxGmshOrder] = {2, 9, 21, 23, 25, 42, 43, 44, 45, 46};
inline constexpr int kQuadrilateralTypes[kMaxGmshOrder] = {3, 10, 36, 37, 38, 47, 48, 49, 50, 51};
inline constexpr int kTetrahedronTypes[kMaxGmshOrder] = {4, 11, 29, 30, 31, 71, 72, 73, 74, 75};
inline constexpr int kHexahedronTypes[kMaxGmshOrder] = {5, 12, 92, 93, 94, 95, 96, 97, 98, 0};

inline constexpr const int* types_of(GmshShape s) {
  switch (s) {
    case GmshShape::line: return kLineTypes;
    case GmshShape::triangle: return kTriangleTypes;
    case GmshShape::quadrilateral: return kQuadrilateralTypes;
    case GmshShape::tetrahedron: return kTetrahedronTypes;
    case GmshShape::hexahedron: return kHexahedronTypes;
    default: return nullptr;
  }
}

inline int shape_num_nodes(GmshShape s, int p) {
  switch (s) {
    case GmshShape::point: return 1;
    case GmshShape::line: return p + 1;
    case GmshShape::triangle: return (p + 1) * (p + 2) / 2;
    case GmshShape::quadrilateral: return (p + 1) * (p + 1);
    case GmshShape::tetrahedron: return (p + 1) * (p + 2) * (p + 3) / 6;
    case GmshShape::hexahedron: return (p + 1) * (p + 1) * (p + 1);
  }
  return 0;
}

inline int shape_dim(GmshShape s) {
  switch (s) {
    case GmshShape::point: return 0;
    case GmshShape::line: return 1;
    case GmshShape::triangle:
    case GmshShape::quadrilateral: return 2;
    default: return 3;
  }
}

}  // namespace detail

inline std::string_view shape_name(GmshShape s) {
  switch (s) {
    case GmshShape::point: return "point";
    case GmshShape::line: return "line";
    case GmshShape::triangle: return "triangle";
    case GmshShape::quadrilateral: return "quadrilateral";
    case GmshShape::tetrahedron: return "tetrahedron";
    case GmshShape::hexahedron: return "hexahedron";
  }
  return "?";
}

/// The types hom reads and writes: points (15) and complete Lagrange lines,
/// triangles, quadrilaterals, tetrahedra (orders 1..10) and hexahedra (1..9).
inline std::optional<GmshElementInfo> gmsh_element_info(int type) {
  if (type == 15) return GmshElementInfo{15, GmshShape::point, 0, 0, 1};
  for (GmshShape s : {GmshShape::line, GmshShape::triangle, GmshShape::quadrilateral, GmshShape::tetrahedron,
                      GmshShape::hexahedron}) {
    const int* t = detail::types_of(s);
    for (int p = 1; p <= detail::kMaxGmshOrder; ++p)
      if (t[p - 1] == type) return GmshElementInfo{type, s, detail::shape_dim(s), p, detail::shape_num_nodes(s, p)};
  }
  return std::nullopt;
}

/// A readable description of a Gmsh type hom does not support, for messages.
inline std::string gmsh_unsupported_type_name(int type) {
  switch (type) {
    case 6: case 13: case 18: case 89: case 90: case 91: case 106: case 107: case 108: case 109: case 110:
      return "prism";
    case 7: case 14: case 19: case 118: case 119: case 120: case 121: case 122: case 123: case 124:
      return "pyramid";
    case 16: case 39: case 40: case 41: case 57: case 58: case 59: case 60: case 61:
      return "serendipity/incomplete quadrilateral";
    case 20: case 22: case 24: case 52: case 53: case 54: case 55: case 56:
      return "serendipity/incomplete triangle";
    case 32: case 33: case 79: case 80: case 81: case 82: case 83: case 137:
      return "serendipity/incomplete tetrahedron";
    case 17: case 99: case 100: case 101: case 102: case 103: case 104: case 105:
      return "serendipity/incomplete hexahedron";
    case 34: case 35: case 69: return "polygon/polyhedron";
    default: return "unknown";
  }
}

/// Gmsh type number of a complete Lagrange element; IoError if Gmsh has none
/// (orders above 10, hexahedra above 9).
inline int gmsh_element_type(GmshShape s, int p) {
  if (s == GmshShape::point) return 15;
  const int* t = detail::types_of(s);
  if (p < 1 || p > detail::kMaxGmshOrder || t[p - 1] == 0)
    throw IoError("Gmsh has no complete " + std::string(shape_name(s)) + " of order " + std::to_string(p));
  return t[p - 1];
}

template <ElementFamily F>
inline constexpr GmshShape gmsh_shape_of = F::is_simplex ? (F::dim == 2 ? GmshShape::triangle : GmshShape::tetrahedron)
                                                         : (F::dim == 2 ? GmshShape::quadrilateral : GmshShape::hexahedron);

/// Shape of the facets (edges in 2D, faces in 3D) of family F.
template <ElementFamily F>
inline constexpr GmshShape gmsh_facet_shape_of =
    F::dim == 2 ? GmshShape::line : (F::is_simplex ? GmshShape::triangle : GmshShape::quadrilateral);

namespace detail {

template <int D>
Lattice<D> lattice_add(Lattice<D> a, const Lattice<D>& b) {
  for (int k = 0; k < D; ++k) a[k] += b[k];
  return a;
}

template <ElementFamily F>
void gmsh_edges(int p, const std::vector<std::array<int, 2>>& edges, std::vector<Lattice<F::dim>>& out) {
  for (const auto& [a, b] : edges) {
    const auto la = F::vertex_lattice(a, p), lb = F::vertex_lattice(b, p);
    for (int i = 1; i < p; ++i) {
      Lattice<F::dim> l{};
      for (int k = 0; k < F::dim; ++k) l[k] = la[k] + i * (lb[k] - la[k]) / p;
      out.push_back(l);
    }
  }
}

// Face interiors: the face sub-element `sub` (face-local lattice indices in
// their own order), embedded one lattice step inside face (f0, f1, ...) along
// the axes f0 -> f1 and f0 -> f[axis2].
template <ElementFamily F>
void gmsh_faces(int p, const std::vector<std::vector<int>>& faces, int axis2, const std::vector<Lattice<2>>& sub,
                std::vector<Lattice<F::dim>>& out) {
  for (const auto& f : faces) {
    const auto l0 = F::vertex_lattice(f[0], p), l1 = F::vertex_lattice(f[1], p), l2 = F::vertex_lattice(f[axis2], p);
    for (const auto& st : sub) {
      Lattice<F::dim> l{};
      for (int k = 0; k < F::dim; ++k)
        l[k] = l0[k] + (st[0] + 1) * (l1[k] - l0[k]) / p + (st[1] + 1) * (l2[k] - l0[k]) / p;
      out.push_back(l);
    }
  }
}

}  // namespace detail

/// Gmsh's local node order of the complete Lagrange element of order p (p >= 0)
/// as hom lattice indices.
template <ElementFamily F>
std::vector<Lattice<F::dim>> gmsh_node_lattice(int p) {
  constexpr int D = F::dim;
  std::vector<Lattice<D>> out;
  if (p == 0) return {Lattice<D>{}};
  for (int v = 0; v < F::num_vertices; ++v) out.push_back(F::vertex_lattice(v, p));
  Lattice<D> one{};
  one.fill(1);
  if constexpr (F::is_simplex && D == 2) {
    detail::gmsh_edges<F>(p, {{0, 1}, {1, 2}, {2, 0}}, out);
    if (p >= 3)
      for (const auto& l : gmsh_node_lattice<F>(p - 3)) out.push_back(detail::lattice_add<D>(l, one));
  } else if constexpr (!F::is_simplex && D == 2) {
    detail::gmsh_edges<F>(p, {{0, 1}, {1, 2}, {2, 3}, {3, 0}}, out);
    if (p >= 2)
      for (const auto& l : gmsh_node_lattice<F>(p - 2)) out.push_back(detail::lattice_add<D>(l, one));
  } else if constexpr (F::is_simplex) {
    detail::gmsh_edges<F>(p, {{0, 1}, {1, 2}, {2, 0}, {3, 0}, {3, 2}, {3, 1}}, out);
    if (p >= 3)
      detail::gmsh_faces<F>(p, {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {3, 1, 2}}, 2, gmsh_node_lattice<Simplex<2>>(p - 3),
                            out);
    if (p >= 4)
      for (const auto& l : gmsh_node_lattice<F>(p - 4)) out.push_back(detail::lattice_add<D>(l, one));
  } else {
    detail::gmsh_edges<F>(
        p, {{0, 1}, {0, 3}, {0, 4}, {1, 2}, {1, 5}, {2, 3}, {2, 6}, {3, 7}, {4, 5}, {4, 7}, {5, 6}, {6, 7}}, out);
    if (p >= 2) {
      detail::gmsh_faces<F>(p, {{0, 3, 2, 1}, {0, 1, 5, 4}, {0, 4, 7, 3}, {1, 2, 6, 5}, {2, 3, 7, 6}, {4, 5, 6, 7}}, 3,
                            gmsh_node_lattice<Cube<2>>(p - 2), out);
      for (const auto& l : gmsh_node_lattice<F>(p - 2)) out.push_back(detail::lattice_add<D>(l, one));
    }
  }
  return out;
}

/// perm[k] = hom local node (NodeLayout order) of Gmsh local node k; cached.
template <ElementFamily F>
const std::vector<int>& gmsh_to_hom(int p) {
  static std::mutex mutex;
  static std::map<int, std::vector<int>> cache;
  const std::lock_guard lock(mutex);
  auto it = cache.find(p);
  if (it == cache.end()) {
    const auto& layout = node_layout<F>(p);
    std::vector<int> perm;
    for (const auto& l : gmsh_node_lattice<F>(p)) perm.push_back(layout.index_of(l));
    it = cache.emplace(p, std::move(perm)).first;
  }
  return it->second;
}

/// Gmsh's line order as positions along the line: 0, p, 1, ..., p - 1. This
/// is also hom's facet order of an edge (mesh/facet.hpp), so lines need no
/// permutation.
inline std::vector<int> gmsh_line_positions(int p) {
  std::vector<int> out{0, p};
  for (int i = 1; i < p; ++i) out.push_back(i);
  return out;
}

}  // namespace hom::io
