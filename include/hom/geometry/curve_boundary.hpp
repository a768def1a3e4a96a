#pragma once
/// @file curve_boundary.hpp
/// Puts the boundary nodes of a (straight-sided, typically just elevated)
/// high-order mesh onto the geometry of the entities they are classified on:
/// the step "curve the boundary faces to match the geometry" of section 4.3.1.
///
///   auto mesh = hom::elevate(linear, 5);          // nodes on straight facets
///   hom::curve_boundary(mesh, model);              // nodes on sphere, planes
///
/// Which nodes move: every node of a classified boundary facet, and every
/// other node classified on_entity (interior nodes of a surface mesh, nodes
/// of 3D mesh edges on a CAD curve), whose entity has a geometry in the
/// model:
///   - a node on_entity of a curve (dimension 1) with a geometry goes to the
///     closest point of that curve; one on a surface (dimension 2), to the
///     closest point of the surface;
///   - a node of a classified facet that is classified free (the mesh did not
///     say it lies on the boundary) is treated as on the facet's entity;
///   - fixed nodes and nodes on points (dimension 0) or on entities without
///     geometry keep their position and classification;
///   - vertices are projected too unless `project_vertices` is false (a
///     mesher's vertices lie on the geometry up to its tolerance; projecting
///     them gives every boundary node exact parameters).
/// Moved nodes become on_entity with the parameters of their new position
/// (periodic parameters in their range, see ParameterRange::unwrap).
///
/// The projection is the closest point of the straight-sided position (for a
/// sphere, radial from its centre; for a plane, orthogonal). This matches the
/// thesis's procedure for its analytic test cases; it is adequate when the
/// facets are small compared with the curvature radius. The ideal (straight-
/// sided) mesh snapshot is not touched.

#include <algorithm>
#include <vector>

#include "hom/geometry/geometry_model.hpp"
#include "hom/mesh/mesh.hpp"

namespace hom {

struct CurveBoundaryOptions {
  bool project_vertices = true;
};

struct CurveBoundaryReport {
  int curve_nodes = 0;              ///< nodes placed on a curve
  int surface_nodes = 0;            ///< nodes placed on a surface
  int without_geometry = 0;         ///< boundary nodes left alone: entity has no geometry in the model
  double max_displacement = 0.0;    ///< largest distance a node moved
};

template <ElementFamily Family, NodeSet Nodes, int SpaceDim>
CurveBoundaryReport curve_boundary(Mesh<Family, Nodes, SpaceDim>& mesh, const GeometryModel<SpaceDim>& model,
                                   const CurveBoundaryOptions& options = {}) {
  constexpr int facet_dim = Family::dim - 1;
  CurveBoundaryReport report;
  const int n = mesh.num_nodes();
  const auto is_vertex = mesh.vertex_mask();

  // Candidates: nodes of classified facets (a free one adopts the facet's
  // entity) and every on_entity node.
  std::vector<char> candidate(n, 0);
  for (const auto& f : mesh.boundary_facets())
    for (int i : mesh.facet_node_ids(f)) {
      NodeClass& c = mesh.node_class(i);
      if (c.kind == NodeKind::free) {
        c.kind = NodeKind::on_entity;
        c.entity = EntityId{facet_dim, f.entity_tag};
        c.num_params = 0;
      }
      candidate[i] = 1;
    }
  for (int i = 0; i < n; ++i)
    if (mesh.node_class(i).kind == NodeKind::on_entity) candidate[i] = 1;

  for (int i = 0; i < n; ++i) {
    if (!candidate[i] || (is_vertex[i] && !options.project_vertices)) continue;
    NodeClass& c = mesh.node_class(i);
    if (c.kind != NodeKind::on_entity || !c.entity || c.entity->dim == 0 || c.entity->dim > 2) continue;
    const Eigen::Matrix<double, SpaceDim, 1> x = mesh.node(i);
    Eigen::Matrix<double, SpaceDim, 1> y;
    if (c.entity->dim == 1) {
      const auto* g = model.curve(c.entity->tag);
      if (!g) {
        ++report.without_geometry;
        continue;
      }
      const double u = g->project(x);
      y = g->evaluate(u);
      c.num_params = 1;
      c.params = {u, 0.0};
      ++report.curve_nodes;
    } else if constexpr (SpaceDim == 3) {
      const AnySurface* g = c.entity->dim == 2 ? model.surface(c.entity->tag) : nullptr;
      if (!g) {
        ++report.without_geometry;
        continue;
      }
      const Eigen::Vector2d uv = g->project(x);
      y = g->evaluate(uv);
      c.num_params = 2;
      c.params = {uv[0], uv[1]};
      ++report.surface_nodes;
    } else {
      continue;
    }
    report.max_displacement = std::max(report.max_displacement, (y - x).norm());
    mesh.node(i) = y;
  }
  return report;
}

}  // namespace hom
