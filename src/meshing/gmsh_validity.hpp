#pragma once
/// @file gmsh_validity.hpp
/// Gmsh's own validity analysis of a hom mesh, as a peer for hom's
/// certificate (issue 8): Plugin(AnalyseMeshQuality) with
/// JacobianDeterminant = 1, in this process through Gmsh's library, and the
/// element-by-element comparison with hom::certify_mesh. Every family whose
/// elements fill their space: planar triangles and quadrilaterals (z = 0),
/// tetrahedra and hexahedra. Used by bench_certify (table 4.1's meshes),
/// bench_curve (the CAD cases) and test_gmsh_validity.
///
/// The mesh goes into a discrete Gmsh model at Gmsh's equispaced nodes
/// (io::to_msh_data), element tag = hom index + 1. The plugin bounds det J
/// by Bezier coefficients with adaptive subdivision and stores min J / max J
/// per element in a view; an element is invalid for Gmsh when min J <= 0 <=
/// max J (ratio <= 0) or when it is completely inverted (min J, max J < 0:
/// the view holds max J / min J > 0). The sign of det J at the reference
/// centroid, from Gmsh's own Jacobian (gmsh::model::mesh::getJacobians),
/// tells the two positive ratios apart: in 3D its determinant; in the plane
/// (x_u x x_v) . e_z, because Gmsh reports unsigned 2D determinants and
/// orients a planar mesh by one normal of its own choice, while hom's
/// planar elements are positive when counter-clockwise.
///
/// Surface meshes (2D elements in R^3) are left out on purpose: Gmsh signs
/// a curved surface element's Jacobian against the normal of its straight
/// facet, which calls strongly curved valid elements invalid (measured in
/// test_surface_certify), so it is not a peer for hom's surface certificate
/// (surface/certified_surface.hpp: mean nodal surface normal).
///
/// The caller holds a hom::meshing::GmshSession.

#include <gmsh.h>

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>
#include <vector>

#include "hom/io/json.hpp"
#include "hom/io/msh.hpp"
#include "hom/mesh/mesh.hpp"
#include "hom/quality/certify.hpp"
#include "meshing_error.hpp"

