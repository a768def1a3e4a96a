#pragma once
/// @file elevate.hpp
/// p-elevation (and node-set conversion) of a mesh.
///
/// The element map is one polynomial; its nodal values at another node set or
/// degree are obtained by evaluating it there (DESIGN.md, "numerical
/// contracts"): X_out = X_in * N_in(xi_out)^T, with xi_out the reference nodes
/// of the target (degree p, node set OutNodes). For p >= q this reproduces the
/// map exactly (up to round-off); for p < q it interpolates.
///
/// Shared nodes are created once: a new node is identified mesh-wide by its
/// site key (mesh/detail/site_key.hpp) and placed from the first element that
/// creates it; in a conforming input both neighbours give the same position
/// because the trace of the map on a shared edge or face depends only on the
/// nodes of that edge or face.
///
/// Numbering: the input's vertex nodes come first (in ascending input id, so a
/// linear input keeps its numbering), then the new nodes in order of first
/// appearance, element by element in layout order.
///
/// Classification of a new node, from the sub-entity (edge, face, interior)
/// it lies on:
///   1. if the input has a node on the same sub-entity, its classification
///      (without parametric coordinates, which belonged to another position);
///   2. else if the sub-entity lies on classified facets of one entity, that
///      (dim - 1)-entity; on facets of several entities (a 3D edge between two
///      surfaces), the curve its two vertices share (from their
///      classification or the model's entity boundaries), else fixed;
///   3. else if it lies on the topological boundary: fixed (geometry unknown);
///   4. else interior: free (volume or planar meshes) or on the element's
///      surface entity (surface meshes).
/// Nodes on a curve or surface get kind on_entity without parameters.

#include <algorithm>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

#include "hom/basis/lagrange.hpp"
#include "hom/mesh/detail/edge_curve.hpp"
#include "hom/mesh/detail/site_key.hpp"
#include "hom/mesh/mesh.hpp"
#include "hom/mesh/topology.hpp"

namespace hom {

namespace detail {

// Bit mask of the local vertices with non-zero weight at a site.
inline unsigned site_support(const std::vector<std::pair<int, int>>& w) {
  unsigned m = 0;
  for (const auto& [v, wt] : w) m |= 1u << v;
  return m;
}

template <class MeshT>
class SubEntityClassifier {
 public:
  using Family = typename MeshT::family;
  static constexpr int dim = Family::dim;

  explicit SubEntityClassifier(const MeshT& mesh) : mesh_(mesh) {
    for (const auto& f : mesh.boundary_facets()) {
      std::vector<int> v(f.vertices.begin(), f.vertices.end());
      add(classified_, v, f.entity_tag);
      if constexpr (dim == 3)
        for (std::size_t k = 0; k < v.size(); ++k) add(classified_, {v[k], v[(k + 1) % v.size()]}, f.entity_tag);
    }
    const Topology<Family> topo(mesh);
    for (const auto& r : topo.boundary_facets()) {
      const auto lv = facet_vertices<Family>(r.local);
      std::vector<int> v;
      for (int l : lv) v.push_back(mesh.vertex(r.element, l));
      add(topological_, v, 0);
      if constexpr (dim == 3)
        for (std::size_t k = 0; k < v.size(); ++k) add(topological_, {v[k], v[(k + 1) % v.size()]}, 0);
    }
  }

  /// Classification of the open sub-entity with these global vertices, seen
  /// from element e.
  NodeClass classify(std::vector<int> verts, int e) const {
    std::sort(verts.begin(), verts.end());
    NodeClass c;
    if (int(verts.size()) == Family::num_vertices) return interior(e);
    if (auto it = classified_.find(verts); it != classified_.end()) {
      if (it->second.size() == 1) {
        c.kind = NodeKind::on_entity;
        c.entity = EntityId{dim - 1, *it->second.begin()};
        return c;
      }
      if (verts.size() == 2) {
        if (auto curve = common_curve(verts[0], verts[1])) {
          c.kind = NodeKind::on_entity;
          c.entity = *curve;
          return c;
        }
      }
      c.kind = NodeKind::fixed;
      return c;
    }
    if (topological_.count(verts)) {
      c.kind = NodeKind::fixed;
      return c;
    }
    return interior(e);
  }

 private:
  using Map = std::map<std::vector<int>, std::set<int>>;
  static void add(Map& m, std::vector<int> v, int tag) {
    std::sort(v.begin(), v.end());
    m[v].insert(tag);
  }

  NodeClass interior(int e) const {
    NodeClass c;
    if constexpr (MeshT::space_dim != dim) {
      c.kind = NodeKind::on_entity;
      c.entity = EntityId{dim, mesh_.element_entities()[e]};
    } else {
      c.kind = NodeKind::free;
      c.entity = EntityId{dim, mesh_.element_entities()[e]};
    }
    return c;
  }

  // The curve (dimension-1 entity) an edge between vertices a and b lies on.
  std::optional<EntityId> common_curve(int a, int b) const { return detail::common_curve(mesh_, a, b); }

