#pragma once
/// @file node_layout.hpp
/// hom's local node numbering of a degree-p element, for every family.
///
/// Order: the vertices (in the family's vertex order), then the interior nodes
/// of each edge (edges in `Family::edges()` order, each edge's nodes running
/// from its first vertex to its second), then (3D) the interior nodes of each
/// face (faces in `Family::faces()` order, each face's nodes sorted by their
/// face-local lattice index (s, t), t major), then the element's interior
/// nodes (sorted by lattice index, last axis major).
///
/// Face-local lattice index of a node on face (f0, f1, f2[, f3]):
///   - simplex face: (s, t) = (w_{f1}, w_{f2}), its integer barycentric weights
///     on the face's second and third vertices;
///   - cube face: s = distance from f0 along f0 -> f1, t along f0 -> f3.
/// So a face's interior node order depends only on the face's own vertex order,
/// and two elements sharing a face agree on its nodes once they agree on the
/// vertex order (meshes identify shared nodes by `Family::vertex_weights`).
///
/// The layout is independent of the node distribution: a node set maps each
/// lattice index to reference coordinates.

#include <algorithm>
#include <array>
#include <cassert>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "hom/element/family.hpp"

namespace hom {

/// Which sub-entity of the reference element a node belongs to.
struct NodeEntity {
  int dim;    ///< 0 vertex, 1 edge, 2 face, Dim interior
  int index;  ///< vertex, edge or face number (0 for the interior)
  friend bool operator==(const NodeEntity&, const NodeEntity&) = default;
};

template <ElementFamily Family>
class NodeLayout {
 public:
  static constexpr int dim = Family::dim;

  explicit NodeLayout(int p) : degree_(p) {
    if (p < 1) throw std::invalid_argument("hom::NodeLayout: degree must be >= 1, got " + std::to_string(p));
    build();
  }

  int degree() const { return degree_; }
  int size() const { return static_cast<int>(lattice_.size()); }

  const Lattice<dim>& lattice(int node) const { return lattice_[node]; }
  const std::vector<Lattice<dim>>& lattice() const { return lattice_; }
  NodeEntity entity(int node) const { return entity_[node]; }

  /// Interior nodes of edge e, from its first vertex to its second.
  const std::vector<int>& edge_nodes(int e) const { return edge_nodes_[e]; }
  /// Interior nodes of face f in face-local lattice order (3D only).
  const std::vector<int>& face_nodes(int f) const { return face_nodes_[f]; }
  /// Interior nodes of the element.
  const std::vector<int>& interior_nodes() const { return interior_nodes_; }

  /// All nodes of edge e (both vertices included), from first vertex to second.
  std::vector<int> closed_edge_nodes(int e) const {
    const auto ed = Family::edges()[e];
    std::vector<int> n{ed[0]};
    n.insert(n.end(), edge_nodes_[e].begin(), edge_nodes_[e].end());
    n.push_back(ed[1]);
    return n;
  }

  /// Local node number of lattice index l, or -1 if l is not a node.
  int index_of(const Lattice<dim>& l) const {
    auto it = index_.find(l);
    return it == index_.end() ? -1 : it->second;
  }

  /// Equispaced reference coordinates of every node, in layout order.
  std::vector<typename Family::Point> equispaced_points() const {
    std::vector<typename Family::Point> x;
    x.reserve(lattice_.size());
    for (const auto& l : lattice_) x.push_back(Family::equispaced_point(l, degree_));
    return x;
  }

  /// Face-local lattice index (s, t) of lattice node l on face f (3D only).
  static std::array<int, 2> face_local(const Lattice<dim>& l, int f, int p) {
    const auto fv = Family::faces()[f];
    if constexpr (Family::is_simplex) {
      const auto w = Family::vertex_weights(l, p);
      return {w[fv[1]], w[fv[2]]};
    } else {
      return {axis_distance(l, fv[0], fv[1], p), axis_distance(l, fv[0], fv[3], p)};
    }
  }

  /// Position (0..p) of lattice node l along edge e, from its first vertex.
  static int edge_local(const Lattice<dim>& l, int e, int p) {
    const auto ed = Family::edges()[e];
    if constexpr (Family::is_simplex)
      return Family::vertex_weights(l, p)[ed[1]];
    else
      return axis_distance(l, ed[0], ed[1], p);
  }

 private:
  // Distance of l from vertex a measured along the axis-aligned direction a -> b.
  static int axis_distance(const Lattice<dim>& l, int a, int b, int p) {
    const auto la = Family::vertex_lattice(a, p), lb = Family::vertex_lattice(b, p);
    int d = 0;
    for (int k = 0; k < dim; ++k) d += (l[k] - la[k]) * (lb[k] - la[k]);
    return d / p;
  }

