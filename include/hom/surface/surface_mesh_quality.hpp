#pragma once
/// @file surface_mesh_quality.hpp
/// Quality of a whole high-order surface mesh (triangles or quadrilaterals in
/// R^3, Mesh<Family, Nodes, 3>) and its statistics in the thesis's table form
/// (tables 5.1-5.4), the surface counterpart of quality/mesh_quality.hpp with
/// the same result type (MeshQuality: per-element ElementQuality, eta_M, q_M,
/// Statistics rows):
///   - every element evaluated with surface_element_quality (defs. 5.1-5.2)
///     against the chosen ideal: its straight-sided counterpart through its
///     (snapshot) vertices in R^3 (IdealKind::straight_sided), or the regular
///     element, equilateral triangle / unit square (IdealKind::regular);
///   - physical tangents from the 3D node coordinates, oriented either by the
///     normal of each element's straight-sided facet (no geometry needed: an
///     element is invalid where its curved tangent plane turns over with
///     respect to its own facet), or by a surface's normal at the nodes'
///     parameters (the overload taking a SurfaceGeometry and a 2 x N matrix of
///     node parameters).
/// eta_M is the ideal-area-weighted root mean square of the element
/// distortions, +inf (q_M = 0) when any element is invalid, as in eq 3.25.

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "hom/geometry/surface_geometry.hpp"
#include "hom/mesh/mesh.hpp"
#include "hom/quadrature/quadrature_policy.hpp"
#include "hom/quality/ideal.hpp"
#include "hom/quality/mesh_quality.hpp"
#include "hom/surface/surface_element_quality.hpp"

namespace hom {

/// Ideal vertices in R^3 of element e of a surface mesh for the requested kind.
template <ElementFamily Family, NodeSet Nodes>
SurfaceIdealVertices<Family> surface_ideal_for(const Mesh<Family, Nodes, 3>& mesh, int e, IdealKind kind) {
  return kind == IdealKind::regular ? embed_ideal<Family>(regular_ideal_vertices<Family>())
                                    : SurfaceIdealVertices<Family>(mesh.ideal_vertices(e));
}

namespace detail {

/// Fills eta_M and q_M from the element results (eq 3.25 with ideal areas).
inline void finish_mesh_quality(MeshQuality& r) {
  double sum = 0.0, area = 0.0;
  bool all_valid = true;
  for (const auto& q : r.elements) {
    all_valid = all_valid && q.valid;
    if (q.valid) sum += std::abs(q.ideal_volume) * q.distortion * q.distortion;
    area += std::abs(q.ideal_volume);
  }
  r.mesh_distortion = all_valid ? std::sqrt(sum / area) : std::numeric_limits<double>::infinity();
  r.mesh_quality = all_valid ? 1.0 / r.mesh_distortion : 0.0;
}

template <ElementFamily Family, NodeSet Nodes, class Measure, class NormalsOf>
MeshQuality evaluate_surface_mesh_quality(const Mesh<Family, Nodes, 3>& mesh, const Measure& measure, IdealKind kind,
                                          const QuadratureRule<2>& rule, const NormalsOf& normals_of) {
  const auto& tab = tabulation<Family, Nodes>(mesh.degree(), rule);
  MeshQuality r;
  const int ne = mesh.num_elements();
  r.elements.resize(ne);
#pragma omp parallel for schedule(dynamic, 16)
  for (int e = 0; e < ne; ++e)
    r.elements[e] = surface_element_quality<Family>(tab, mesh.element_coordinates(e), surface_ideal_for(mesh, e, kind),
                                                    normals_of(tab, e), measure);
  finish_mesh_quality(r);
  return r;
}

/// Node parameters of element e, periodic ones unwrapped next to vertex 0's.
template <ElementFamily Family, NodeSet Nodes, SurfaceGeometry G>
Eigen::Matrix<double, 2, Eigen::Dynamic> element_parameters(const Mesh<Family, Nodes, 3>& mesh, const G& g,
                                                           const Eigen::Ref<const Eigen::Matrix2Xd>& uv, int e) {
  Eigen::Matrix<double, 2, Eigen::Dynamic> U(2, mesh.nodes_per_element());
  for (int i = 0; i < mesh.nodes_per_element(); ++i) U.col(i) = uv.col(mesh.elements()(i, e));
  for (int k = 0; k < 2; ++k) {
    const ParameterRange range = g.range(k);
    if (range.periodic)
      for (int i = 1; i < U.cols(); ++i) U(k, i) = range.unwrap(U(k, i), U(k, 0));
  }
  return U;
}

}  // namespace detail

/// Evaluates every element of a surface mesh against the ideal `kind`,
/// oriented by the elements' straight-sided facets (mesh.ideal_vertices).
template <ElementFamily Family, NodeSet Nodes, class Measure>
MeshQuality surface_mesh_quality(const Mesh<Family, Nodes, 3>& mesh, const Measure& measure, IdealKind kind,
                                 const QuadratureRule<2>& rule) {
  return detail::evaluate_surface_mesh_quality(mesh, measure, kind, rule, [&](const Tabulation<Family>&, int e) {
    return facet_normals<Family>(mesh.ideal_vertices(e));
  });
}

/// Default rule (DefaultExactness) for the mesh's degree.
template <ElementFamily Family, NodeSet Nodes, class Measure>
MeshQuality surface_mesh_quality(const Mesh<Family, Nodes, 3>& mesh, const Measure& measure,
                                 IdealKind kind = IdealKind::straight_sided) {
  return surface_mesh_quality(mesh, measure, kind, quadrature_for<Family, DefaultExactness>(mesh.degree()));
}

/// Evaluates every element of a surface mesh whose node i lies on `g` at
/// parameters uv.col(i) (2 x num_nodes), oriented by g's normal S_u x S_v.
template <ElementFamily Family, NodeSet Nodes, SurfaceGeometry G, class Measure>
MeshQuality surface_mesh_quality(const Mesh<Family, Nodes, 3>& mesh, const G& g, const Eigen::Ref<const Eigen::Matrix2Xd>& uv,
                                 const Measure& measure, IdealKind kind, const QuadratureRule<2>& rule) {
  if (uv.cols() != mesh.num_nodes())
    throw std::invalid_argument("hom::surface_mesh_quality: " + std::to_string(uv.cols()) + " node parameters for " +
                                std::to_string(mesh.num_nodes()) + " nodes");
  return detail::evaluate_surface_mesh_quality(mesh, measure, kind, rule, [&](const Tabulation<Family>& tab, int e) {
    return surface_normals(tab, g, detail::element_parameters(mesh, g, uv, e));
  });
}

/// Point-wise quality at every mesh node (the minimum over the elements that
/// share it), oriented by the straight-sided facets; for VTU coloring.
template <ElementFamily Family, NodeSet Nodes, class Measure>
std::vector<double> surface_nodal_mesh_quality(const Mesh<Family, Nodes, 3>& mesh, const Measure& measure,
                                               IdealKind kind, const QuadratureRule<2>& rule) {
  const auto& tab = tabulation<Family, Nodes>(mesh.degree(), rule);
  std::vector<double> q(mesh.num_nodes(), 1.0);
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const auto local = surface_nodal_quality<Family>(tab, mesh.element_coordinates(e), surface_ideal_for(mesh, e, kind),
                                                     facet_normals<Family>(mesh.ideal_vertices(e)), measure);
    for (int i = 0; i < mesh.nodes_per_element(); ++i) {
      double& v = q[mesh.elements()(i, e)];
      v = std::min(v, local[i]);
    }
  }
  return q;
}

}  // namespace hom
