#pragma once
/// @file topology.hpp
/// Mesh topology: unique vertices, edges and faces with the orientation each
/// element sees them in, facet-to-element incidence, boundary facets and
/// node-to-element adjacency.
///
/// Entities are identified by their vertex nodes (vertices come first in
/// every element, element/node_layout.hpp), so topology does not depend on the
/// degree. Canonical forms:
///   - edge: (a, b) with a < b; an element's local edge k = Family::edges()[k]
///     has sign +1 if it runs a -> b, -1 otherwise;
///   - face: the vertex cycle rotated so its smallest vertex comes first, and
///     reflected if needed so that the second entry is smaller than the last;
///     an element's local face k (Family::faces()[k], outward) is that cycle
///     rotated by `rotation` places and, if `reflected`, traversed backwards.
/// Facets are edges in 2D and faces in 3D; local facet k of an element is its
/// local edge k (2D) or local face k (3D), see facet.hpp.

#include <algorithm>
#include <array>
#include <map>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "hom/element/family.hpp"
#include "hom/mesh/facet.hpp"

namespace hom {

/// Local facet `local` of element `element`.
struct FacetRef {
  int element = 0;
  int local = 0;
  friend bool operator==(const FacetRef&, const FacetRef&) = default;
};

/// How an element sees a canonical face (see the file comment).
struct FaceOrientation {
  int rotation = 0;
  bool reflected = false;
  friend bool operator==(const FaceOrientation&, const FaceOrientation&) = default;
};

template <ElementFamily Family>
class Topology {
 public:
  static constexpr int dim = Family::dim;
  static constexpr int num_local_edges = static_cast<int>(Family::edges().size());
  static constexpr int num_local_facets = num_facets<Family>;
  using Face = FacetVertices<Family>;

  /// MeshT: anything with num_nodes(), num_elements() and vertex(e, v), e.g. Mesh.
  template <class MeshT>
  explicit Topology(const MeshT& mesh) : num_elements_(mesh.num_elements()) {
    build_vertices(mesh);
    build_edges(mesh);
    if constexpr (dim == 3) build_faces(mesh);
    build_facets();
    build_node_elements(mesh);
  }

  int num_elements() const { return num_elements_; }

  /// Global node ids of the distinct element vertices, ascending.
  const std::vector<int>& vertices() const { return vertices_; }
  int num_vertices() const { return static_cast<int>(vertices_.size()); }

  const std::vector<std::array<int, 2>>& edges() const { return edges_; }
  int num_edges() const { return static_cast<int>(edges_.size()); }
  int element_edge(int e, int k) const { return element_edges_[e * num_local_edges + k]; }
  int element_edge_sign(int e, int k) const { return element_edge_signs_[e * num_local_edges + k]; }

  /// 3D only: canonical faces.
  const std::vector<Face>& faces() const { return faces_; }
  int num_faces() const { return static_cast<int>(faces_.size()); }
  int element_face(int e, int k) const { return element_faces_[e * num_local_facets + k]; }
  FaceOrientation element_face_orientation(int e, int k) const { return element_face_orient_[e * num_local_facets + k]; }

  /// Facets: edges in 2D, faces in 3D.
  int num_facets_total() const { return dim == 2 ? num_edges() : num_faces(); }
  int element_facet(int e, int k) const { return dim == 2 ? element_edge(e, k) : element_face(e, k); }
  /// The one or two element sides that share facet i.
  std::span<const FacetRef> facet_elements(int i) const {
    return {facet_refs_.data() + 2 * i, static_cast<std::size_t>(facet_count_[i])};
  }
  /// Facets with exactly one element: the mesh boundary.
  const std::vector<FacetRef>& boundary_facets() const { return boundary_; }
  /// The element across local facet k of element e, if any.
  std::optional<int> neighbor(int e, int k) const {
    for (const auto& r : facet_elements(element_facet(e, k)))
      if (r.element != e) return r.element;
    return std::nullopt;
  }

  /// Elements that contain node n (any node, not only vertices).
  std::span<const int> node_elements(int n) const {
    return {node_elements_.data() + node_offsets_[n], static_cast<std::size_t>(node_offsets_[n + 1] - node_offsets_[n])};
  }

  /// V - E + F (2D) or V - E + F - C (3D) of the element complex.
  long euler_characteristic() const {
    if constexpr (dim == 2)
      return long(num_vertices()) - num_edges() + num_elements_;
    else
      return long(num_vertices()) - num_edges() + num_faces() - num_elements_;
  }

