#pragma once
/// @file optimize_boundary_face.hpp
/// Chapter 5 on one boundary face of a volume mesh: the nodes of the
/// boundary facets on face entity `face_tag` are optimized on that face's
/// surface in (u, v) (optimize_surface.hpp, eq 5.22), each facet against its
/// straight-sided counterpart (the volume mesh's ideal vertices); the nodes
/// on the face's edges and vertices stay, as do fixed nodes. With
/// options.certify the face is then certified (Bernstein bounds of the
/// surface Jacobian, surface/certified_surface.hpp) and its uncertified
/// triangles repaired on the surface: a triangle folded between the
/// quadrature points, at a node say, passes the optimizer's test and still
/// leaves its tetrahedron inverted there.
///
/// The CAD pipeline optimizes every CAD face before the volume (section 6.1,
/// steps 5-6; src/curve). With `element_ideals` each facet is measured
/// against its element's ideal's face instead (the boundary-layer
/// pipeline's stage (c), whose stretched ideal is per element). The
/// boundary-layer pipeline needs it for the faces
/// its layer meets without being its wall (the box faces a wing section
/// spans): the layer's triangles there are curved along the wall's border
/// curve, the volume optimizer holds their nodes, and a triangle folded in
/// its plane leaves its tetrahedron with det D phi < 0 at that node whatever
/// the free nodes do.
///
///     hom::optimize_boundary_face(mesh, 4, plane, options);

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "hom/element/simplex.hpp"
#include "hom/geometry/surface_geometry.hpp"
#include "hom/io/msh.hpp"
#include "hom/mesh/mesh.hpp"
#include "hom/quality/ideal.hpp"
#include "hom/surface/certified_surface.hpp"
#include "hom/surface/optimize_surface.hpp"