  static std::vector<Lattice<dim>> all_lattice_points(int p) {
    std::vector<Lattice<dim>> pts;
    Lattice<dim> l{};
    // Enumerate the box [0, p]^dim with the last axis major and keep members.
    const int total = [&] {
      int n = 1;
      for (int k = 0; k < dim; ++k) n *= p + 1;
      return n;
    }();
    for (int id = 0; id < total; ++id) {
      int r = id;
      for (int k = 0; k < dim; ++k) {
        l[k] = r % (p + 1);
        r /= p + 1;
      }
      if (Family::in_lattice(l, p)) pts.push_back(l);
    }
    return pts;
  }

  NodeEntity classify(const Lattice<dim>& l) const {
    const int p = degree_;
    const auto w = Family::vertex_weights(l, p);
    int nonzero = 0;
    for (int wi : w) nonzero += wi != 0;
    if (nonzero == 1) {
      for (int v = 0; v < Family::num_vertices; ++v)
        if (w[v] != 0) return {0, v};
    }
    // A node lies on the closure of a sub-entity iff every vertex with non-zero
    // weight belongs to that sub-entity; the owner is the lowest-dimensional one.
    auto on = [&](const auto& verts) {
      int hit = 0;
      for (int v : verts) hit += w[v] != 0;
      return hit == nonzero;
    };
    const auto edges = Family::edges();
    for (int e = 0; e < int(edges.size()); ++e)
      if (on(edges[e])) return {1, e};
    if constexpr (dim == 3) {
      const auto faces = Family::faces();
      for (int f = 0; f < int(faces.size()); ++f)
        if (on(faces[f])) return {2, f};
    }
    return {dim, 0};
  }

  void build() {
    const int p = degree_;
    const auto pts = all_lattice_points(p);
    const auto edges = Family::edges();
    edge_nodes_.assign(edges.size(), {});
    std::vector<std::vector<std::pair<std::array<int, 2>, Lattice<dim>>>> face_members;
    if constexpr (dim == 3) face_members.assign(Family::faces().size(), {});

    for (int v = 0; v < Family::num_vertices; ++v) push(Family::vertex_lattice(v, p), {0, v});

    std::vector<std::vector<std::pair<int, Lattice<dim>>>> edge_members(edges.size());
    std::vector<Lattice<dim>> interior;
    for (const auto& l : pts) {
      const NodeEntity ent = classify(l);
      if (ent.dim == 1) edge_members[ent.index].push_back({edge_local(l, ent.index, p), l});
      if constexpr (dim == 3)
        if (ent.dim == 2) {
          const auto st = face_local(l, ent.index, p);
          face_members[ent.index].push_back({{st[1], st[0]}, l});  // t major
        }
      if (ent.dim == dim) interior.push_back(l);
    }
    for (int e = 0; e < int(edges.size()); ++e) {
      auto& m = edge_members[e];
      std::sort(m.begin(), m.end());
      for (const auto& [s, l] : m) edge_nodes_[e].push_back(push(l, {1, e}));
    }
    if constexpr (dim == 3) {
      face_nodes_.assign(face_members.size(), {});
      for (int f = 0; f < int(face_members.size()); ++f) {
        auto& m = face_members[f];
        std::sort(m.begin(), m.end());
        for (const auto& [ts, l] : m) face_nodes_[f].push_back(push(l, {2, f}));
      }
    }
    for (const auto& l : interior) interior_nodes_.push_back(push(l, {dim, 0}));
    assert(size() == Family::num_nodes(p));
  }

  int push(const Lattice<dim>& l, NodeEntity e) {
    const int id = size();
    lattice_.push_back(l);
    entity_.push_back(e);
    index_[l] = id;
    return id;
  }

  int degree_;
  std::vector<Lattice<dim>> lattice_;
  std::vector<NodeEntity> entity_;
  std::vector<std::vector<int>> edge_nodes_;
  std::vector<std::vector<int>> face_nodes_;
  std::vector<int> interior_nodes_;
  std::map<Lattice<dim>, int> index_;
};

/// The layout of degree p, built once and shared (thread-safe).
template <ElementFamily Family>
const NodeLayout<Family>& node_layout(int p) {
  static std::mutex mutex;
  static std::map<int, std::unique_ptr<NodeLayout<Family>>> cache;
  std::lock_guard lock(mutex);
  auto& slot = cache[p];
  if (!slot) slot = std::make_unique<NodeLayout<Family>>(p);
  return *slot;
}

}  // namespace hom