 private:
  template <class MeshT>
  void build_vertices(const MeshT& mesh) {
    std::vector<char> is_vertex(mesh.num_nodes(), 0);
    for (int e = 0; e < mesh.num_elements(); ++e)
      for (int v = 0; v < Family::num_vertices; ++v) is_vertex[mesh.vertex(e, v)] = 1;
    for (int n = 0; n < mesh.num_nodes(); ++n)
      if (is_vertex[n]) vertices_.push_back(n);
  }

  template <class MeshT>
  void build_edges(const MeshT& mesh) {
    std::map<std::array<int, 2>, int> index;
    element_edges_.resize(std::size_t(num_elements_) * num_local_edges);
    element_edge_signs_.resize(element_edges_.size());
    const auto local = Family::edges();
    for (int e = 0; e < num_elements_; ++e)
      for (int k = 0; k < num_local_edges; ++k) {
        const int a = mesh.vertex(e, local[k][0]), b = mesh.vertex(e, local[k][1]);
        const std::array<int, 2> key{std::min(a, b), std::max(a, b)};
        auto [it, inserted] = index.try_emplace(key, num_edges());
        if (inserted) edges_.push_back(key);
        element_edges_[e * num_local_edges + k] = it->second;
        element_edge_signs_[e * num_local_edges + k] = a < b ? 1 : -1;
      }
  }

  template <class MeshT>
  void build_faces(const MeshT& mesh) {
    constexpr int nf = facet_num_vertices<Family>;
    std::map<Face, int> index;
    element_faces_.resize(std::size_t(num_elements_) * num_local_facets);
    element_face_orient_.resize(element_faces_.size());
    for (int e = 0; e < num_elements_; ++e)
      for (int k = 0; k < num_local_facets; ++k) {
        const auto lv = facet_vertices<Family>(k);
        Face g{};
        for (int i = 0; i < nf; ++i) g[i] = mesh.vertex(e, lv[i]);
        const int r = int(std::min_element(g.begin(), g.end()) - g.begin());
        Face c{};
        for (int i = 0; i < nf; ++i) c[i] = g[(r + i) % nf];
        const bool reflected = c[1] > c[nf - 1];
        if (reflected) std::reverse(c.begin() + 1, c.end());
        auto [it, inserted] = index.try_emplace(c, num_faces());
        if (inserted) faces_.push_back(c);
        element_faces_[e * num_local_facets + k] = it->second;
        element_face_orient_[e * num_local_facets + k] = {r, reflected};
      }
  }

  void build_facets() {
    const int n = num_facets_total();
    facet_refs_.assign(2 * std::size_t(n), FacetRef{});
    facet_count_.assign(n, 0);
    for (int e = 0; e < num_elements_; ++e)
      for (int k = 0; k < num_local_facets; ++k) {
        const int f = element_facet(e, k);
        if (facet_count_[f] == 2)
          throw std::invalid_argument("hom::Topology: facet shared by more than two elements (element " +
                                      std::to_string(e) + ", local facet " + std::to_string(k) + ")");
        facet_refs_[2 * f + facet_count_[f]++] = {e, k};
      }
    for (int f = 0; f < n; ++f)
      if (facet_count_[f] == 1) boundary_.push_back(facet_refs_[2 * f]);
  }

  template <class MeshT>
  void build_node_elements(const MeshT& mesh) {
    const int nn = mesh.num_nodes();
    node_offsets_.assign(nn + 1, 0);
    const auto& conn = mesh.elements();
    for (Eigen::Index e = 0; e < conn.cols(); ++e)
      for (Eigen::Index i = 0; i < conn.rows(); ++i) ++node_offsets_[conn(i, e) + 1];
    for (int n = 0; n < nn; ++n) node_offsets_[n + 1] += node_offsets_[n];
    node_elements_.resize(node_offsets_[nn]);
    std::vector<int> fill(node_offsets_.begin(), node_offsets_.end() - 1);
    for (Eigen::Index e = 0; e < conn.cols(); ++e)
      for (Eigen::Index i = 0; i < conn.rows(); ++i) node_elements_[fill[conn(i, e)]++] = static_cast<int>(e);
  }

  int num_elements_ = 0;
  std::vector<int> vertices_;
  std::vector<std::array<int, 2>> edges_;
  std::vector<int> element_edges_;
  std::vector<int> element_edge_signs_;
  std::vector<Face> faces_;
  std::vector<int> element_faces_;
  std::vector<FaceOrientation> element_face_orient_;
  std::vector<FacetRef> facet_refs_;
  std::vector<int> facet_count_;
  std::vector<FacetRef> boundary_;
  std::vector<int> node_offsets_;
  std::vector<int> node_elements_;
};

/// Topology of a mesh (deduces the family).
template <class MeshT>
Topology<typename MeshT::family> make_topology(const MeshT& mesh) {
  return Topology<typename MeshT::family>(mesh);
}

}  // namespace hom
