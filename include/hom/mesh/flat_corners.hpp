#pragma once
/// @file flat_corners.hpp
/// Simplices of a linear mesh with a "flat corner", and their repair by
/// edge splitting, before the mesh is curved (chapter 6's a posteriori
/// approach).
///
/// At a vertex of a Lagrange simplex, D phi is spanned by the tangents of the
/// element's edges there (each column of D phi at a vertex is the derivative
/// along one of the d edges from it). If all d edges from vertex a lie on one
/// smooth boundary entity (a curve in 2D, a surface in 3D: each edge is an
/// edge of a boundary facet classified on that entity), or on patches of one
/// smooth surface (boundary facets of several entities, nearly coplanar
/// around a), then once they are
/// curved onto it their tangents lie in its tangent line / plane at a (up to
/// the interpolation error of the curved edges), so det(D phi(a)) is zero
/// or nearly so, with a sign the boundary alone sets, whatever the free
/// nodes do: the optimizer (chapter 4) and any repair that moves interior
/// nodes cannot make the element valid.
/// A tetrahedron with two faces on the same surface (a linear mesher makes
/// them at a reflex edge of the surface triangulation, and on thin parts) has
/// two such corners; a triangle with two edges on one curve, one.
///
/// The repair is topological: an edge of the element's facet opposite the
/// flat corner that is not a boundary edge (the longest such) is split at its
/// midpoint, with every element around it (each into two, the halves keeping
/// the orientation). Where every edge of the element is a boundary edge (a
/// tetrahedron with three or four faces on the boundary, as at a thin
/// trailing edge), the element alone is split at its centroid into d + 1.
/// A straight corner (FlatCorner) whose two boundary edges' far ends are
/// joined by a boundary edge has its interior face through the three split
/// at its centre instead, with both tetrahedra on it.
/// Afterwards every corner of the new elements has an edge to the new,
/// interior node, so none is flat; the boundary facets keep their vertices
/// (the split edge is on none; a centroid split keeps the facets). The
/// analogue for quadrilaterals and surface triangles, whose corners on a
/// curve the mesher splits, is src/cad/ears.hpp.

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "hom/element/simplex.hpp"
#include "hom/mesh/facet.hpp"
#include "hom/mesh/mesh.hpp"

