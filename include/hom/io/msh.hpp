#pragma once
/// @file msh.hpp
/// Gmsh MSH files to and from hom's Mesh.
///
///   auto mesh = hom::io::read_msh<hom::Simplex<3>>("part.msh");        // warp & blend nodes
///   hom::io::write_msh("out.msh", mesh, {hom::io::MshFormat::Version::v41, true});
///
/// Gmsh stores each element's equispaced nodes in its own order
/// (gmsh_elements.hpp). Reading builds the element map from them (Lagrange
/// basis on Equispaced) and evaluates it at the reference nodes of the Mesh's
/// node set; writing evaluates hom's map at the equispaced nodes. With the
/// Equispaced node set both are copies. A node shared by several elements is
/// placed from the first element that holds it (the others give the same
/// position up to round-off in a conforming mesh).
///
/// Reading (`to_mesh`) takes the elements of the family's dimension as the
/// mesh (ordered by tag; nodes numbered by ascending tag) and refuses (ParseError "FILE:LINE: what"):
///   - elements of a higher dimension, another shape of the same dimension
///     (mixed meshes), or another order;
///   - duplicate node tags, elements referring to missing nodes, an element
///     listing a node twice;
///   - non-conforming connectivity: two elements that put different nodes on
///     their shared edge or face, or one node at two different places;
///   - inconsistent orientation: two elements that traverse their shared edge
///     (2D) or face (3D) in the same direction;
///   - a planar mesh (SpaceDim = Family::dim = 2) with a node off z = 0;
///   - boundary elements (dimension Family::dim - 1) that are not a facet of
///     an element, have another order, or other nodes than that facet.
/// If most elements of a planar or volume mesh have a negative Jacobian at
/// their centre (a mesh of the other orientation, e.g. a Gmsh surface whose
/// normal is -z) every element is reflected; a few negative elements are kept
/// as they are (a tangled mesh is valid input for the untangler).
///
/// Node classification: from the node's entity (MSH 4) or the
/// lowest-dimensional element holding it (MSH 2): entity of dimension
/// SpaceDim -> free, dimension 0 -> fixed, else on_entity; parametric
/// coordinates are kept for nodes whose position is the file's (vertices, or
/// the Equispaced node set). A node on the mesh's topological boundary that
/// would be free (the file lacks boundary information) is fixed.
/// Boundary elements become Mesh::boundary_facets (with their orientation);
/// lower-dimensional elements (points, 3D curve edges) only classify nodes.

#include <algorithm>
#include <map>
#include <string>
#include <type_traits>
#include <unordered_map>
#include <vector>

#include "hom/basis/lagrange.hpp"
#include "hom/io/error.hpp"
#include "hom/io/gmsh_elements.hpp"
#include "hom/io/msh_data.hpp"
#include "hom/io/msh_reader.hpp"
#include "hom/io/msh_writer.hpp"
#include "hom/mesh/detail/site_key.hpp"
#include "hom/mesh/mesh.hpp"
#include "hom/mesh/topology.hpp"
#include "hom/nodes/equispaced.hpp"
#include "hom/quality/ideal.hpp"

