#pragma once
/// @file mesh_ears.hpp
/// The ear split of ears.hpp for a user's linear mesh classified on the model
/// by projection (classify in cad_mesher.hpp), as `hom curve --mesh` reads it.
/// Gmsh's meshes get the split in cad_mesh_data, where Gmsh's line elements
/// say which mesh edges lie on which CAD curve. A user's file need not carry
/// lines, so here the curves' mesh edges come from the classification: an
/// edge of a boundary facet (of an element, for a surface mesh) lies on
/// curve c when both its ends lie on c (on it, or on one of its vertices) and
/// its midpoint is within a quarter of its length of c. A chord of an arc of
/// up to 106 degrees is (its sagitta is tan(angle / 4) / 2 of its length);
/// a chord across a face between two points of one curve, as a thin face's
/// ear has, is much farther.

#include <algorithm>
#include <cstdint>
#include <map>
#include <set>
#include <utility>
#include <vector>

#include "cad_mesher.hpp"
#include "ears.hpp"
#include "hom/io/msh.hpp"

namespace hom::cad {

namespace detail {

/// The CAD curves through each node of `d` (a node on a curve: that curve;
/// on a model vertex: the curves that end there).
inline std::vector<std::set<int>> node_curves(const io::MshData& d, const CadModel& cad) {
  std::map<int, std::set<int>> vertex_curves;
  for (int c = 1; c <= cad.num_edges(); ++c)
    if (!cad.degenerated(c))
      for (int v : cad.edge_vertices(c)) vertex_curves[v].insert(c);
  std::vector<std::set<int>> out(d.nodes.size());
  for (std::size_t i = 0; i < d.nodes.size(); ++i) {
    const auto& e = d.nodes[i].entity;
    if (e && e->dim == 1) out[i] = {e->tag};
    if (e && e->dim == 0 && vertex_curves.count(e->tag)) out[i] = vertex_curves.at(e->tag);
  }
  return out;
}

/// The mesh edges of `d`'s triangles and quadrilaterals (a volume mesh's
/// boundary facets) that lie on a CAD curve (the file comment's test), each
/// as its two node tags (ascending) and the curve's tag.
inline std::map<std::pair<std::int64_t, std::int64_t>, int> edges_on_curves(const io::MshData& d, const CadModel& cad,
                                                                          const GeometryModel<3>& geometry) {
  constexpr int gmsh_triangle = 2, gmsh_quad = 3;
  const auto curves = node_curves(d, cad);
  auto point = [&](std::int64_t tag) {
    const auto& x = d.nodes[tag - 1].x;
    return Eigen::Vector3d(x[0], x[1], x[2]);
  };
  std::map<std::pair<std::int64_t, std::int64_t>, int> on_curve;
  for (const auto& e : d.elements) {
    if (e.type != gmsh_triangle && e.type != gmsh_quad) continue;
    const auto n = d.nodes_of(e);
    for (std::size_t k = 0; k < n.size(); ++k) {
      const std::int64_t a = std::min(n[k], n[(k + 1) % n.size()]), b = std::max(n[k], n[(k + 1) % n.size()]);
      if (on_curve.count({a, b})) continue;
      const Eigen::Vector3d mid = 0.5 * (point(a) + point(b));
      const double length = (point(b) - point(a)).norm();
      for (int c : curves[a - 1]) {
        if (!curves[b - 1].count(c)) continue;
        const auto* g = geometry.curve(c);
        if (g && (g->evaluate(g->project(mid)) - mid).norm() <= 0.25 * length) {
          on_curve[{a, b}] = c;
          break;
        }
      }
    }
  }
  return on_curve;
}

}  // namespace detail

/// Splits the ears of a linear mesh classified on `cad` (tetrahedra with the
/// boundary triangles on the model's faces, or a surface mesh of triangles
/// or quadrilaterals), as split_triangle_ears / split_quad_ears do for
/// Gmsh's meshes. Returns the number of ears split; the mesh is replaced
/// only when there were some, and its new nodes (one per triangle ear, four
/// per quadrilateral ear, on the ear's face) must then be classified again
/// (classify). A planar mesh (SpaceDim = 2, in z = 0 as MSH data holds it)
/// gets its quadrilaterals' ears split in the plane, as Gmsh's planar quads
/// get theirs in cad_mesh_data; its triangles are left (returns 0): the
/// curving pipeline splits their flat corners (hom/mesh/flat_corners.hpp).
template <ElementFamily Family, NodeSet Nodes, int SpaceDim>
int split_mesh_ears(Mesh<Family, Nodes, SpaceDim>& mesh, const CadModel& cad) {
  static_assert(Family::dim == 2 || Family::is_simplex, "hom::cad::split_mesh_ears: tetrahedra, triangles or quads");
  static_assert(SpaceDim == 3 || Family::dim == 2, "hom::cad::split_mesh_ears: a planar mesh of triangles or quads");
  if constexpr (SpaceDim == 2 && Family::is_simplex) {
    return 0;
  } else {
    if (mesh.degree() != 1) return 0;
    constexpr int gmsh_line = 1;
    io::MshData d = io::to_msh_data(mesh);  // node tags: mesh index + 1; z = 0 for a planar mesh
    const auto geometry = cad.geometry_model();
    const auto on_curve = detail::edges_on_curves(d, cad, geometry);
    if (on_curve.size() < 2) return 0;  // an ear has two edges on one curve
    // Gmsh's line elements on the curves, which the splits read.
    const std::int64_t first_line = d.elements.empty() ? 1 : d.elements.back().tag + 1;
    std::int64_t tag = first_line;
    for (const auto& [edge, c] : on_curve) {
      io::MshElement line;
      line.tag = tag++;
      line.type = gmsh_line;
      line.entity = EntityId{1, c};
      line.first = d.element_nodes.size();
      line.num_nodes = 2;
      d.element_nodes.push_back(edge.first);
      d.element_nodes.push_back(edge.second);
      d.elements.push_back(line);
    }
    const FaceGeometry faces = face_geometry(geometry);
    const int ears = Family::is_simplex ? split_triangle_ears(d, faces) : split_quad_ears(d, faces);
    if (ears == 0) return 0;
    std::erase_if(d.elements, [&](const io::MshElement& e) {
      return e.type == gmsh_line && e.entity.dim == 1 && e.tag >= first_line && e.tag < tag;
    });
    mesh = io::to_mesh<Family, Nodes, SpaceDim>(d);
    return ears;
  }
}

}  // namespace hom::cad