namespace hom::meshing {

struct GmshVerdict {
  std::string version;
  double time_s = 0.0;          ///< model set-up + plugin + reading the view
  std::vector<char> invalid;    ///< per hom element: min J <= 0 for Gmsh
  int completely_inverted = 0;  ///< min J, max J < 0
  double min_ratio = 1.0;       ///< min over elements of min J / max J (negative when
                                ///< completely inverted)
};

namespace detail {

/// Gmsh's reference centroid of the family (triangles and tetrahedra on
/// [0,1]^d, quadrilaterals and hexahedra on [-1,1]^d).
template <ElementFamily Family>
std::vector<double> gmsh_reference_centroid() {
  if constexpr (std::is_same_v<Family, Simplex<2>>) return {1.0 / 3, 1.0 / 3, 0.0};
  if constexpr (std::is_same_v<Family, Simplex<3>>) return {0.25, 0.25, 0.25};
  return {0.0, 0.0, 0.0};
}

/// Signed det J from one 3 x 3 block of getJacobians (rows: x_u, x_v, x_w;
/// for 2D elements the third row is Gmsh's own normal).
template <int Dim>
double signed_determinant(const double *j, double unsigned_det) {
  if constexpr (Dim == 3) return unsigned_det;
  return j[0] * j[4] - j[1] * j[3];
}

/// A discrete Gmsh model holding the mesh's elements (all nodes on one
/// entity of the elements' dimension: the plugin needs only the elements'
/// nodes). Returns the Gmsh element type.
template <ElementFamily Family, NodeSet Nodes>
int add_gmsh_model(const Mesh<Family, Nodes, Family::dim> &mesh, const std::string &name) {
  constexpr int D = Family::dim;
  const io::MshData d = io::to_msh_data(mesh);
  gmsh::model::add(name);
  gmsh::model::addDiscreteEntity(D, 1);
  std::vector<std::size_t> tags(d.nodes.size());
  std::vector<double> xyz(3 * d.nodes.size(), 0.0);
  for (std::size_t n = 0; n < d.nodes.size(); ++n) {
    tags[n] = static_cast<std::size_t>(d.nodes[n].tag);
    for (int a = 0; a < D; ++a) xyz[3 * n + a] = d.nodes[n].x[a];
  }
  gmsh::model::mesh::addNodes(D, 1, tags, xyz);
  int type = 0;
  std::vector<std::size_t> element_tags, element_nodes;
  for (const auto &e : d.elements) {
    if (e.entity.dim != D) continue;  // boundary facets
    type = e.type;
    element_tags.push_back(element_tags.size() + 1);  // hom element index + 1
    for (int k = 0; k < e.num_nodes; ++k)
      element_nodes.push_back(static_cast<std::size_t>(d.element_nodes[e.first + k]));
  }
  gmsh::model::mesh::addElementsByType(1, type, element_tags, element_nodes);
  return type;
}

/// Runs the plugin on the current model's elements of dimension `dim` and
/// returns the view it creates (min J / max J per element).
inline int run_jacobian_plugin(int dim) {
  std::vector<int> before, after;
  gmsh::view::getTags(before);
  gmsh::plugin::setNumber("AnalyseMeshQuality", "JacobianDeterminant", 1);
  gmsh::plugin::setNumber("AnalyseMeshQuality", "IGEMeasure", 0);
  gmsh::plugin::setNumber("AnalyseMeshQuality", "ICNMeasure", 0);
  gmsh::plugin::setNumber("AnalyseMeshQuality", "HidingThreshold",
                          99);  // hide nothing
  gmsh::plugin::setNumber("AnalyseMeshQuality", "CreateView", 1);
  gmsh::plugin::setNumber("AnalyseMeshQuality", "Recompute",
                          1);  // the plugin caches per dimension
  gmsh::plugin::setNumber("AnalyseMeshQuality", "DimensionOfElements", dim);
  gmsh::plugin::run("AnalyseMeshQuality");
  gmsh::view::getTags(after);
  std::vector<int> created;
  for (int t : after)
    if (std::find(before.begin(), before.end(), t) == before.end()) created.push_back(t);
  if (created.size() != 1)
    throw std::runtime_error("Plugin(AnalyseMeshQuality) created " + std::to_string(created.size()) +
                             " views, expected one (min J / max J)");
  return created[0];
}

}  // namespace detail

template <ElementFamily Family, NodeSet Nodes>
GmshVerdict gmsh_validity(const Mesh<Family, Nodes, Family::dim> &mesh, const std::string &name) {
  constexpr int D = Family::dim;
  const int ne = mesh.num_elements();
  GmshVerdict v;
  v.invalid.assign(ne, 0);
  const auto t0 = std::chrono::steady_clock::now();
  gmsh_call([&] {
    gmsh::option::getString("General.Version", v.version);
    const int element_type = detail::add_gmsh_model(mesh, name);
    const int view = detail::run_jacobian_plugin(D);
    std::string data_type;
    std::vector<std::size_t> tags;
    std::vector<std::vector<double>> data;
    double time = 0.0;
    int components = 0;
    gmsh::view::getModelData(view, 0, data_type, tags, data, time, components);
    // The ratio is > 0 both for valid and for completely inverted elements:
    // the sign of Gmsh's det J at the centroid tells them apart.
    std::vector<std::size_t> order, ignored;
    gmsh::model::mesh::getElementsByType(element_type, order, ignored, -1);
    std::vector<double> jacobians, determinants, coords;
    gmsh::model::mesh::getJacobians(element_type, detail::gmsh_reference_centroid<Family>(), jacobians, determinants,
                                    coords, -1);
    std::vector<double> centroid_det(ne, 0.0);
    for (std::size_t i = 0; i < order.size(); ++i)
      centroid_det.at(order[i] - 1) = detail::signed_determinant<D>(&jacobians.at(9 * i), determinants.at(i));
    std::vector<char> seen(ne, 0);
    for (std::size_t i = 0; i < tags.size(); ++i) {
      const std::size_t e = tags[i] - 1;
      const double ratio = data.at(i).at(0);
      const bool inverted = ratio > 0.0 && centroid_det.at(e) < 0.0;
      v.invalid.at(e) = ratio <= 0.0 || inverted;
      v.completely_inverted += inverted;
      v.min_ratio = std::min(v.min_ratio, inverted ? -ratio : ratio);
      seen.at(e) = 1;
    }
    if (std::count(seen.begin(), seen.end(), 1) != ne)
      throw std::runtime_error("Plugin(AnalyseMeshQuality)'s view misses elements");
    gmsh::view::remove(view);
    gmsh::model::remove();
  });
  v.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return v;
}

/// Gmsh's verdict against hom's certificate, element by element.
struct PeerComparison {
  GmshVerdict gmsh;
  int invalid = 0;                 ///< Gmsh: min J <= 0
  int hom_invalid_gmsh_valid = 0;  ///< disagreements (hom decided)
  int hom_valid_gmsh_invalid = 0;
  int undecided_gmsh_invalid = 0;  ///< hom undecided: no disagreement, Gmsh's verdict for the record
  int undecided_gmsh_valid = 0;
  std::vector<int> disagreeing;  ///< hom element ids (first few)
  int disagreements() const { return hom_invalid_gmsh_valid + hom_valid_gmsh_invalid; }
};

template <ElementFamily Family, NodeSet Nodes>
PeerComparison compare_with_gmsh(const Mesh<Family, Nodes, Family::dim> &mesh, const MeshCertificate<Family> &c,
                                 const std::string &name) {
  PeerComparison r;
  r.gmsh = gmsh_validity(mesh, name);
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const bool g = r.gmsh.invalid[e];
    r.invalid += g;
    const auto s = c.elements[e].status;
    bool differ = false;
    if (s == Certificate::certified_invalid && !g) differ = true, ++r.hom_invalid_gmsh_valid;
    if (s == Certificate::certified_valid && g) differ = true, ++r.hom_valid_gmsh_invalid;
    if (s == Certificate::undecided) ++(g ? r.undecided_gmsh_invalid : r.undecided_gmsh_valid);
    if (differ && r.disagreeing.size() < 10) r.disagreeing.push_back(e);
  }
  return r;
}

inline io::Json peer_json(const PeerComparison &r) {
  io::Json::Array ids(r.disagreeing.begin(), r.disagreeing.end());
  io::Json j = io::Json::object();
  j.set("tool", "gmsh")
      .set("version", r.gmsh.version)
      .set("method",
           "Plugin(AnalyseMeshQuality), JacobianDeterminant = 1 "
           "(Bezier bounds of det J)")
      .set("certified_invalid", r.invalid)
      .set("certified_valid", static_cast<int>(r.gmsh.invalid.size()) - r.invalid)
      .set("completely_inverted", r.gmsh.completely_inverted)
      .set("min_jacobian_ratio", r.gmsh.min_ratio)
      .set("disagreements", r.disagreements())
      .set("hom_invalid_gmsh_valid", r.hom_invalid_gmsh_valid)
      .set("hom_valid_gmsh_invalid", r.hom_valid_gmsh_invalid)
      .set("hom_undecided_gmsh_invalid", r.undecided_gmsh_invalid)
      .set("hom_undecided_gmsh_valid", r.undecided_gmsh_valid)
      .set("disagreeing_elements", io::Json(std::move(ids)))
      .set("time_s", r.gmsh.time_s);
  return j;
}

}  // namespace hom::meshing