namespace hom::io {

namespace detail {

/// Local node permutation that mirrors an element (swaps reference axes 0
/// and 1): new local i takes old local reflection[i].
template <ElementFamily Family>
std::vector<int> reflection_permutation(int p) {
  const auto& layout = node_layout<Family>(p);
  std::vector<int> perm(layout.size());
  for (int i = 0; i < layout.size(); ++i) {
    auto l = layout.lattice(i);
    std::swap(l[0], l[1]);
    perm[i] = layout.index_of(l);
  }
  return perm;
}

inline std::string facet_word(int dim) { return dim == 2 ? "edge" : "face"; }
inline std::string a_facet(int dim) { return dim == 2 ? "an edge" : "a face"; }

}  // namespace detail

/// Builds a Mesh from parsed MSH data (see the file comment for the checks).
template <ElementFamily Family, NodeSet Nodes = WarpBlend, int SpaceDim = Family::dim>
Mesh<Family, Nodes, SpaceDim> to_mesh(const MshData& d) {
  using M = Mesh<Family, Nodes, SpaceDim>;
  constexpr int D = Family::dim;
  constexpr int nv = Family::num_vertices;
  constexpr GmshShape shape = gmsh_shape_of<Family>;
  auto fail = [&](std::size_t line, const std::string& what) -> void { throw ParseError(d.path, line, what); };
  auto tag_str = [](std::int64_t t) { return std::to_string(t); };

  // 1. The mesh's elements: those of the family's dimension.
  int p = 0;
  std::vector<std::size_t> top;
  for (std::size_t i = 0; i < d.elements.size(); ++i) {
    const auto& e = d.elements[i];
    const auto info = gmsh_element_info(e.type);
    if (!info) fail(e.line, "unsupported element type " + std::to_string(e.type));
    if (info->num_nodes != e.num_nodes) fail(e.line, "element " + tag_str(e.tag) + " has the wrong number of nodes");
    if (info->dim > D)
      fail(e.line, "element " + tag_str(e.tag) + " is a " + std::string(shape_name(info->shape)) +
                       "; the file holds a " + std::to_string(info->dim) + "D mesh, not a " + std::string(Family::name) +
                       " mesh");
    if (info->dim < D) continue;
    if (info->shape != shape)
      fail(e.line, "the mesh mixes " + std::string(Family::name) + " and " + std::string(shape_name(info->shape)) +
                       " elements; hom needs one element family per mesh");
    if (p == 0) p = info->order;
    if (info->order != p)
      fail(e.line, "the mesh mixes orders " + std::to_string(p) + " and " + std::to_string(info->order));
    top.push_back(i);
  }
  if (top.empty()) throw IoError(d.path + ": no " + std::string(Family::name) + " elements");
  // Element order: by tag (MSH 4 groups elements in blocks per entity).
  std::stable_sort(top.begin(), top.end(), [&](auto a, auto b) { return d.elements[a].tag < d.elements[b].tag; });
  const int np = Family::num_nodes(p);

  // 2. Node tags.
  std::unordered_map<std::int64_t, std::size_t> by_tag;
  by_tag.reserve(d.nodes.size());
  for (std::size_t i = 0; i < d.nodes.size(); ++i) {
    auto [it, inserted] = by_tag.emplace(d.nodes[i].tag, i);
    if (!inserted)
      fail(d.nodes[i].line, "duplicate node tag " + tag_str(d.nodes[i].tag) + " (first at line " +
                                std::to_string(d.nodes[it->second].line) + ")");
  }
  auto lookup = [&](const MshElement& e, std::int64_t t) {
    auto it = by_tag.find(t);
    if (it == by_tag.end()) fail(e.line, "element " + tag_str(e.tag) + " refers to missing node " + tag_str(t));
    return it->second;
  };

  // 3. Mesh nodes: those of the mesh's elements, by ascending tag (so a file
  // hom wrote, with tags 1..N, reads back with the same numbering).
  std::vector<int> to_mesh_index(d.nodes.size(), -1);
  std::vector<std::size_t> from_mesh_index;
  for (auto i : top)
    for (auto t : d.nodes_of(d.elements[i])) {
      const auto j = lookup(d.elements[i], t);
      if (to_mesh_index[j] < 0) {
        to_mesh_index[j] = 0;
        from_mesh_index.push_back(j);
      }
    }
  std::sort(from_mesh_index.begin(), from_mesh_index.end(),
            [&](std::size_t a, std::size_t b) { return d.nodes[a].tag < d.nodes[b].tag; });
  for (std::size_t k = 0; k < from_mesh_index.size(); ++k) to_mesh_index[from_mesh_index[k]] = static_cast<int>(k);
  const int nn = static_cast<int>(from_mesh_index.size());

  // 4. Connectivity in hom's layout, with the conformity checks.
  const auto& perm = gmsh_to_hom<Family>(p);
  typename M::Connectivity conn(np, top.size());
  const auto sites = hom::detail::local_site_weights<Family>(p);
  std::vector<hom::detail::SiteKey> node_key(nn);
  std::vector<char> has_key(nn, 0);
  std::unordered_map<hom::detail::SiteKey, int, hom::detail::SiteKeyHash> key_node;
  std::vector<int> sorted(np);
  for (std::size_t k = 0; k < top.size(); ++k) {
    const auto& e = d.elements[top[k]];
    const auto tags = d.nodes_of(e);
    for (int g = 0; g < np; ++g) conn(perm[g], Eigen::Index(k)) = to_mesh_index[lookup(e, tags[g])];
    for (int i = 0; i < np; ++i) sorted[i] = conn(i, Eigen::Index(k));
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end())
      fail(e.line, "element " + tag_str(e.tag) + " lists a node twice");
    std::array<int, nv> verts{};
    for (int v = 0; v < nv; ++v) verts[v] = conn(v, Eigen::Index(k));
    for (int i = 0; i < np; ++i) {
      const int n = conn(i, Eigen::Index(k));
      const auto key = hom::detail::site_key(sites[i], verts);
      if (!has_key[n]) {
        node_key[n] = key;
        has_key[n] = 1;
      } else if (!(node_key[n] == key)) {
        fail(e.line, "element " + tag_str(e.tag) + " uses node " + tag_str(d.nodes[from_mesh_index[n]].tag) +
                         " at another place than an earlier element does (non-conforming or corrupt connectivity)");
      }
      auto [it, inserted] = key_node.emplace(key, n);
      if (!inserted && it->second != n)
        fail(e.line, "element " + tag_str(e.tag) + " and an earlier element put different nodes (" +
                         tag_str(d.nodes[from_mesh_index[n]].tag) + ", " +
                         tag_str(d.nodes[from_mesh_index[it->second]].tag) + ") at the same place of a shared " +
                         "edge or face (non-conforming mesh)");
    }
  }

