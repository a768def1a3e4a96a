#pragma once
/// @file mesh.hpp
/// A conforming high-order mesh of one element family.
///
/// `Mesh<Family, Nodes, SpaceDim>` stores
///   - the degree p (run-time) and the node coordinates, one column per node
///     (`SpaceDim x num_nodes`); SpaceDim = 3 with a 2D family is a surface mesh;
///   - the connectivity, one column per element (`n_p x num_elements`), in
///     hom's local node layout (element/node_layout.hpp): vertices first, so
///     `elements()(v, e)` for v < num_vertices are the element's vertices;
///   - the node set `Nodes` the coordinates are nodal values at: the element map
///     is phi(xi) = sum_j x_j N_j(xi) (eq A.1) with N_j the Lagrange basis on
///     `Nodes` (a file's equispaced nodes are converted by evaluating the map,
///     never copied: DESIGN.md);
///   - per node a classification (free, fixed, on a geometric entity with
///     parametric coordinates), per element its geometric entity tag, the
///     model's entities and physical groups, and the facets classified on
///     lower-dimensional entities (boundary curves and surfaces);
///   - the ideal (straight-sided) mesh of section 3.1.2: a snapshot of the
///     vertex positions, taken at construction (and by `reset_ideal`), so that
///     moving nodes during optimization does not move the ideal. An element's
///     ideal is its snapshot vertices mapped by the affine (simplex) or
///     multilinear (cube) map, its nodes at `Nodes`' reference points.
///
/// Invariants (checked by the constructor): p >= 1, `elements()` has n_p rows
/// and every entry is a node index; the per-node and per-element vectors have
/// one entry per node / element. Conformity (shared nodes agree) is the
/// builder's business: readers and `elevate` check or guarantee it.

#include <array>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "hom/basis/lagrange.hpp"
#include "hom/element/family.hpp"
#include "hom/element/node_layout.hpp"
#include "hom/mesh/facet.hpp"
#include "hom/nodes/node_set.hpp"
#include "hom/nodes/warp_blend.hpp"
#include "hom/quality/ideal.hpp"

namespace hom {

/// How a node may move.
enum class NodeKind {
  free,       ///< interior of the domain: moves freely
  fixed,      ///< must not move (geometric vertex, or boundary with unknown geometry)
  on_entity,  ///< lies on a curve or surface entity and may slide on it
};

/// A geometric entity of the model: dimension (0 point, 1 curve, 2 surface,
/// 3 volume) and tag, as in Gmsh.
struct EntityId {
  int dim = 0;
  int tag = 0;
  friend auto operator<=>(const EntityId&, const EntityId&) = default;
};

/// Classification of one node.
///
/// `entity` is the lowest-dimensional entity the node lies on, when known.
/// `params` holds `num_params` parametric coordinates on that entity (u on a
/// curve, (u, v) on a surface) when they are known; they are valid for the
/// node's current position. An on_entity node without parameters lies on its
/// entity but its parameters have to be recomputed (by projection) before the
/// node may slide.
struct NodeClass {
  NodeKind kind = NodeKind::free;
  std::optional<EntityId> entity;
  int num_params = 0;
  std::array<double, 2> params{};

