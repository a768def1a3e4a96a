#pragma once
/// @file mesh_quality.hpp
/// Quality of a whole high-order mesh (definitions 3.7-3.8) and its statistics
/// in the thesis's table form: every element evaluated with element_quality
/// against the chosen ideal (straight-sided: relative quality; regular:
/// absolute quality, section 3.3.2), in parallel over elements.
///
/// The mesh distortion eta_M of eq 3.25 is the ideal-volume-weighted root mean
/// square of the element distortions; it is +inf (q_M = 0) when any element is
/// invalid (corollary 3.4).

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "hom/mesh/mesh.hpp"
#include "hom/quadrature/quadrature_policy.hpp"
#include "hom/quality/element_quality.hpp"
#include "hom/quality/ideal.hpp"
#include "hom/quality/statistics.hpp"

namespace hom {

struct MeshQuality {
  std::vector<ElementQuality> elements;
  double mesh_distortion = 1.0;  ///< eta_M, eq 3.25
  double mesh_quality = 1.0;     ///< q_M = 1 / eta_M, eq 3.26

  std::vector<double> qualities() const {
    std::vector<double> q;
    q.reserve(elements.size());
    for (const auto& e : elements) q.push_back(e.quality);
    return q;
  }
  std::vector<double> scaled_jacobians() const {
    std::vector<double> s;
    s.reserve(elements.size());
    for (const auto& e : elements) s.push_back(e.scaled_jacobian());
    return s;
  }
  std::vector<bool> invalid() const {
    std::vector<bool> b;
    b.reserve(elements.size());
    for (const auto& e : elements) b.push_back(!e.valid);
    return b;
  }
  /// Table row of the element quality q_E (Min, Max, Mean, Std.Dev., #inv).
  Statistics quality_statistics() const { return summarize(qualities(), invalid()); }
  /// Table row of the scaled Jacobian (table 4.5).
  Statistics scaled_jacobian_statistics() const { return summarize(scaled_jacobians(), invalid()); }
  int inverted() const {
    int n = 0;
    for (const auto& e : elements) n += !e.valid;
    return n;
  }
};

/// The ideal vertices of element e for the requested kind; a straight-sided
/// ideal that is inverted or flat gives way to the regular element
/// (straight_sided_or_regular).
template <ElementFamily Family, NodeSet Nodes>
IdealVertices<Family> ideal_for(const Mesh<Family, Nodes, Family::dim>& mesh, int e, IdealKind kind) {
  if (kind == IdealKind::regular) return regular_ideal_vertices<Family>();
  return straight_sided_or_regular<Family>(IdealVertices<Family>(mesh.ideal_vertices(e)));
}

/// How many elements' straight-sided ideals are inverted or flat, so that
/// ideal_for measures them against the regular element.
template <ElementFamily Family, NodeSet Nodes>
int count_replaced_ideals(const Mesh<Family, Nodes, Family::dim>& mesh) {
  int n = 0;
  for (int e = 0; e < mesh.num_elements(); ++e)
    n += !valid_ideal<Family>(IdealVertices<Family>(mesh.ideal_vertices(e)));
  return n;
}

namespace detail {

template <ElementFamily Family, NodeSet Nodes, class Measure, class IdealOf>
MeshQuality evaluate_mesh_quality(const Mesh<Family, Nodes, Family::dim>& mesh, const Measure& measure,
                                  const QuadratureRule<Family::dim>& rule, const IdealOf& ideal_of) {
  const auto& tab = tabulation<Family, Nodes>(mesh.degree(), rule);
  MeshQuality r;
  const int ne = mesh.num_elements();
  r.elements.resize(ne);
#pragma omp parallel for schedule(dynamic, 16)
  for (int e = 0; e < ne; ++e) r.elements[e] = element_quality<Family>(tab, mesh.element_coordinates(e), ideal_of(e), measure);
  double sum = 0.0, volume = 0.0;
  bool all_valid = true;
  for (const auto& q : r.elements) {
    all_valid = all_valid && q.valid;
    if (q.valid) sum += std::abs(q.ideal_volume) * q.distortion * q.distortion;
    volume += std::abs(q.ideal_volume);
  }
  r.mesh_distortion = all_valid ? std::sqrt(sum / volume) : std::numeric_limits<double>::infinity();
  r.mesh_quality = all_valid ? 1.0 / r.mesh_distortion : 0.0;
  return r;
}

}  // namespace detail

/// Evaluates every element of a planar or volume mesh against the ideal `kind`.
template <ElementFamily Family, NodeSet Nodes, class Measure>
MeshQuality mesh_quality(const Mesh<Family, Nodes, Family::dim>& mesh, const Measure& measure, IdealKind kind,
                         const QuadratureRule<Family::dim>& rule) {
  return detail::evaluate_mesh_quality(mesh, measure, rule, [&](int e) { return ideal_for(mesh, e, kind); });
}

/// Evaluates every element against a user-given ideal per element (for
/// example stretched boundary-layer ideals, IdealMesh::affine).
template <ElementFamily Family, NodeSet Nodes, class Measure>
MeshQuality mesh_quality(const Mesh<Family, Nodes, Family::dim>& mesh, const Measure& measure,
                         const IdealMesh<Family>& ideal, const QuadratureRule<Family::dim>& rule) {
  if (ideal.size() != mesh.num_elements())
    throw std::invalid_argument("hom::mesh_quality: the ideal mesh has " + std::to_string(ideal.size()) +
                                " elements, the mesh " + std::to_string(mesh.num_elements()));
  return detail::evaluate_mesh_quality(mesh, measure, rule, [&](int e) { return ideal.vertices(e); });
}

/// Default rule (DefaultExactness) for the mesh's degree.
template <ElementFamily Family, NodeSet Nodes, class Measure>
MeshQuality mesh_quality(const Mesh<Family, Nodes, Family::dim>& mesh, const Measure& measure,
                         IdealKind kind = IdealKind::straight_sided) {
  return mesh_quality(mesh, measure, kind, quadrature_for<Family, DefaultExactness>(mesh.degree()));
}

/// Point-wise quality at every mesh node (the minimum over the elements that
/// share it), for coloring a mesh by quality in ParaView.
template <ElementFamily Family, NodeSet Nodes, class Measure>
std::vector<double> nodal_mesh_quality(const Mesh<Family, Nodes, Family::dim>& mesh, const Measure& measure,
                                       IdealKind kind, const QuadratureRule<Family::dim>& rule) {
  const auto& tab = tabulation<Family, Nodes>(mesh.degree(), rule);
  std::vector<double> q(mesh.num_nodes(), 1.0);
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const auto local = nodal_quality<Family>(tab, mesh.element_coordinates(e), ideal_for(mesh, e, kind), measure);
    for (int i = 0; i < mesh.nodes_per_element(); ++i) {
      double& v = q[mesh.elements()(i, e)];
      v = std::min(v, local[i]);
    }
  }
  return q;
}

}  // namespace hom