namespace hom {

namespace detail {

/// The face of an element's ideal `element_ideal` under boundary facet `f`,
/// its vertices in the order of f.vertices (facet_node_ids' first three).
template <NodeSet Nodes>
SurfaceIdealVertices<Simplex<2>> facet_ideal(const Mesh<Simplex<3>, Nodes, 3>& mesh, const BoundaryFacet<Simplex<3>>& f,
                                             const IdealVertices<Simplex<3>>& element_ideal) {
  SurfaceIdealVertices<Simplex<2>> v;
  for (int k = 0; k < 3; ++k)
    for (int local = 0; local < 4; ++local)
      if (mesh.vertex(f.element, local) == f.vertices[k]) v.col(k) = element_ideal.col(local);
  return v;
}

}  // namespace detail

struct BoundaryFaceResult {
  SurfaceOptimizeResult optimization;
  std::optional<CertificationOutcome> certification;  ///< with options.certify
};

/// Optimizes the nodes of `mesh` on face entity `face_tag` on `surface` (see
/// the file comment); options.solver must be newton (the surface problems
/// are small). Returns nothing when the face has no facet of `mesh` or no
/// free node. `element_ideals`, when given, holds one ideal per element of
/// `mesh` (file comment).
template <class Measure = ShapeMeasure, QuadraturePolicy Q = DefaultExactness, NodeSet Nodes, SurfaceGeometry Surface>
std::optional<BoundaryFaceResult> optimize_boundary_face(Mesh<Simplex<3>, Nodes, 3>& mesh, int face_tag,
                                                            const Surface& surface, const OptimizeOptions& options,
                                                            const Measure& measure = {},
                                                            const IdealMesh<Simplex<3>>* element_ideals = nullptr) {
  using FaceMesh = Mesh<Simplex<2>, Nodes, 3>;
  const int p = mesh.degree();
  if (element_ideals && element_ideals->size() != mesh.num_elements())
    throw std::invalid_argument("hom::optimize_boundary_face: " + std::to_string(element_ideals->size()) +
                                " element ideals for " + std::to_string(mesh.num_elements()) + " elements");
  std::vector<std::vector<int>> facets;
  std::vector<SurfaceIdealVertices<Simplex<2>>> facet_ideals;  // with element_ideals, in facet vertex order
  for (const auto& f : mesh.boundary_facets()) {
    if (f.entity_tag != face_tag) continue;
    facets.push_back(mesh.facet_node_ids(f));
    if (element_ideals) facet_ideals.push_back(detail::facet_ideal(mesh, f, element_ideals->vertices(f.element)));
  }
  if (facets.empty()) return std::nullopt;

  // The face's nodes, numbered locally.
  std::vector<int> global, local(mesh.num_nodes(), -1);
  typename FaceMesh::Connectivity conn(Simplex<2>::num_nodes(p), Eigen::Index(facets.size()));
  for (std::size_t e = 0; e < facets.size(); ++e)
    for (std::size_t i = 0; i < facets[e].size(); ++i) {
      const int g = facets[e][i];
      if (local[g] < 0) {
        local[g] = int(global.size());
        global.push_back(g);
      }
      conn(Eigen::Index(i), Eigen::Index(e)) = local[g];
    }
  const int n = int(global.size());
  Eigen::Matrix3Xd X(3, n), ideal(3, n);
  Eigen::Matrix2Xd uv(2, n);
  for (int k = 0; k < n; ++k) {
    X.col(k) = mesh.node(global[k]);
    ideal.col(k) = mesh.ideal_coordinates().col(global[k]);
    const NodeClass& c = mesh.node_class(global[k]);
    uv.col(k) = c.entity && c.entity->dim == 2 && c.entity->tag == face_tag && c.num_params == 2
                    ? Eigen::Vector2d(c.params[0], c.params[1])
                    : surface.project(X.col(k));
  }

  // The facets turn outward from the volume; the surface optimizer's
  // elements must turn like S_u x S_v. All facets of one face agree, so the
  // first one decides (at its straight-sided centroid).
  const auto& first = facets.front();
  const Eigen::Vector3d a = ideal.col(local[first[0]]), b = ideal.col(local[first[1]]), c = ideal.col(local[first[2]]);
  const auto d = surface.derivatives(surface.project((a + b + c) / 3.0));
  if (d.col(0).cross(d.col(1)).dot((b - a).cross(c - a)) < 0.0) {
    const auto mirror = io::detail::reflection_permutation<Simplex<2>>(p);
    const auto turned = conn;
    for (Eigen::Index e = 0; e < conn.cols(); ++e)
      for (Eigen::Index i = 0; i < conn.rows(); ++i) conn(i, e) = turned(mirror[i], e);
    // The vertex nodes come first, so mirror's first three entries turn the vertices.
    for (auto& v : facet_ideals) {
      const SurfaceIdealVertices<Simplex<2>> unturned = v;
      for (int i = 0; i < 3; ++i) v.col(i) = unturned.col(mirror[i]);
    }
  }

  FaceMesh face(p, std::move(X), std::move(conn));
  face.set_ideal_coordinates(std::move(ideal));
  for (int k = 0; k < n; ++k) face.node_class(k) = mesh.node_class(global[k]);
  const auto free = surface_free_node_mask(face);
  bool any_free = false;
  for (int k = 0; k < n; ++k)
    if (free[k]) {
      any_free = true;
      // A parameter a hair outside the face's range makes the objective +inf.
      for (int axis = 0; axis < 2; ++axis) uv(axis, k) = surface.range(axis).normalize(uv(axis, k));
    }
  if (!any_free) return std::nullopt;

  OptimizeOptions o = options;
  o.ideal = IdealKind::straight_sided;
  const Eigen::Matrix2Xd uv_start = o.certify ? uv : Eigen::Matrix2Xd();  // the repair's fallback
  const auto ideals = element_ideals ? std::move(facet_ideals) : surface_ideals(face, o.ideal);
  BoundaryFaceResult r{optimize_surface<Measure, Q>(face, surface, uv, ideals, o, measure), std::nullopt};
  if (o.certify)
    r.certification = certify_and_repair_surface<Measure, Q>(face, surface, uv, ideals, o.solver_options(),
                                                             o.certify_repair_options(), o.threads,
                                                             o.regularization_alpha, measure, &uv_start);
  for (int k = 0; k < n; ++k) {
    if (!free[k]) continue;
    mesh.node(global[k]) = face.node(k);
    NodeClass& cls = mesh.node_class(global[k]);
    if (cls.entity && cls.entity->dim == 2 && cls.entity->tag == face_tag) {
      cls.num_params = 2;
      cls.params = {uv(0, k), uv(1, k)};
    }
  }
  return r;
}

}  // namespace hom
