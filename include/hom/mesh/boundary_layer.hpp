#pragma once
/// @file boundary_layer.hpp
/// Insertion of a boundary layer of simplices into a linear isotropic simplex
/// mesh (thesis section 6.3.3.1, step 2, figures 6.7 and 6.8), with the
/// per-element stretched ideal that the smoothing and untangling of chapter 4
/// then realizes.
///
///     hom::BoundaryLayerOptions o{.first_height = 1e-3, .growth = 2, .layers = 4};
///     auto bl = hom::insert_boundary_layer(linear, {wall_tag}, o);
///     hom::optimize(bl.mesh, bl.ideal, opt);    // layers grow to their heights
///
/// Construction (L = options.layers, h_k = first_height growth^k the height
/// of level k, H_k = h_0 + ... + h_{k-1}, H = H_L the total height):
///   - every wall facet (boundary facet whose entity tag is a wall tag) is
///     split 1-to-4 (3D, edge midpoints) or 1-to-2 (2D), the midpoint of an
///     edge shared by two wall facets being one node;
///   - the wall nodes are duplicated: the copies (and the midpoints) stay on
///     the wall, the original nodes, which the original elements keep using,
///     move into the domain by extrusion_fraction * H along the averaged
///     inward unit normal (only the topology is wanted here: the thesis
///     extrudes by 10 % to keep the original elements valid);
///   - between them, interfaces 1..L-1 get one node per wall vertex and wall
///     edge midpoint, at extrusion_fraction * H_k along the normal;
///   - levels 0..L-2 are the stacked template (12 tetrahedra per wall
///     triangle, 4 triangles per wall edge), level L-1 the transition
///     template to the unsplit original facet (7 tetrahedra, 3 triangles);
///     see detail/layer_templates.hpp. A wall facet thus becomes
///     12 (L - 1) + 7 tetrahedra (3D) or 4 (L - 1) + 3 triangles (2D).
/// The original elements keep their ids (0..num_original_elements-1) and the
/// original nodes theirs; layer nodes and elements are appended.
///
/// Wall border: a wall vertex that also lies on non-wall boundary facets
/// (the wall meets a symmetry plane or a box face) has its normal projected
/// onto that facet plane (onto the common line of two planes), so the moved
/// and interface nodes stay on the neighbouring boundary; the layer's side
/// facets there are classified on that neighbour's entity. Those nodes are not
/// free for the volume optimizer, so smoothing cannot lift them from the
/// fraction to their heights: `full_height_positions` has every node at its
/// full height (fraction 1), and a caller moves the held border nodes there
/// before smoothing (boundary_layer_pipeline.hpp does), accepting that the
/// elements between them and the free nodes may start inverted. Since the
/// elements among held nodes only cannot be repaired, the full-height stack
/// of an edge midpoint is the isoparametric one between the curved wall and
/// the straight top edge (see the nodes section of insert_boundary_layer),
/// which stays untangled on a wall edge with a large sagitta (a wing's
/// leading edge at the box faces) where stacking along the normal pokes
/// through the transition's top. A wall-border midpoint lies on the curve
/// its edge lies on, also where one end is a model vertex bounding it.
///
/// Ideal (section 6.3.3.1: "each element on the viscous part is idealized by
/// a tetrahedron that presents the proper stretching along the normal
/// direction", "the elements on the inviscid part are idealized by the
/// corresponding initial linear element"): a layer element of level k is its
/// template simplex placed in the right prism over its flat wall facet, node
/// (site s, interface j) at wall_position(s) + H_j n_f with n_f the facet's
/// inward unit normal, so it has exactly the height h_k; an original element's
/// ideal is its input vertices. The ideal mesh is per element, not conformal.
///
/// Aspect ratio (reported for the ideal layer elements, the stretching of
/// issue 9): longest edge / shortest altitude, simplex_aspect_ratio below;
/// for a layer element of height h over a wall facet of size s it is about
/// s / h (the regular tetrahedron has sqrt(3/2), the equilateral triangle
/// 2 / sqrt(3)).
///
/// Node classification: wall copies keep the original's (with parameters,
/// same position); wall midpoints get the wall entity (or the curve both
/// endpoints lie on, for an edge on the wall's border); moved original and
/// interface nodes are free, except on the wall border, where they are
/// on_entity of the neighbouring boundary entity (fixed at a corner of two
/// or more neighbouring planes).

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include <Eigen/Dense>