  // 5. Coordinates at the file's (equispaced) nodes.
  typename M::Coordinates X(SpaceDim, nn);
  {
    double extent = 0;
    for (int n = 0; n < nn; ++n)
      for (int a = 0; a < 3; ++a) extent = std::max(extent, std::abs(d.nodes[from_mesh_index[n]].x[a]));
    for (int n = 0; n < nn; ++n) {
      const auto& node = d.nodes[from_mesh_index[n]];
      for (int a = 0; a < SpaceDim; ++a) X(a, n) = node.x[a];
      if constexpr (SpaceDim == 2)
        if (std::abs(node.x[2]) > 1e-12 * std::max(1.0, extent))
          fail(node.line, "node " + tag_str(node.tag) + " has z = " + std::to_string(node.x[2]) +
                              ": not a planar mesh (read it as a surface mesh, SpaceDim = 3)");
    }
  }

  // 6. Orientation: combinatorial consistency, then the global sign.
  std::optional<Topology<Family>> topo;
  {
    M probe(p, X, conn);
    try {
      topo.emplace(probe);
    } catch (const std::invalid_argument&) {
      fail(d.elements[top.front()].line, "a " + detail::facet_word(D) + " is shared by more than two elements");
    }
    constexpr int nf = facet_num_vertices<Family>;
    for (int f = 0; f < topo->num_facets_total(); ++f) {
      const auto refs = topo->facet_elements(f);
      if (refs.size() != 2) continue;
      std::array<std::array<int, nf>, 2> cyc;
      for (int s = 0; s < 2; ++s) {
        const auto lv = facet_vertices<Family>(refs[s].local);
        for (int k = 0; k < nf; ++k) cyc[s][k] = conn(lv[k], refs[s].element);
      }
      // Consistent neighbours traverse the facet in opposite directions: an
      // edge (2D) as (a, b) and (b, a), a face (3D) as a cycle and a rotation
      // of its reverse.
      bool opposite = true;
      if constexpr (nf == 2) {
        opposite = cyc[1][0] == cyc[0][1] && cyc[1][1] == cyc[0][0];
      } else {
        const int r = int(std::find(cyc[1].begin(), cyc[1].end(), cyc[0][0]) - cyc[1].begin());
        for (int k = 0; k < nf; ++k) opposite = opposite && cyc[1][(r - k + nf) % nf] == cyc[0][k];
      }
      if (!opposite) {
        const auto& a = d.elements[top[refs[0].element]];
        const auto& b = d.elements[top[refs[1].element]];
        fail(b.line, "elements " + tag_str(a.tag) + " and " + tag_str(b.tag) +
                         " are oriented inconsistently across their shared " + detail::facet_word(D));
      }
    }
  }
  if constexpr (SpaceDim == D) {
    typename Family::Point centre;
    if constexpr (Family::is_simplex)
      centre.setConstant(1.0 / (D + 1));
    else
      centre.setZero();
    const auto G = vertex_shape_gradients<Family>(centre);
    int negative = 0;
    for (Eigen::Index k = 0; k < conn.cols(); ++k) {
      Eigen::Matrix<double, D, nv> V;
      for (int v = 0; v < nv; ++v) V.col(v) = X.col(conn(v, k));
      negative += (V * G).determinant() < 0;
    }
    if (2 * negative > conn.cols()) {
      const auto r = detail::reflection_permutation<Family>(p);
      const typename M::Connectivity old = conn;
      for (Eigen::Index k = 0; k < conn.cols(); ++k)
        for (int i = 0; i < np; ++i) conn(i, k) = old(r[i], k);
      topo.emplace(M(p, X, conn));
    }
  }