namespace hom {

namespace detail {

using MeshEdge = std::pair<int, int>;
inline MeshEdge mesh_edge(int a, int b) { return a < b ? MeshEdge{a, b} : MeshEdge{b, a}; }

/// The boundary facets (indices into mesh.boundary_facets()) each boundary
/// edge belongs to.
template <int D, NodeSet Nodes>
std::map<MeshEdge, std::vector<int>> boundary_edge_facets(const Mesh<Simplex<D>, Nodes, D>& mesh) {
  std::map<MeshEdge, std::vector<int>> out;
  const auto& facets = mesh.boundary_facets();
  for (int k = 0; k < int(facets.size()); ++k)
    for (int i = 0; i < D; ++i)
      for (int j = i + 1; j < D; ++j) out[mesh_edge(facets[k].vertices[i], facets[k].vertices[j])].push_back(k);
  return out;
}

/// Unit normal of a straight boundary facet (either orientation).
template <int D, NodeSet Nodes>
Eigen::Matrix<double, D, 1> facet_normal(const Mesh<Simplex<D>, Nodes, D>& mesh, const BoundaryFacet<Simplex<D>>& f) {
  if constexpr (D == 2) {
    const Eigen::Vector2d t = mesh.node(f.vertices[1]) - mesh.node(f.vertices[0]);
    return Eigen::Vector2d(-t[1], t[0]).normalized();
  } else {
    const Eigen::Vector3d x0 = mesh.node(f.vertices[0]), x1 = mesh.node(f.vertices[1]), x2 = mesh.node(f.vertices[2]);
    return (x1 - x0).cross(x2 - x0).normalized();
  }
}

}  // namespace detail

/// A flat corner of a simplex: local vertex `vertex` of element `element`,
/// whose d edges all lie on boundary entity `entity` (see above), or on
/// boundary facets of several entities that are within
/// `flat_corner_max_angle` of coplanar there (patches of one smooth surface,
/// such as the two halves of a wing's leading edge; `entity` is then one of
/// them), or on entities whose geometry has one tangent plane (line) there
/// (EntityNormal: faces meeting tangentially, as a fillet meets the faces it
/// rounds; `entity` is then one of them).
///
/// A straight corner (tetrahedra, with EntityNormal): two edges from vertex
/// `vertex` lie on the boundary, on entities with one tangent plane there,
/// and their chords projected onto the plane either point to opposite sides
/// (within flat_corner_max_angle of antiparallel) or turn the other way
/// round than the chords themselves. Curved, both edges end tangent to the
/// plane, along the projected chords, so det D phi at the corner is zero (an
/// angle of 180 degrees) or has the sign opposite to the straight element's,
/// whatever its third, interior edge does: the sign of det D phi there is
/// that of (t_b x t_c) . t_d, and the curved t_b, t_c are set by the
/// boundary. The first happens where an element's edge spans a fillet
/// narrower than the elements and its neighbour continues on the face beyond
/// the fillet's seam; the second where two edges go round a body thinner
/// than the elements (a fuselage's tail tip) to its far side. Local vertices
/// `split_from` and `split_to` are the two edges' other ends: the edge
/// between them is split if it is interior, else the face (vertex,
/// split_from, split_to), which is then interior, at its centre. Either
/// leaves each new element at the corner with one edge on the boundary.
///
/// The two boundary edges may also lie on entities with no common tangent
/// plane, as at a wing tip's leading edge, where the tip face meets the
/// wing at a right angle and the wing's upper and lower faces meet
/// tangentially: there each edge's curved direction is taken alone (its
/// chord projected onto its entity's tangent plane, or the tangent line of
/// the curve between its two entities, n1 x n2), and a corner whose two
/// directions turn the other way round than the chords is a straight corner
/// too (an edge on the tip's airfoil curve, along the leading edge, and one
/// on the lower face, both in the wing's tangent plane, with the third edge
/// interior).
struct FlatCorner {
  int element = 0;
  int vertex = 0;
  int entity = 0;
  int split_from = -1;  ///< straight corners only (see above); -1 otherwise
  int split_to = -1;
};

/// The largest angle between the straight boundary facets around a corner
/// on several entities for it to count as flat (30 degrees): on a smooth
/// surface the facets' normals approach the surface's as the mesh is
/// refined, and a split where the surface has a crease only adds an
/// interior node.
inline constexpr double flat_corner_max_angle = 0.5235987755982988;

/// The unit normal of boundary entity `entity` (a CAD face in 3D, a curve in
/// 2D) at mesh node `node`, from the geometry the mesh discretizes (either
/// orientation); empty where there is none (a pole, a cone's apex). With it,
/// a corner whose edges lie on several entities is flat also when the
/// entities' normals there are within flat_corner_max_angle, however far
/// apart the straight facets' normals are: across a fillet narrower than the
/// elements the facets meet at a wide angle, yet the curved edges all end
/// tangent to the fillet's tangent plane at a node on its tangent seam.
template <int D>
using EntityNormal = std::function<std::optional<Eigen::Matrix<double, D, 1>>(int entity, int node)>;

namespace detail {

/// Whether the unit vectors are pairwise within the angle whose cosine is
/// min_cos of parallel (either orientation).
template <int D>
bool nearly_parallel(const std::vector<Eigen::Matrix<double, D, 1>>& normals, double min_cos) {
  for (std::size_t i = 0; i < normals.size(); ++i)
    for (std::size_t j = i + 1; j < normals.size(); ++j)
      if (std::abs(normals[i].dot(normals[j])) < min_cos) return false;
  return true;
}

/// The normals at mesh node `node` of the entities of the facets `around`,
/// by entity tag, each evaluated once (a projection onto a CAD surface);
/// empty where one has none.
template <int D>
std::optional<std::map<int, Eigen::Matrix<double, D, 1>>> entity_normals(
    const std::vector<BoundaryFacet<Simplex<D>>>& facets, const std::vector<int>& around, int node,
    const EntityNormal<D>& normal) {
  std::map<int, Eigen::Matrix<double, D, 1>> normals;
  for (int k : around) {
    const int t = facets[k].entity_tag;
    if (normals.count(t)) continue;
    const auto n = normal(t, node);
    if (!n) return std::nullopt;
    normals.emplace(t, *n);
  }
  return normals;
}

/// The common tangent plane's normal of entities with these normals: the
/// first one when all are nearly parallel, nothing otherwise.
template <int D>
std::optional<Eigen::Matrix<double, D, 1>> common_normal(const std::map<int, Eigen::Matrix<double, D, 1>>& normals,
                                                         double min_cos) {
  std::vector<Eigen::Matrix<double, D, 1>> all;
  for (const auto& [tag, n] : normals) all.push_back(n);
  if (all.empty() || !nearly_parallel(all, min_cos)) return std::nullopt;
  return all.front();
}

/// The common tangent plane's normal at mesh node `node` of the entities of
/// the facets `around` (see common_normal; nothing where one has no normal).
template <int D>
std::optional<Eigen::Matrix<double, D, 1>> tangent_normal(const std::vector<BoundaryFacet<Simplex<D>>>& facets,
                                                          const std::vector<int>& around, int node,
                                                          const EntityNormal<D>& normal, double min_cos) {
  const auto normals = entity_normals(facets, around, node, normal);
  return normals ? common_normal(*normals, min_cos) : std::nullopt;
}

/// The direction in which a boundary edge leaves a corner once curved (see
/// FlatCorner), from the normals there of the entities of its facets: its
/// chord projected onto their common tangent plane where they have one, else
/// the tangent line of the curve between its two entities (n1 x n2),
/// oriented along the chord; empty where more than two entities meet at an
/// angle.
inline std::optional<Eigen::Vector3d> curved_edge_direction(const std::map<int, Eigen::Vector3d>& normals,
                                                            const Eigen::Vector3d& chord, double min_cos) {
  if (const auto n = common_normal(normals, min_cos)) return Eigen::Vector3d(chord - chord.dot(*n) * *n).normalized();
  if (normals.size() != 2) return std::nullopt;
  const Eigen::Vector3d t = normals.begin()->second.cross(normals.rbegin()->second).normalized();  // not parallel
  return chord.dot(t) < 0.0 ? Eigen::Vector3d(-t) : t;
}

/// Whether mesh nodes a, b, c make a face that is not a boundary facet (so
/// two tetrahedra share it): either b-c is interior, or none of its facets
/// has a.
inline bool interior_face(const std::vector<BoundaryFacet<Simplex<3>>>& facets,
                          const std::map<MeshEdge, std::vector<int>>& on_boundary, int a, int b, int c) {
  const auto it = on_boundary.find(mesh_edge(b, c));
  if (it == on_boundary.end()) return true;
  return std::none_of(it->second.begin(), it->second.end(), [&](int k) {
    return std::find(facets[k].vertices.begin(), facets[k].vertices.end(), a) != facets[k].vertices.end();
  });
}

/// The straight corner at vertex a of tetrahedron e (see FlatCorner), if it
/// has one whose face opposite its interior edge is interior (a face on the
/// boundary would leave nothing to split).
template <NodeSet Nodes>
std::optional<FlatCorner> straight_corner(const Mesh<Simplex<3>, Nodes, 3>& mesh, int e, int a,
                                          const std::map<MeshEdge, std::vector<int>>& on_boundary,
                                          const EntityNormal<3>& normal, double min_cos) {
  const auto& facets = mesh.boundary_facets();
  const int node = mesh.vertex(e, a);
  std::vector<int> ends, around;  // local vertices b with a-b on the boundary, their facets
  std::vector<std::vector<int>> edge_facets;
  for (int b = 0; b <= 3; ++b) {
    if (b == a) continue;
    const auto it = on_boundary.find(mesh_edge(node, mesh.vertex(e, b)));
    if (it == on_boundary.end()) continue;
    ends.push_back(b);
    edge_facets.push_back(it->second);
    around.insert(around.end(), it->second.begin(), it->second.end());
  }
  if (ends.size() != 2) return std::nullopt;  // three: a flat corner of the first kind, if any
  const int b = ends[0], c = ends[1], d = 6 - a - b - c;
  if (!interior_face(facets, on_boundary, node, mesh.vertex(e, b), mesh.vertex(e, c))) return std::nullopt;
  auto chord = [&](int k) -> Eigen::Vector3d { return mesh.node(mesh.vertex(e, k)) - mesh.node(node); };
  // The curved edges' directions at the corner: in the entities' common
  // tangent plane where there is one, else each edge's own (see FlatCorner).
  const auto normals = entity_normals(facets, around, node, normal);
  if (!normals) return std::nullopt;
  Eigen::Vector3d u, v;
  if (const auto tangent = common_normal(*normals, min_cos)) {
    const Eigen::Vector3d n = *tangent;
    u = (chord(b) - chord(b).dot(n) * n).normalized();
    v = (chord(c) - chord(c).dot(n) * n).normalized();
  } else {
    auto of_edge = [&](const std::vector<int>& edge) {  // the normals of one edge's entities
      std::map<int, Eigen::Vector3d> out;
      for (int k : edge) out.emplace(facets[k].entity_tag, normals->at(facets[k].entity_tag));
      return out;
    };
    const auto ub = curved_edge_direction(of_edge(edge_facets[0]), chord(b), min_cos);
    const auto vc = curved_edge_direction(of_edge(edge_facets[1]), chord(c), min_cos);
    if (!ub || !vc) return std::nullopt;
    u = *ub;
    v = *vc;
  }
  const bool straight = u.dot(v) <= -min_cos;
  const double linear = chord(b).cross(chord(c)).dot(chord(d));
  const double curved = u.cross(v).dot(chord(d));
  const bool folded = linear * curved < 0.0;
  if (!straight && !folded) return std::nullopt;
  return FlatCorner{e, a, facets[around.front()].entity_tag, b, c};
}

}  // namespace detail

/// The flat corners of a linear simplex mesh (planar triangles or
/// tetrahedra), from its boundary facets and their entity tags, and from the
/// entities' normals where `normal` is given.
template <int D, NodeSet Nodes>
std::vector<FlatCorner> find_flat_corners(const Mesh<Simplex<D>, Nodes, D>& mesh,
                                          const EntityNormal<D>& normal = {}) {
  const auto on_boundary = detail::boundary_edge_facets(mesh);
  const auto& facets = mesh.boundary_facets();
  const double min_cos = std::cos(flat_corner_max_angle);
  std::vector<FlatCorner> out;
  for (int e = 0; e < mesh.num_elements(); ++e)
    for (int a = 0; a <= D; ++a) {
      // The facets of the edges from vertex a, and the entities every edge has.
      std::vector<int> around;
      std::optional<std::vector<int>> common;
      bool all_on_boundary = true;
      for (int b = 0; b <= D && all_on_boundary; ++b) {
        if (b == a) continue;
        const auto it = on_boundary.find(detail::mesh_edge(mesh.vertex(e, a), mesh.vertex(e, b)));
        if (it == on_boundary.end()) {
          all_on_boundary = false;
          break;
        }
        std::vector<int> tags;
        for (int k : it->second) {
          around.push_back(k);
          tags.push_back(facets[k].entity_tag);
        }
        if (!common)
          common = tags;
        else
          std::erase_if(*common, [&](int t) { return std::find(tags.begin(), tags.end(), t) == tags.end(); });
      }
      if (!all_on_boundary) {
        if constexpr (D == 3)
          if (normal)
            if (const auto c = detail::straight_corner(mesh, e, a, on_boundary, normal, min_cos)) out.push_back(*c);
        continue;
      }
      if (!common->empty()) {
        out.push_back({e, a, common->front()});
        continue;
      }
      std::vector<Eigen::Matrix<double, D, 1>> facet_normals;
      for (int k : around) facet_normals.push_back(detail::facet_normal(mesh, facets[k]));
      if (detail::nearly_parallel(facet_normals, min_cos) ||
          (normal && detail::tangent_normal(facets, around, mesh.vertex(e, a), normal, min_cos)))
        out.push_back({e, a, facets[around.front()].entity_tag});
    }
  return out;
}

/// What split_flat_corners did.
struct FlatCornerSplit {
  int corners = 0;      ///< flat corners found
  int edges_split = 0;     ///< edges split (each adds one node)
  int faces_split = 0;     ///< interior faces split at their centre (each adds one node)
  int centroid_splits = 0; ///< elements split at their centroid (each adds one node)
};

namespace detail {

/// One pass of split_flat_corners: every corner found at its start.
template <int D, NodeSet Nodes>
FlatCornerSplit split_flat_corners_once(Mesh<Simplex<D>, Nodes, D>& mesh, const EntityNormal<D>& normal) {
  using Family = Simplex<D>;
  using MeshT = Mesh<Family, Nodes, D>;
  if (mesh.degree() != 1)
    throw std::invalid_argument("hom::split_flat_corners: the mesh must be linear, it has degree " +
                                std::to_string(mesh.degree()));
  FlatCornerSplit out;
  const auto corners = find_flat_corners(mesh, normal);
  out.corners = int(corners.size());
  if (corners.empty()) return out;

  const auto on_boundary = detail::boundary_edge_facets(mesh);
  std::vector<std::array<int, D + 1>> elements(mesh.num_elements());
  for (int e = 0; e < mesh.num_elements(); ++e)
    for (int k = 0; k <= D; ++k) elements[e][k] = mesh.vertex(e, k);
  std::vector<Eigen::Matrix<double, D, 1>> x;
  for (int i = 0; i < mesh.num_nodes(); ++i) x.push_back(mesh.node(i));
  auto node_classes = mesh.node_classes();
  auto entities = mesh.element_entities();
  auto facets = mesh.boundary_facets();

  auto has = [](const std::array<int, D + 1>& el, int v) { return std::find(el.begin(), el.end(), v) != el.end(); };
  auto split = [&](int a, int b) {
    const int m = int(x.size());
    x.push_back(0.5 * (x[a] + x[b]));
    const std::size_t before = elements.size();
    for (std::size_t e = 0; e < before; ++e) {
      if (!has(elements[e], a) || !has(elements[e], b)) continue;
      // The half with b replaced by m stays at e; the other is appended.
      auto other = elements[e];
      std::replace(other.begin(), other.end(), a, m);
      std::replace(elements[e].begin(), elements[e].end(), b, m);
      elements.push_back(other);
      entities.push_back(entities[e]);
      // A facet owned by e contains a or b, not both (ab is on none).
      for (auto& f : facets)
        if (f.element == int(e) && std::find(f.vertices.begin(), f.vertices.end(), b) != f.vertices.end())
          f.element = int(elements.size()) - 1;
      if (node_classes.size() == std::size_t(m))
        node_classes.push_back(NodeClass{NodeKind::free, EntityId{D, entities[e]}, 0, {}});
    }
    ++out.edges_split;
  };
  auto split_at_centroid = [&](int e) {
    const int g = int(x.size());
    x.push_back(Eigen::Matrix<double, D, 1>::Zero());
    for (int v : elements[e]) x.back() += x[v] / double(D + 1);
    node_classes.push_back(NodeClass{NodeKind::free, EntityId{D, entities[e]}, 0, {}});
    // Child k has vertex k replaced by g; child 0 stays at e, and the facet
    // at local facet f belongs to a child that keeps all its vertices.
    const auto parent = elements[e];
    for (int k = 1; k <= D; ++k) {
      elements.push_back(parent);
      elements.back()[k] = g;
      entities.push_back(entities[e]);
    }
    elements[e][0] = g;
    for (auto& f : facets) {
      if (f.element != e) continue;
      int missing = 0;  // the parent's vertex the facet lacks
      while (std::find(f.vertices.begin(), f.vertices.end(), parent[missing]) != f.vertices.end()) ++missing;
      if (missing != 0) f.element = int(elements.size()) - D + (missing - 1);
    }
    ++out.centroid_splits;
  };
  // Face (a, b, c) of a tetrahedron, interior, split at its centre g with
  // both tetrahedra on it, each into three: child k has vertex k of the face
  // replaced by g (at its place, which keeps the orientation), and a
  // facet owned by the parent goes to the child that keeps all its vertices.
  auto split_face = [&](int a, int b, int c) {
    const int g = int(x.size());
    x.push_back((x[a] + x[b] + x[c]) / 3.0);
    const std::size_t before = elements.size();
    for (std::size_t e = 0; e < before; ++e) {
      if (!has(elements[e], a) || !has(elements[e], b) || !has(elements[e], c)) continue;
      if (node_classes.size() == std::size_t(g))
        node_classes.push_back(NodeClass{NodeKind::free, EntityId{D, entities[e]}, 0, {}});
      const auto parent = elements[e];
      for (int v : {b, c}) {
        elements.push_back(parent);
        std::replace(elements.back().begin(), elements.back().end(), v, g);
        entities.push_back(entities[e]);
        for (auto& f : facets)
          if (f.element == int(e) && !std::count(f.vertices.begin(), f.vertices.end(), v))
            f.element = int(elements.size()) - 1;
      }
      std::replace(elements[e].begin(), elements[e].end(), a, g);
    }
    ++out.faces_split;
  };
  // Every corner that is still flat when its turn comes (a split around
  // another corner may have removed it): the new elements have none.
  for (const auto& c : corners) {
    const auto el = elements[c.element];
    bool untouched = true;
    for (int k = 0; k <= D; ++k) untouched = untouched && el[k] == mesh.vertex(c.element, k);
    if (!untouched) continue;
    if (c.split_from >= 0) {
      if constexpr (D == 3)
        if (on_boundary.count(detail::mesh_edge(el[c.split_from], el[c.split_to]))) {
          split_face(el[c.vertex], el[c.split_from], el[c.split_to]);
          continue;
        }
      split(el[c.split_from], el[c.split_to]);
      continue;
    }
    std::optional<detail::MeshEdge> longest;
    double length = -1.0;
    for (int i = 0; i <= D; ++i)
      for (int j = i + 1; j <= D; ++j) {
        if (i == c.vertex || j == c.vertex) continue;
        const auto edge = detail::mesh_edge(el[i], el[j]);
        if (on_boundary.count(edge)) continue;
        const double l = (x[el[i]] - x[el[j]]).norm();
        if (l > length) {
          length = l;
          longest = edge;
        }
      }
    if (longest)
      split(longest->first, longest->second);
    else
      split_at_centroid(c.element);
  }

  typename MeshT::Coordinates nodes(D, x.size());
  for (std::size_t i = 0; i < x.size(); ++i) nodes.col(i) = x[i];
  typename MeshT::Connectivity connectivity(D + 1, elements.size());
  for (std::size_t e = 0; e < elements.size(); ++e)
    for (int k = 0; k <= D; ++k) connectivity(k, e) = elements[e][k];
  MeshT split_mesh(1, std::move(nodes), std::move(connectivity));
  split_mesh.node_classes() = std::move(node_classes);
  split_mesh.element_entities() = std::move(entities);
  split_mesh.entities() = mesh.entities();
  split_mesh.physical_groups() = mesh.physical_groups();
  split_mesh.boundary_facets() = std::move(facets);
  mesh = std::move(split_mesh);
  return out;
}

}  // namespace detail

/// Splits edges until no element has a flat corner (see above). The mesh
/// must be linear; new nodes are free (interior), classified on the split
/// elements' entity; the ideal becomes the new straight-sided mesh. A split
/// leaves no flat corner of the first kind (every corner of a new element
/// has an edge to the new, interior node), but a straight corner's split can
/// leave another straight corner at the same vertex (its element's third
/// edge on the boundary too), so passes repeat while they find corners (at
/// most max_passes).
template <int D, NodeSet Nodes>
FlatCornerSplit split_flat_corners(Mesh<Simplex<D>, Nodes, D>& mesh, const EntityNormal<D>& normal = {}) {
  constexpr int max_passes = 4;
  FlatCornerSplit total;
  for (int pass = 0; pass < max_passes; ++pass) {
    const auto s = detail::split_flat_corners_once(mesh, normal);
    total.corners += s.corners;
    total.edges_split += s.edges_split;
    total.faces_split += s.faces_split;
    total.centroid_splits += s.centroid_splits;
    if (s.corners == 0) break;
  }
  return total;
}

}  // namespace hom