#include "hom/element/simplex.hpp"
#include "hom/mesh/detail/edge_curve.hpp"
#include "hom/mesh/detail/layer_templates.hpp"
#include "hom/mesh/facet.hpp"
#include "hom/mesh/mesh.hpp"
#include "hom/mesh/topology.hpp"
#include "hom/quality/ideal.hpp"

namespace hom {

struct BoundaryLayerOptions {
  double first_height = 0.0;        ///< h_0, height of the level at the wall (required, > 0)
  double growth = 2.0;              ///< h_{k+1} / h_k (>= 1)
  int layers = 7;                   ///< number of levels L (>= 1), the last one is the transition
  double extrusion_fraction = 0.1;  ///< the inserted topology is extruded by this fraction of H (0 < f <= 1)

  /// Throws std::invalid_argument naming the first bad value.
  void validate() const {
    if (!(first_height > 0.0) || !std::isfinite(first_height))
      throw std::invalid_argument("hom::BoundaryLayerOptions: first_height must be positive and finite, got " +
                                  std::to_string(first_height));
    if (!(growth >= 1.0) || !std::isfinite(growth))
      throw std::invalid_argument("hom::BoundaryLayerOptions: growth must be >= 1, got " + std::to_string(growth));
    if (layers < 1)
      throw std::invalid_argument("hom::BoundaryLayerOptions: layers must be >= 1, got " + std::to_string(layers));
    if (!(extrusion_fraction > 0.0) || !(extrusion_fraction <= 1.0))
      throw std::invalid_argument("hom::BoundaryLayerOptions: extrusion_fraction must be in (0, 1], got " +
                                  std::to_string(extrusion_fraction));
  }
  /// h_k = first_height growth^k.
  double level_height(int k) const { return first_height * std::pow(growth, k); }
  /// H_k = h_0 + ... + h_{k-1}: distance of interface k from the wall.
  double cumulative_height(int k) const {
    double s = 0.0;
    for (int j = 0; j < k; ++j) s += level_height(j);
    return s;
  }
  double total_height() const { return cumulative_height(layers); }
};

/// Longest edge / shortest altitude of a simplex (D x (D+1) vertex columns);
/// +inf for a degenerate one.
template <int Dim>
double simplex_aspect_ratio(const Eigen::Matrix<double, Dim, Dim + 1>& v) {
  double longest = 0.0;
  for (int i = 0; i <= Dim; ++i)
    for (int j = i + 1; j <= Dim; ++j) longest = std::max(longest, (v.col(i) - v.col(j)).norm());
  Eigen::Matrix<double, Dim, Dim> J;
  for (int k = 0; k < Dim; ++k) J.col(k) = v.col(k + 1) - v.col(0);
  const double volume_times = std::abs(J.determinant());  // Dim! * volume
  // Largest facet measure times (Dim - 1)!: edge length (2D), 2 * area (3D).
  double largest_facet = 0.0;
  for (int f = 0; f <= Dim; ++f) {
    std::array<int, Dim> idx{};
    for (int i = 0, n = 0; i <= Dim; ++i)
      if (i != f) idx[n++] = i;
    double m = 0.0;
    if constexpr (Dim == 2) {
      m = (v.col(idx[1]) - v.col(idx[0])).norm();
    } else {
      const Eigen::Vector3d a = v.col(idx[1]) - v.col(idx[0]), b = v.col(idx[2]) - v.col(idx[0]);
      m = a.cross(b).norm();
    }
    largest_facet = std::max(largest_facet, m);
  }
  // Altitude onto the largest facet = Dim * volume / facet measure
  // = (Dim! volume) / ((Dim-1)! facet measure).
  const double altitude = volume_times / largest_facet;
  return altitude > 0.0 ? longest / altitude : std::numeric_limits<double>::infinity();
}

/// The mesh with its inserted layer, and what the next steps need.
template <int Dim, NodeSet Nodes = WarpBlend>
struct BoundaryLayer {
  using Family = Simplex<Dim>;
  Mesh<Family, Nodes> mesh;  ///< linear, conformal, positively oriented (on a flat enough wall)
  IdealMesh<Family> ideal;   ///< per element: stretched layer ideal or the original element
  /// Per element: its level (0 at the wall, layers - 1 the transition) or
  /// nullopt for an original element.
  std::vector<std::optional<int>> level;
  /// Per element: the index of the wall facet whose stack it belongs to, or
  /// nullopt for an original element.
  std::vector<std::optional<int>> wall_facet;
  /// Per wall facet: its wall nodes (interface 0) in template site order
  /// (detail/layer_templates.hpp: a, b, c, m_ab, m_bc, m_ca; 2D: a, b, m),
  /// ordered so that the extrusion (into the domain) is the right-hand
  /// normal of (a, b, c) (3D) or lies left of a -> b (2D).
  std::vector<std::array<int, detail::layer_num_sites<Dim>>> facet_wall_nodes;
  std::vector<int> facet_tags;      ///< per wall facet: its entity tag
  std::vector<int> wall_nodes;      ///< nodes on the wall: vertex copies and edge midpoints
  std::vector<int> moved_nodes;     ///< the original wall vertices, moved into the domain
  /// Layer nodes on the wall border above the wall (interfaces >= 1 and the
  /// moved originals): the optimizer holds them (not free).
  std::vector<int> border_nodes;
  /// Every node where a full-height extrusion (fraction 1) would put it;
  /// equal to mesh.nodes() off the layer.
  typename Mesh<Simplex<Dim>, Nodes>::Coordinates full_height_positions;
  int num_original_elements = 0;
  int num_wall_facets = 0;          ///< wall facets of the input (each became 4 / 2)
  double total_height = 0.0;        ///< H
  double max_aspect_ratio = 0.0;    ///< largest simplex_aspect_ratio of the ideal layer elements