  const MeshT& mesh_;
  Map classified_;
  Map topological_;
};

}  // namespace detail

/// The mesh with degree p on node set OutNodes, by evaluating each element's
/// map at the new reference nodes. p may be lower than the input's degree
/// (then the map is interpolated, not reproduced).
template <NodeSet OutNodes, ElementFamily Family, NodeSet InNodes, int SpaceDim>
Mesh<Family, OutNodes, SpaceDim> change_degree(const Mesh<Family, InNodes, SpaceDim>& in, int p) {
  using Out = Mesh<Family, OutNodes, SpaceDim>;
  constexpr int nv = Family::num_vertices;
  if (p < 1) throw std::invalid_argument("hom::change_degree: degree must be >= 1, got " + std::to_string(p));
  const int q = in.degree();
  const int n_out = Family::num_nodes(p);
  const Eigen::MatrixXd B =
      lagrange_basis<Family, InNodes>(q).values(OutNodes::template points<Family>(p)).transpose();  // n_in x n_out
  const auto sites = detail::local_site_weights<Family>(p);
  const auto in_sites = detail::local_site_weights<Family>(q);
  // Input local node with a given support (sub-entity), for classification rule 1.
  std::map<unsigned, int> in_node_of_support;
  for (int i = nv; i < int(in_sites.size()); ++i) in_node_of_support.try_emplace(detail::site_support(in_sites[i]), i);

  // Vertices keep their relative order and come first.
  std::vector<int> vmap(in.num_nodes(), -1);
  {
    const auto is_vertex = in.vertex_mask();
    int next = 0;
    for (int i = 0; i < in.num_nodes(); ++i)
      if (is_vertex[i]) vmap[i] = next++;
  }
  int num_new = 0;
  for (int v : vmap) num_new += v >= 0;

  typename Out::Connectivity conn(n_out, in.num_elements());
  std::vector<Eigen::Matrix<double, SpaceDim, 1>> positions;
  std::vector<NodeClass> classes;
  std::vector<Eigen::Matrix<double, SpaceDim, 1>> ideal;
  positions.resize(num_new);
  classes.resize(num_new);
  ideal.resize(num_new);
  for (int i = 0; i < in.num_nodes(); ++i)
    if (vmap[i] >= 0) {
      positions[vmap[i]] = in.node(i);
      classes[vmap[i]] = in.node_class(i);
      ideal[vmap[i]] = in.ideal_coordinates().col(i);
    }

  const detail::SubEntityClassifier<Mesh<Family, InNodes, SpaceDim>> classifier(in);
  std::unordered_map<detail::SiteKey, int, detail::SiteKeyHash> index;
  std::array<int, nv> old_vertices{};
  for (int e = 0; e < in.num_elements(); ++e) {
    for (int v = 0; v < nv; ++v) {
      old_vertices[v] = in.vertex(e, v);
      conn(v, e) = vmap[old_vertices[v]];
    }
    typename Out::Coordinates x;  // evaluated lazily: only if the element creates a node
    for (int i = nv; i < n_out; ++i) {
      auto [it, inserted] = index.try_emplace(detail::site_key(sites[i], old_vertices), int(positions.size()));
      conn(i, e) = it->second;
      if (!inserted) continue;
      if (x.cols() == 0) x = in.element_coordinates(e) * B;
      positions.push_back(x.col(i));
      ideal.push_back(x.col(i));
      const unsigned support = detail::site_support(sites[i]);
      if (auto s = in_node_of_support.find(support); s != in_node_of_support.end()) {
        NodeClass c = in.node_class(in.element(e)[s->second]);
        c.num_params = 0;
        c.params = {};
        classes.push_back(c);
      } else {
        std::vector<int> verts;
        for (const auto& [v, w] : sites[i]) verts.push_back(old_vertices[v]);
        classes.push_back(classifier.classify(verts, e));
      }
    }
  }

  typename Out::Coordinates X(SpaceDim, positions.size()), I(SpaceDim, positions.size());
  for (std::size_t i = 0; i < positions.size(); ++i) {
    X.col(i) = positions[i];
    I.col(i) = ideal[i];
  }
  Out out(p, std::move(X), std::move(conn));
  out.node_classes() = std::move(classes);
  out.element_entities() = in.element_entities();
  out.entities() = in.entities();
  out.physical_groups() = in.physical_groups();
  for (auto f : in.boundary_facets()) {
    for (auto& v : f.vertices) v = vmap[v];
    out.boundary_facets().push_back(f);
  }
  out.set_ideal_coordinates(std::move(I));
  return out;
}

/// p-elevation on the same node set: the mesh of degree p >= in.degree() with
/// the same geometric map.
template <ElementFamily Family, NodeSet Nodes, int SpaceDim>
Mesh<Family, Nodes, SpaceDim> elevate(const Mesh<Family, Nodes, SpaceDim>& in, int p) {
  if (p < in.degree())
    throw std::invalid_argument("hom::elevate: target degree " + std::to_string(p) + " is below the mesh's degree " +
                                std::to_string(in.degree()) + " (use change_degree to interpolate)");
  return change_degree<Nodes>(in, p);
}

}  // namespace hom