  friend bool operator==(const NodeClass&, const NodeClass&) = default;
};

/// A model entity with its physical groups and bounding entities.
struct Entity {
  EntityId id;
  std::vector<int> physical_tags;
  /// Tags of the bounding entities of dimension id.dim - 1, signed by
  /// orientation (as Gmsh's $Entities lists them).
  std::vector<int> boundary;
};

struct PhysicalGroup {
  int dim = 0;
  int tag = 0;
  std::string name;
  friend bool operator==(const PhysicalGroup&, const PhysicalGroup&) = default;
};

/// A facet (edge in 2D, face in 3D) classified on an entity of dimension
/// Family::dim - 1: a boundary curve or surface, or an embedded interface.
template <ElementFamily Family>
struct BoundaryFacet {
  int element = 0;      ///< element that owns the facet
  int local_facet = 0;  ///< local facet number (see facet.hpp)
  int entity_tag = 0;   ///< tag of the (Family::dim - 1)-dimensional entity
  /// Global node ids of the facet's vertices in the orientation of the
  /// lower-dimensional element it came from (outward by default).
  FacetVertices<Family> vertices{};
  friend bool operator==(const BoundaryFacet&, const BoundaryFacet&) = default;
};

namespace detail {

/// Values of the vertex (linear / multilinear) shape functions at xi: the map
/// of a straight-sided element is sum_v L_v(xi) X_v.
template <ElementFamily Family>
std::array<double, Family::num_vertices> vertex_shape_values(const typename Family::Point& xi) {
  std::array<double, Family::num_vertices> l{};
  if constexpr (Family::is_simplex) {
    l[0] = 1.0 - xi.sum();
    for (int k = 0; k < Family::dim; ++k) l[k + 1] = xi[k];
  } else {
    for (int v = 0; v < Family::num_vertices; ++v) {
      const auto c = Family::vertex_corner(v);
      double s = 1.0;
      for (int a = 0; a < Family::dim; ++a) s *= c[a] ? (1.0 + xi[a]) / 2.0 : (1.0 - xi[a]) / 2.0;
      l[v] = s;
    }
  }
  return l;
}

/// num_vertices x n_p: vertex shape values at the reference points of `Nodes`,
/// cached per degree. Ideal element nodes = ideal vertices * this.
template <ElementFamily Family, NodeSet Nodes>
const Eigen::MatrixXd& vertex_shape_matrix(int p) {
  static std::mutex mutex;
  static std::map<int, Eigen::MatrixXd> cache;
  const std::lock_guard lock(mutex);
  auto it = cache.find(p);
  if (it == cache.end()) {
    const auto pts = Nodes::template points<Family>(p);
    Eigen::MatrixXd m(Family::num_vertices, pts.size());
    for (std::size_t j = 0; j < pts.size(); ++j) {
      const auto l = vertex_shape_values<Family>(pts[j]);
      for (int v = 0; v < Family::num_vertices; ++v) m(v, j) = l[v];
    }
    it = cache.emplace(p, std::move(m)).first;
  }
  return it->second;
}

}  // namespace detail

template <ElementFamily Family, NodeSet Nodes = WarpBlend, int SpaceDim = Family::dim>
class Mesh {
  static_assert(SpaceDim == Family::dim || (SpaceDim == 3 && Family::dim == 2),
                "hom::Mesh: SpaceDim must equal the family's dimension, or be 3 for a surface mesh of a 2D family");
  static_assert(NodeSetFor<Nodes, Family>, "hom::Mesh: the node set does not define nodes on this family");

 public:
  using family = Family;
  using node_set = Nodes;
  static constexpr int dim = Family::dim;
  static constexpr int space_dim = SpaceDim;
  static constexpr int num_vertices = Family::num_vertices;
  using Point = typename Family::Point;                      ///< reference coordinates
  using SpacePoint = Eigen::Matrix<double, SpaceDim, 1>;     ///< physical coordinates
  using Coordinates = Eigen::Matrix<double, SpaceDim, Eigen::Dynamic>;
  using Connectivity = Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic>;
  using Jacobian = Eigen::Matrix<double, SpaceDim, Family::dim>;
  using VertexCoordinates = Eigen::Matrix<double, SpaceDim, Family::num_vertices>;

  Mesh() = default;