  // 7. Coordinates at the Mesh's node set.
  constexpr bool same_nodes = std::is_same_v<Nodes, Equispaced>;
  std::vector<char> is_vertex(nn, 0);
  for (Eigen::Index k = 0; k < conn.cols(); ++k)
    for (int v = 0; v < nv; ++v) is_vertex[conn(v, k)] = 1;
  typename M::Coordinates Y = X;
  if constexpr (!same_nodes) {
    const Eigen::MatrixXd B =
        lagrange_basis<Family, Equispaced>(p).values(Nodes::template points<Family>(p)).transpose();
    std::vector<char> done(nn, 0);
    typename M::Coordinates Xe(SpaceDim, np);
    for (Eigen::Index k = 0; k < conn.cols(); ++k) {
      for (int i = 0; i < np; ++i) Xe.col(i) = X.col(conn(i, k));
      const typename M::Coordinates Ye = Xe * B;
      for (int i = nv; i < np; ++i) {
        const int n = conn(i, k);
        if (!done[n]) {
          Y.col(n) = Ye.col(i);
          done[n] = 1;
        }
      }
    }
  }
  M mesh(p, std::move(Y), conn);
  mesh.set_ideal_coordinates(X);  // vertex columns: the file's vertices

  // 8. Classification.
  std::vector<std::optional<EntityId>> derived(nn);
  for (const auto& e : d.elements) {
    if (e.entity.dim >= D) continue;
    for (auto t : d.nodes_of(e)) {
      auto it = by_tag.find(t);
      if (it == by_tag.end()) fail(e.line, "element " + tag_str(e.tag) + " refers to missing node " + tag_str(t));
      const int n = to_mesh_index[it->second];
      if (n >= 0 && (!derived[n] || e.entity.dim < derived[n]->dim)) derived[n] = e.entity;
    }
  }
  for (std::size_t k = 0; k < top.size(); ++k)
    for (int i = 0; i < np; ++i) {
      const int n = conn(i, Eigen::Index(k));
      if (!derived[n]) derived[n] = d.elements[top[k]].entity;
    }
  std::vector<char> on_boundary(nn, 0);
  for (const auto& r : topo->boundary_facets())
    for (int i : facet_nodes<Family>(p, r.local)) on_boundary[conn(i, r.element)] = 1;
  for (int n = 0; n < nn; ++n) {
    const auto& node = d.nodes[from_mesh_index[n]];
    NodeClass c;
    c.entity = node.entity ? node.entity : derived[n];
    const int edim = c.entity->dim;
    c.kind = edim == SpaceDim ? NodeKind::free : (edim == 0 ? NodeKind::fixed : NodeKind::on_entity);
    if (node.num_params > 0 && node.num_params == edim && edim <= 2 && (same_nodes || is_vertex[n])) {
      c.num_params = node.num_params;
      for (int k = 0; k < c.num_params; ++k) c.params[k] = node.params[k];
    }
    if (c.kind == NodeKind::free && on_boundary[n]) {
      c.kind = NodeKind::fixed;
      c.entity.reset();
    }
    mesh.node_class(n) = c;
  }