  bool is_layer(int e) const { return level[e].has_value(); }
};

/// Projection of a point onto the wall, for placing the wall midpoints on a
/// curved wall (empty: midpoints stay on the flat facets). `entities` are the
/// entity tags of the wall facets around the point, ascending: one inside a
/// wall entity; two or more on an edge where wall entities meet, the point
/// then belonging on their intersection. Projecting onto the nearest of all
/// wall entities instead would put a midpoint on a neighbouring face where
/// the chord's sagitta exceeds the distance to that face.
template <int Dim>
using WallProjection = std::function<Eigen::Matrix<double, Dim, 1>(const Eigen::Matrix<double, Dim, 1>&,
                                                                    const std::vector<int>& entities)>;

namespace detail {

template <int Dim>
std::array<int, Dim> sorted_facet_key(std::array<int, Dim> k) {
  std::sort(k.begin(), k.end());
  return k;
}

/// Unit normal of a facet (Dim vertex columns) by the right-hand rule (3D) or
/// the left normal of a -> b (2D), and its measure.
template <int Dim>
std::pair<Eigen::Matrix<double, Dim, 1>, double> facet_normal(const std::array<Eigen::Matrix<double, Dim, 1>, Dim>& x) {
  Eigen::Matrix<double, Dim, 1> n;
  if constexpr (Dim == 2) {
    const Eigen::Vector2d t = x[1] - x[0];
    n = Eigen::Vector2d(-t[1], t[0]);
  } else {
    n = (x[1] - x[0]).cross(x[2] - x[0]);
  }
  const double m = n.norm();
  return {m > 0.0 ? Eigen::Matrix<double, Dim, 1>(n / m) : n, Dim == 2 ? m : m / 2.0};
}

}  // namespace detail

/// Inserts a boundary layer at the boundary facets whose entity tag is in
/// `wall_tags` (file comment). `linear` must be degree 1 with its boundary
/// facets classified (mesh.boundary_facets()); `project_to_wall`, if given,
/// places the wall edge midpoints (and the nodes stacked above them) from
/// the projection of the flat midpoint. Throws std::invalid_argument for bad
/// options, a non-linear mesh, a wall tag with no boundary facet, a wall
/// facet inside the domain, or a vertex whose averaged normal vanishes.
template <int Dim, NodeSet Nodes>
BoundaryLayer<Dim, Nodes> insert_boundary_layer(const Mesh<Simplex<Dim>, Nodes>& linear, const std::vector<int>& wall_tags,
                                                const BoundaryLayerOptions& options,
                                                const WallProjection<Dim>& project_to_wall = {}) {
  using Family = Simplex<Dim>;
  using Point = Eigen::Matrix<double, Dim, 1>;
  using Key = std::array<int, Dim>;
  options.validate();
  if (linear.degree() != 1)
    throw std::invalid_argument("hom::insert_boundary_layer: the mesh must be linear (degree 1), got degree " +
                                std::to_string(linear.degree()));
  if (wall_tags.empty()) throw std::invalid_argument("hom::insert_boundary_layer: no wall tags given");
  const std::set<int> walls(wall_tags.begin(), wall_tags.end());
  for (int t : walls) {
    bool found = false;
    for (const auto& f : linear.boundary_facets()) found = found || f.entity_tag == t;
    if (!found)
      throw std::invalid_argument("hom::insert_boundary_layer: no boundary facet has entity tag " + std::to_string(t));
  }
  const int L = options.layers;
  const double H = options.total_height();
  const double f_ext = options.extrusion_fraction;

  // --- wall facets, oriented with the extrusion (inward) --------------------
  const Topology<Family> topo(linear);
  std::map<Key, FacetRef> boundary_ref;
  for (const auto& r : topo.boundary_facets()) {
    Key k{};
    const auto lv = facet_vertices<Family>(r.local);
    for (int i = 0; i < Dim; ++i) k[i] = linear.vertex(r.element, lv[i]);
    boundary_ref.emplace(detail::sorted_facet_key<Dim>(k), r);
  }
  struct WallFacet {
    Key v;        // inward order (template's a, b(, c))
    int tag = 0;
    int element = 0;
    Point normal;  // inward unit normal
    double measure = 0.0;
  };
  std::vector<WallFacet> wall;
  std::set<Key> wall_keys;
  std::vector<const BoundaryFacet<Family>*> kept_facets;  // non-wall classified facets
  std::map<Key, int> kept_tag;                              // their sorted keys -> entity tag
  for (const auto& bf : linear.boundary_facets()) {
    Key k{};
    for (int i = 0; i < Dim; ++i) k[i] = bf.vertices[i];
    const Key sk = detail::sorted_facet_key<Dim>(k);
    if (!walls.count(bf.entity_tag)) {
      kept_facets.push_back(&bf);
      kept_tag.emplace(sk, bf.entity_tag);
      continue;
    }
    if (!wall_keys.insert(sk).second) continue;  // listed twice
    const auto it = boundary_ref.find(sk);
    if (it == boundary_ref.end())
      throw std::invalid_argument("hom::insert_boundary_layer: a facet of wall entity " + std::to_string(bf.entity_tag) +
                                  " lies inside the domain (embedded walls are not supported)");
    const auto lv = facet_vertices<Family>(it->second.local);  // outward
    WallFacet w;
    for (int i = 0; i < Dim; ++i) w.v[i] = linear.vertex(it->second.element, lv[i]);
    if constexpr (Dim == 3) std::swap(w.v[1], w.v[2]);  // outward right-hand -> inward
    w.tag = bf.entity_tag;
    w.element = it->second.element;
    std::array<Point, Dim> x;
    for (int i = 0; i < Dim; ++i) x[i] = linear.node(w.v[i]);
    std::tie(w.normal, w.measure) = detail::facet_normal<Dim>(x);
    wall.push_back(w);
  }

  // --- sites: wall vertices and wall edge midpoints ------------------------
  struct Site {
    std::array<int, 2> ends{};  // the vertex (ends[0] == ends[1]) or the edge's end vertices
    Point wall_position;        // flat position (chord midpoint)
    Point position;             // where the stacked nodes start (projected midpoint if asked)
    Point normal = Point::Zero();
    std::vector<int> facets;    // incident wall facets
    std::set<int> side_tags;    // entities of incident non-wall boundary facets
    std::vector<Point> side_normals;
    bool is_vertex() const { return ends[0] == ends[1]; }
  };
  std::vector<Site> sites;
  std::map<std::array<int, 2>, int> site_of;
  auto site_index = [&](int a, int b) {
    const std::array<int, 2> key{std::min(a, b), std::max(a, b)};
    auto [it, inserted] = site_of.try_emplace(key, int(sites.size()));
    if (inserted) {
      Site s;
      s.ends = key;
      s.wall_position = 0.5 * (linear.node(a) + linear.node(b));
      s.position = s.wall_position;
      sites.push_back(s);
    }
    return it->second;
  };
  // Local sites of each wall facet (template order, layer_templates.hpp).
  std::vector<std::array<int, detail::layer_num_sites<Dim>>> facet_sites(wall.size());
  for (std::size_t f = 0; f < wall.size(); ++f) {
    const auto& v = wall[f].v;
    auto& fs = facet_sites[f];
    for (int i = 0; i < Dim; ++i) fs[i] = site_index(v[i], v[i]);
    if constexpr (Dim == 3)
      for (int i = 0; i < 3; ++i) fs[3 + i] = site_index(v[i], v[(i + 1) % 3]);
    else
      fs[2] = site_index(v[0], v[1]);
    for (int s : fs) sites[s].facets.push_back(int(f));
  }
  // Non-wall boundary facets touching the wall: the border.
  for (const auto& r : topo.boundary_facets()) {
    Key k{};
    const auto lv = facet_vertices<Family>(r.local);
    for (int i = 0; i < Dim; ++i) k[i] = linear.vertex(r.element, lv[i]);
    if (wall_keys.count(detail::sorted_facet_key<Dim>(k))) continue;
    const auto kt = kept_tag.find(detail::sorted_facet_key<Dim>(k));
    const int tag = kt == kept_tag.end() ? 0 : kt->second;  // 0: unclassified neighbour
    std::array<Point, Dim> x;
    for (int i = 0; i < Dim; ++i) x[i] = linear.node(k[i]);
    const Point m = detail::facet_normal<Dim>(x).first;
    auto touch = [&](int a, int b) {
      const auto it = site_of.find({std::min(a, b), std::max(a, b)});
      if (it == site_of.end()) return;
      Site& s = sites[it->second];
      s.side_tags.insert(tag);
      bool seen = false;
      for (const auto& n : s.side_normals) seen = seen || std::abs(n.dot(m)) > 1.0 - 1e-10;
      if (!seen) s.side_normals.push_back(m);
    };
    for (int i = 0; i < Dim; ++i) {
      touch(k[i], k[i]);
      if constexpr (Dim == 3) touch(k[i], k[(i + 1) % 3]);
    }
  }
  // Normals: area-weighted average of the incident facets' inward normals,
  // kept in the plane (line) of a single neighbouring boundary facet.
  for (auto& s : sites) {
    if (!s.is_vertex()) continue;
    for (int f : s.facets) s.normal += wall[f].measure * wall[f].normal;
    if (s.side_normals.size() == 1) {
      s.normal -= s.normal.dot(s.side_normals[0]) * s.side_normals[0];
    } else if constexpr (Dim == 3) {
      if (s.side_normals.size() == 2) {
        const Eigen::Vector3d line = s.side_normals[0].cross(s.side_normals[1]);
        s.normal = (line.dot(s.normal) >= 0.0 ? 1.0 : -1.0) * line;
      }
    }
    const double n = s.normal.norm();
    if (!(n > 1e-12))
      throw std::invalid_argument("hom::insert_boundary_layer: the averaged wall normal vanishes at node " +
                                  std::to_string(s.ends[0]));
    s.normal /= n;
  }
  for (auto& s : sites) {
    if (s.is_vertex()) continue;
    const Point sum = sites[site_of.at({s.ends[0], s.ends[0]})].normal + sites[site_of.at({s.ends[1], s.ends[1]})].normal;
    if (!(sum.norm() > 1e-12))
      throw std::invalid_argument("hom::insert_boundary_layer: opposite wall normals at the ends of edge (" +
                                  std::to_string(s.ends[0]) + ", " + std::to_string(s.ends[1]) + ")");
    s.normal = sum.normalized();
    if (project_to_wall) {
      std::vector<int> entities;
      for (int f : s.facets) entities.push_back(wall[f].tag);
      std::sort(entities.begin(), entities.end());
      entities.erase(std::unique(entities.begin(), entities.end()), entities.end());
      s.position = project_to_wall(s.wall_position, entities);
    }
  }

  // --- nodes ------------------------------------------------------------------
  const int N0 = linear.num_nodes();
  const int S = int(sites.size());
  // Node of site s on interface k < L; on interface L the original vertex.
  auto node_id = [&](int s, int k) { return k == L ? sites[s].ends[0] : N0 + k * S + s; };
  using Coordinates = typename Mesh<Family, Nodes>::Coordinates;
  Coordinates X(Dim, N0 + L * S);
  X.leftCols(N0) = linear.nodes();
  // The same nodes at the full heights (fraction 1), for the nodes smoothing
  // cannot move there (BoundaryLayer::full_height_positions).
  Coordinates X_full = X;
  // At full height an edge-midpoint site's stack is the isoparametric one
  // of its macro prism, linear in zeta_k = H_k / H between the curved wall
  // point P (the projected midpoint) and the midpoint of the straight top
  // edge c + H nbar (c the chord midpoint, nbar the mean of the end vertices'
  // normals): x_k = (1 - zeta_k) P + zeta_k (c + H nbar). Stacking along the
  // normal instead, P + H_k n, puts interface L - 1 above that top edge where
  // the sagitta s is large against H and the end normals diverge by theta
  // (s + H_{L-1} > H cos(theta / 2)): on the NACA 0012 section's leading
  // edge (chord 0.139, theta = 79 deg, s = 0.011 along n, H = 0.0254) by
  // 0.0237 against 0.0197, a tangle the smoother cannot undo where these
  // nodes are held (the wall border). The isoparametric stack is monotone
  // whenever the top is above the wall (H cos(theta / 2) > s), with every
  // level scaled by the same factor, and it is what carry_wall_curving
  // (boundary_layer_pipeline.hpp) does to the layer at (d). The stacks at
  // the extrusion fraction stay along the normal (only the topology is
  // wanted there, thesis section 6.3.3.1; the smoother places the free ones).
  auto full_height = [&](const Site& st, int k) -> Point {
    const double Hk = options.cumulative_height(k);
    if (st.is_vertex()) return st.position + Hk * st.normal;
    const Point nbar = 0.5 * (sites[site_of.at({st.ends[0], st.ends[0]})].normal +
                              sites[site_of.at({st.ends[1], st.ends[1]})].normal);
    const double zeta = Hk / H;
    return (1.0 - zeta) * st.position + zeta * (st.wall_position + H * nbar);
  };
  for (int k = 0; k < L; ++k)
    for (int s = 0; s < S; ++s) {
      X.col(node_id(s, k)) = sites[s].position + f_ext * options.cumulative_height(k) * sites[s].normal;
      X_full.col(node_id(s, k)) = full_height(sites[s], k);
    }
  for (const auto& s : sites)
    if (s.is_vertex()) {
      X.col(s.ends[0]) = s.position + f_ext * H * s.normal;
      X_full.col(s.ends[0]) = s.position + H * s.normal;
    }

  // --- elements -----------------------------------------------------------
  const int E0 = linear.num_elements();
  const int per_facet = Dim == 3 ? 12 * (L - 1) + 7 : 4 * (L - 1) + 3;
  const int E = E0 + per_facet * int(wall.size());
  typename Mesh<Family, Nodes>::Connectivity conn(Family::num_vertices, E);
  conn.leftCols(E0) = linear.elements();
  std::vector<int> entities = linear.element_entities();
  entities.resize(E);
  std::vector<IdealVertices<Family>> ideal(E);
  for (int e = 0; e < E0; ++e)
    for (int v = 0; v < Family::num_vertices; ++v) ideal[e].col(v) = linear.node(linear.vertex(e, v));
  std::vector<std::optional<int>> level(E), element_facet(E);
  double max_ar = 0.0;
  int e = E0;
  for (std::size_t f = 0; f < wall.size(); ++f) {
    const auto& fs = facet_sites[f];
    auto global = [&](detail::LayerNode n) { return node_id(fs[n.site], n.interface); };
    auto emit = [&](const std::vector<detail::LayerSimplex<Dim>>& simplices, int k) {
      for (const auto& t : simplices) {
        for (int v = 0; v <= Dim; ++v) {
          conn(v, e) = global(t[v]);
          ideal[e].col(v) = sites[fs[t[v].site]].wall_position + options.cumulative_height(t[v].interface) * wall[f].normal;
        }
        entities[e] = linear.element_entities()[wall[f].element];
        level[e] = k;
        element_facet[e] = int(f);
        max_ar = std::max(max_ar, simplex_aspect_ratio<Dim>(ideal[e]));
        ++e;
      }
    };
    for (int k = 0; k + 1 < L; ++k) emit(detail::stacked_template<Dim>(k, global), k);
    int diagonal = 0;
    if constexpr (Dim == 3) {
      // The octahedron's shortest diagonal (any one is conformal).
      double best = std::numeric_limits<double>::infinity();
      for (int d = 0; d < 3; ++d) {
        const double len = (X.col(global({3 + d, L - 1})) - X.col(global({(d + 2) % 3, L}))).norm();
        if (len < best) {
          best = len;
          diagonal = d;
        }
      }
    }
    emit(detail::transition_template<Dim>(L - 1, diagonal), L - 1);
  }

  BoundaryLayer<Dim, Nodes> out;
  out.mesh = Mesh<Family, Nodes>(1, std::move(X), std::move(conn));
  out.full_height_positions = std::move(X_full);
  auto& mesh = out.mesh;
  mesh.element_entities() = std::move(entities);
  mesh.entities() = linear.entities();
  mesh.physical_groups() = linear.physical_groups();

  // --- classification -------------------------------------------------------
  auto& classes = mesh.node_classes();
  std::copy(linear.node_classes().begin(), linear.node_classes().end(), classes.begin());
  auto wall_tag_of = [&](const Site& s) -> std::optional<int> {
    std::optional<int> t;
    for (int f : s.facets) {
      if (t && *t != wall[f].tag) return std::nullopt;
      t = wall[f].tag;
    }
    return t;
  };
  // Off the wall: free inside, on the neighbouring entity on the border.
  auto lifted_class = [&](const Site& s) {
    NodeClass c;
    if (s.side_tags.empty()) {
      c.kind = NodeKind::free;
      c.entity = EntityId{Dim, linear.element_entities()[wall[s.facets[0]].element]};
    } else if (s.side_normals.size() == 1 && s.side_tags.size() == 1 && *s.side_tags.begin() != 0) {
      c.kind = NodeKind::on_entity;
      c.entity = EntityId{Dim - 1, *s.side_tags.begin()};
    } else {
      c.kind = NodeKind::fixed;
    }
    return c;
  };
  // The curve a wall-border edge (a, b) lies on, by the rule elevate.hpp
  // classifies edges with (detail::common_curve), which covers the edge at
  // the end of a wing's leading or trailing edge line, where it meets a box
  // face. Without it such a midpoint was fixed where it lies, and its
  // high-order edge nodes stayed on the chord at (d) while the layer above curved.
  auto border_curve = [&](int a, int b) -> std::optional<EntityId> {
    if constexpr (Dim != 3) return std::nullopt;
    return detail::common_curve(linear, a, b);
  };
  for (int s = 0; s < S; ++s) {
    const Site& site = sites[s];
    NodeClass on_wall;
    if (site.is_vertex()) {
      on_wall = linear.node_class(site.ends[0]);
    } else {
      const auto tag = wall_tag_of(site);
      const auto curve = site.side_tags.empty() ? std::nullopt : border_curve(site.ends[0], site.ends[1]);
      if (curve) {
        on_wall.kind = NodeKind::on_entity;  // border edge on a curve
        on_wall.entity = curve;
      } else if (site.side_tags.empty() && tag) {
        on_wall.kind = NodeKind::on_entity;
        on_wall.entity = EntityId{Dim - 1, *tag};
      } else {
        on_wall.kind = NodeKind::fixed;
      }
    }
    classes[node_id(s, 0)] = on_wall;
    const NodeClass up = lifted_class(site);
    for (int k = 1; k < L; ++k) classes[node_id(s, k)] = up;
    if (site.is_vertex()) classes[site.ends[0]] = up;
    out.wall_nodes.push_back(node_id(s, 0));
    if (site.is_vertex()) out.moved_nodes.push_back(site.ends[0]);
    if (!site.side_tags.empty()) {
      for (int k = 1; k < L; ++k) out.border_nodes.push_back(node_id(s, k));
      if (site.is_vertex()) out.border_nodes.push_back(site.ends[0]);
    }
  }

  // --- boundary facets ----------------------------------------------------
  for (const auto* bf : kept_facets) mesh.boundary_facets().push_back(*bf);
  std::vector<int> site_of_node(mesh.num_nodes(), -1);
  for (int s = 0; s < S; ++s) {
    for (int k = 0; k <= L; ++k)
      if (k < L || sites[s].is_vertex()) site_of_node[node_id(s, k)] = s;
  }
  const Topology<Family> new_topo(mesh);
  for (const auto& r : new_topo.boundary_facets()) {
    const auto lv = facet_vertices<Family>(r.local);
    BoundaryFacet<Family> bf;
    bf.element = r.element;
    bf.local_facet = r.local;
    Key k{};
    for (int i = 0; i < Dim; ++i) bf.vertices[i] = k[i] = mesh.vertex(r.element, lv[i]);
    if (kept_tag.count(detail::sorted_facet_key<Dim>(k))) continue;
    if (!level[r.element]) continue;  // an original element's unclassified boundary facet
    bool on_wall = true;
    for (int v : k) on_wall = on_wall && v >= N0 && v < N0 + S;
    std::optional<int> tag;
    if (on_wall) {
      // The wall facet all the sub-facet's sites belong to.
      for (int fw : sites[site_of_node[k[0]]].facets) {
        bool all = true;
        for (int v : k) {
          const auto& fsv = sites[site_of_node[v]].facets;
          all = all && std::find(fsv.begin(), fsv.end(), fw) != fsv.end();
        }
        if (all) tag = wall[fw].tag;
      }
    } else {
      // A side facet along the wall border: every one contains a node of the
      // border edge's midpoint (3D) or border vertex (2D) stack.
      for (int v : k) {
        if (site_of_node[v] < 0) continue;
        const Site& s = sites[site_of_node[v]];
        if (s.is_vertex() == (Dim == 2) && s.side_tags.size() == 1 && *s.side_tags.begin() != 0)
          tag = *s.side_tags.begin();
      }
    }
    if (!tag) continue;
    bf.entity_tag = *tag;
    mesh.boundary_facets().push_back(bf);
  }

  out.ideal = IdealMesh<Family>(std::move(ideal));
  out.level = std::move(level);
  out.wall_facet = std::move(element_facet);
  for (const auto& fs : facet_sites) {
    auto& w = out.facet_wall_nodes.emplace_back();
    for (int i = 0; i < detail::layer_num_sites<Dim>; ++i) w[i] = node_id(fs[i], 0);
  }
  for (const auto& w : wall) out.facet_tags.push_back(w.tag);
  out.num_original_elements = E0;
  out.num_wall_facets = int(wall.size());
  out.total_height = H;
  out.max_aspect_ratio = max_ar;
  return out;
}

}  // namespace hom