  /// Nodes (SpaceDim x N) and connectivity (n_p x E). Nodes are classified
  /// free, elements get entity tag 1; the ideal is the current vertex positions.
  Mesh(int p, Coordinates nodes, Connectivity elements)
      : degree_(p), nodes_(std::move(nodes)), elements_(std::move(elements)) {
    if (p < 1) throw std::invalid_argument("hom::Mesh: degree must be >= 1, got " + std::to_string(p));
    if (elements_.rows() != Family::num_nodes(p))
      throw std::invalid_argument("hom::Mesh: a degree-" + std::to_string(p) + " " + std::string(Family::name) +
                                  " has " + std::to_string(Family::num_nodes(p)) + " nodes, connectivity has " +
                                  std::to_string(elements_.rows()) + " rows");
    for (Eigen::Index e = 0; e < elements_.cols(); ++e)
      for (Eigen::Index i = 0; i < elements_.rows(); ++i)
        if (elements_(i, e) < 0 || elements_(i, e) >= nodes_.cols())
          throw std::invalid_argument("hom::Mesh: element " + std::to_string(e) + " refers to node " +
                                      std::to_string(elements_(i, e)) + ", mesh has " +
                                      std::to_string(nodes_.cols()) + " nodes");
    node_classes_.assign(nodes_.cols(), NodeClass{});
    element_entities_.assign(elements_.cols(), 1);
    ideal_ = nodes_;
  }

  // --- sizes -------------------------------------------------------------
  int degree() const { return degree_; }
  int num_nodes() const { return static_cast<int>(nodes_.cols()); }
  int num_elements() const { return static_cast<int>(elements_.cols()); }
  int nodes_per_element() const { return static_cast<int>(elements_.rows()); }

  // --- geometry and connectivity ------------------------------------------
  const Coordinates& nodes() const { return nodes_; }
  /// Mutable node coordinates (the optimizer moves them; the ideal stays).
  Coordinates& nodes() { return nodes_; }
  auto node(int i) const { return nodes_.col(i); }
  auto node(int i) { return nodes_.col(i); }

  const Connectivity& elements() const { return elements_; }
  /// Global node ids of element e (n_p entries, layout order).
  auto element(int e) const { return elements_.col(e); }
  /// Global id of vertex v of element e.
  int vertex(int e, int v) const { return elements_(v, e); }

  /// SpaceDim x n_p: the node coordinates of element e in layout order.
  Coordinates element_coordinates(int e) const {
    Coordinates x(SpaceDim, nodes_per_element());
    for (int i = 0; i < nodes_per_element(); ++i) x.col(i) = nodes_.col(elements_(i, e));
    return x;
  }

  const NodeLayout<Family>& layout() const { return node_layout<Family>(degree_); }
  const LagrangeBasis<Family, Nodes>& basis() const { return lagrange_basis<Family, Nodes>(degree_); }

  /// phi_e(xi) = sum_j x_j N_j(xi) (eq A.1).
  SpacePoint map(int e, const Point& xi) const { return element_coordinates(e) * basis().value(xi); }
  /// D phi_e(xi), SpaceDim x Dim.
  Jacobian jacobian(int e, const Point& xi) const { return element_coordinates(e) * basis().gradient(xi); }

  // --- classification and model -------------------------------------------
  const std::vector<NodeClass>& node_classes() const { return node_classes_; }
  std::vector<NodeClass>& node_classes() { return node_classes_; }
  const NodeClass& node_class(int i) const { return node_classes_[i]; }
  NodeClass& node_class(int i) { return node_classes_[i]; }

  /// Tag of the Family::dim-dimensional entity of each element.
  const std::vector<int>& element_entities() const { return element_entities_; }
  std::vector<int>& element_entities() { return element_entities_; }

  const std::vector<Entity>& entities() const { return entities_; }
  std::vector<Entity>& entities() { return entities_; }
  /// The entity with this id, if the model lists it.
  const Entity* find_entity(EntityId id) const {
    for (const auto& en : entities_)
      if (en.id == id) return &en;
    return nullptr;
  }

  /// Physical tags of an entity (empty if it has none or is not listed);
  /// an element's are physical_tags({dim, element_entities()[e]}).
  const std::vector<int>& physical_tags(EntityId id) const {
    static const std::vector<int> none;
    const Entity* en = find_entity(id);
    return en ? en->physical_tags : none;
  }