  // 9. Model: entities, physical groups, element entities.
  for (std::size_t k = 0; k < top.size(); ++k) mesh.element_entities()[k] = d.elements[top[k]].entity.tag;
  mesh.entities() = d.entities;
  mesh.physical_groups() = d.physical_names;

  // 10. Boundary facets.
  constexpr int nf = facet_num_vertices<Family>;
  constexpr GmshShape facet_shape = gmsh_facet_shape_of<Family>;
  std::map<std::array<int, nf>, FacetRef> facet_of;
  for (int f = 0; f < topo->num_facets_total(); ++f) {
    const auto r = topo->facet_elements(f)[0];
    std::array<int, nf> key{};
    const auto lv = facet_vertices<Family>(r.local);
    for (int k = 0; k < nf; ++k) key[k] = mesh.vertex(r.element, lv[k]);
    std::sort(key.begin(), key.end());
    facet_of.emplace(key, r);
  }
  std::vector<std::size_t> facet_elements;
  for (std::size_t i = 0; i < d.elements.size(); ++i)
    if (d.elements[i].entity.dim == D - 1) facet_elements.push_back(i);
  std::stable_sort(facet_elements.begin(), facet_elements.end(),
                   [&](auto a, auto b) { return d.elements[a].tag < d.elements[b].tag; });
  for (auto fi : facet_elements) {
    const auto& e = d.elements[fi];
    const auto info = gmsh_element_info(e.type);
    if (info->shape != facet_shape)
      fail(e.line, "boundary element " + tag_str(e.tag) + " is a " + std::string(shape_name(info->shape)) +
                       "; the facets of a " + std::string(Family::name) + " mesh are " +
                       std::string(shape_name(facet_shape)) + "s");
    if (info->order != p)
      fail(e.line, "boundary element " + tag_str(e.tag) + " has order " + std::to_string(info->order) +
                       ", the mesh has order " + std::to_string(p));
    const auto tags = d.nodes_of(e);
    std::vector<int> ids(tags.size());
    for (std::size_t g = 0; g < tags.size(); ++g) {
      const int n = to_mesh_index[lookup(e, tags[g])];
      if (n < 0)
        fail(e.line, "boundary element " + tag_str(e.tag) + " uses node " + tag_str(tags[g]) +
                         ", which no " + std::string(Family::name) + " holds");
      int local = int(g);
      if constexpr (D == 3) local = gmsh_to_hom<FaceFamily<Family>>(p)[g];
      ids[local] = n;
    }
    std::array<int, nf> key{};
    for (int k = 0; k < nf; ++k) key[k] = ids[k];
    std::sort(key.begin(), key.end());
    const auto it = facet_of.find(key);
    if (it == facet_of.end())
      fail(e.line, "boundary element " + tag_str(e.tag) + " does not lie on " + detail::a_facet(D) + " of any " +
                       std::string(Family::name));
    BoundaryFacet<Family> bf;
    bf.element = it->second.element;
    bf.local_facet = it->second.local;
    bf.entity_tag = e.entity.tag;
    for (int k = 0; k < nf; ++k) bf.vertices[k] = ids[k];
    std::vector<int> expected;
    try {
      expected = mesh.facet_node_ids(bf);
    } catch (const std::invalid_argument&) {
      fail(e.line, "boundary element " + tag_str(e.tag) + " lists its vertices in an impossible order");
    }
    if (expected != ids)
      fail(e.line, "boundary element " + tag_str(e.tag) + " does not have the nodes of the " + detail::facet_word(D) +
                       " of element " + tag_str(d.elements[top[bf.element]].tag) + " it lies on");
    mesh.boundary_facets().push_back(bf);
  }
  return mesh;
}

/// Reads an MSH file (4.1 ASCII/binary or 2.2 ASCII) into a Mesh.
template <ElementFamily Family, NodeSet Nodes = WarpBlend, int SpaceDim = Family::dim>
Mesh<Family, Nodes, SpaceDim> read_msh(const std::string& path) {
  return to_mesh<Family, Nodes, SpaceDim>(read_msh_data(path));
}

/// MSH data of a Mesh: nodes at Gmsh's equispaced reference nodes, tags
/// 1..N in hom's numbering, boundary facets first then the elements.
template <ElementFamily Family, NodeSet Nodes, int SpaceDim>
MshData to_msh_data(const Mesh<Family, Nodes, SpaceDim>& m) {
  constexpr int D = Family::dim;
  constexpr int nv = Family::num_vertices;
  const int p = m.degree();
  const int np = m.nodes_per_element();
  const int type = gmsh_element_type(gmsh_shape_of<Family>, p);
  const int facet_type = gmsh_element_type(gmsh_facet_shape_of<Family>, p);
  constexpr bool same_nodes = std::is_same_v<Nodes, Equispaced>;

  MshData d;
  d.nodes.resize(m.num_nodes());
  std::vector<char> done(m.num_nodes(), 0), is_vertex(m.num_nodes(), 0);
  Eigen::MatrixXd B;
  if constexpr (!same_nodes) B = m.basis().values(node_layout<Family>(p).equispaced_points()).transpose();
  for (int e = 0; e < m.num_elements(); ++e) {
    const auto ids = m.element(e);
    for (int v = 0; v < nv; ++v) is_vertex[ids[v]] = 1;
    typename Mesh<Family, Nodes, SpaceDim>::Coordinates Xe;
    if constexpr (same_nodes)
      Xe = m.element_coordinates(e);
    else
      Xe = m.element_coordinates(e) * B;
    for (int i = 0; i < np; ++i) {
      const int n = ids[i];
      if (done[n]) continue;
      done[n] = 1;
      MshNode& node = d.nodes[n];
      node.tag = n + 1;
      for (int a = 0; a < SpaceDim; ++a) node.x[a] = i < nv ? m.node(n)[a] : Xe(a, i);
      const auto& c = m.node_class(n);
      node.entity = c.entity ? *c.entity : EntityId{D, m.element_entities()[e]};
      if (c.entity && c.num_params > 0 && c.num_params == c.entity->dim && (same_nodes || i < nv)) {
        node.num_params = c.num_params;
        for (int k = 0; k < c.num_params; ++k) node.params[k] = c.params[k];
      }
    }
  }
  for (int n = 0; n < m.num_nodes(); ++n)
    if (!done[n]) throw IoError("node " + std::to_string(n) + " belongs to no element");

  std::int64_t tag = 1;
  for (const auto& f : m.boundary_facets()) {
    const auto ids = m.facet_node_ids(f);
    MshElement e;
    e.tag = tag++;
    e.type = facet_type;
    e.entity = EntityId{D - 1, f.entity_tag};
    e.first = d.element_nodes.size();
    e.num_nodes = static_cast<int>(ids.size());
    for (std::size_t g = 0; g < ids.size(); ++g) {
      std::size_t local = g;
      if constexpr (D == 3) local = gmsh_to_hom<FaceFamily<Family>>(p)[g];
      d.element_nodes.push_back(ids[local] + 1);
    }
    d.elements.push_back(e);
  }
  const auto& perm = gmsh_to_hom<Family>(p);
  for (int k = 0; k < m.num_elements(); ++k) {
    MshElement e;
    e.tag = tag++;
    e.type = type;
    e.entity = EntityId{D, m.element_entities()[k]};
    e.first = d.element_nodes.size();
    e.num_nodes = np;
    for (int g = 0; g < np; ++g) d.element_nodes.push_back(m.element(k)[perm[g]] + 1);
    d.elements.push_back(e);
  }
  d.entities = m.entities();
  d.physical_names = m.physical_groups();
  return d;
}

/// Writes a Mesh as MSH 4.1 (ASCII or binary) or 2.2 (ASCII), atomically.
template <ElementFamily Family, NodeSet Nodes, int SpaceDim>
void write_msh(const std::string& path, const Mesh<Family, Nodes, SpaceDim>& m, const MshFormat& format = {}) {
  MshData d;
  try {
    d = to_msh_data(m);
  } catch (const IoError& e) {
    throw IoError(path + ": " + e.what());
  }
  d.path = path;
  write_msh_data(path, d, format);
}

}  // namespace hom::io