  const std::vector<PhysicalGroup>& physical_groups() const { return physical_groups_; }
  std::vector<PhysicalGroup>& physical_groups() { return physical_groups_; }

  const std::vector<BoundaryFacet<Family>>& boundary_facets() const { return boundary_facets_; }
  std::vector<BoundaryFacet<Family>>& boundary_facets() { return boundary_facets_; }

  /// Global node ids of a classified facet, in its own node order (facet.hpp)
  /// and its recorded orientation.
  std::vector<int> facet_node_ids(const BoundaryFacet<Family>& f) const {
    FacetVertices<Family> local{};
    for (int k = 0; k < facet_num_vertices<Family>; ++k) {
      int found = -1;
      for (int v = 0; v < num_vertices; ++v)
        if (elements_(v, f.element) == f.vertices[k]) found = v;
      if (found < 0) throw std::invalid_argument("hom::Mesh::facet_node_ids: facet vertex is not a vertex of its element");
      local[k] = found;
    }
    const auto loc = facet_nodes<Family>(degree_, local);
    std::vector<int> ids(loc.size());
    for (std::size_t i = 0; i < loc.size(); ++i) ids[i] = elements_(loc[i], f.element);
    return ids;
  }

  // --- ideal (straight-sided) mesh ----------------------------------------
  /// Snapshot coordinates; only the columns of vertex nodes are meaningful.
  const Coordinates& ideal_coordinates() const { return ideal_; }
  /// Replace the snapshot (SpaceDim x num_nodes; vertex columns are used).
  void set_ideal_coordinates(Coordinates x) {
    if (x.cols() != nodes_.cols()) throw std::invalid_argument("hom::Mesh::set_ideal_coordinates: wrong number of columns");
    ideal_ = std::move(x);
  }
  /// The ideal becomes the straight-sided mesh of the current vertices.
  void reset_ideal() { ideal_ = nodes_; }

  VertexCoordinates ideal_vertices(int e) const {
    VertexCoordinates v;
    for (int k = 0; k < num_vertices; ++k) v.col(k) = ideal_.col(elements_(k, e));
    return v;
  }
  /// SpaceDim x n_p: nodes of element e's ideal at Nodes' reference points.
  Coordinates ideal_element_coordinates(int e) const {
    return ideal_vertices(e) * detail::vertex_shape_matrix<Family, Nodes>(degree_);
  }
  /// phi_I(xi) of element e: affine / multilinear map of its ideal vertices.
  SpacePoint ideal_map(int e, const Point& xi) const {
    const auto l = detail::vertex_shape_values<Family>(xi);
    SpacePoint x = SpacePoint::Zero();
    for (int k = 0; k < num_vertices; ++k) x += l[k] * ideal_.col(elements_(k, e));
    return x;
  }
  /// The ideal as the quality module's per-element ideal (planar/volume
  /// meshes); an inverted or flat straight-sided element gives way to the
  /// regular one (straight_sided_or_regular).
  IdealMesh<Family> straight_sided_ideal() const
    requires(SpaceDim == Family::dim)
  {
    std::vector<IdealVertices<Family>> v(num_elements());
    for (int e = 0; e < num_elements(); ++e) v[e] = straight_sided_or_regular<Family>(ideal_vertices(e));
    return IdealMesh<Family>(std::move(v));
  }

  /// Whether node i is a vertex of some element.
  std::vector<bool> vertex_mask() const {
    std::vector<bool> m(num_nodes(), false);
    for (int e = 0; e < num_elements(); ++e)
      for (int v = 0; v < num_vertices; ++v) m[elements_(v, e)] = true;
    return m;
  }

 private:
  int degree_ = 1;
  Coordinates nodes_;
  Connectivity elements_;
  std::vector<NodeClass> node_classes_;
  std::vector<int> element_entities_;
  std::vector<Entity> entities_;
  std::vector<PhysicalGroup> physical_groups_;
  std::vector<BoundaryFacet<Family>> boundary_facets_;
  Coordinates ideal_;
};

}  // namespace hom
