#pragma once
/// @file gmsh_validity.hpp
/// Gmsh's own validity analysis of a hom tetrahedral mesh, as a peer for
/// hom's certificate (issue 8): Plugin(AnalyseMeshQuality) with
/// JacobianDeterminant = 1, in this process through Gmsh's library, and the
/// element-by-element comparison with hom::certify_mesh. Used by
/// bench_certify (table 4.1's meshes) and bench_curve (the CAD cases).
///
/// The mesh goes into a discrete Gmsh model at Gmsh's equispaced nodes
/// (io::to_msh_data), element tag = hom index + 1. The plugin bounds det J by
/// Bezier coefficients with adaptive subdivision and stores min(J)/max(J)
/// per element in a view; an element is invalid for Gmsh when min J <= 0 <=
/// max J (ratio <= 0) or when it is completely inverted (min J, max J < 0:
/// ratio > 0, told apart by the sign of det J at the centroid, from
/// gmsh::model::mesh::getJacobians). The caller holds a
/// hom::meshing::GmshSession.

#include <gmsh.h>

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>
#include <vector>

#include "harness.hpp"
#include "hom/element/simplex.hpp"
#include "hom/io/json.hpp"
#include "hom/io/msh.hpp"
#include "hom/mesh/mesh.hpp"
#include "hom/quality/certify.hpp"
#include "meshing_error.hpp"

namespace hom::bench {

using GmshTetMesh = hom::Mesh<hom::Simplex<3>>;

struct GmshVerdict {
  std::string version;
  double time_s = 0.0;            ///< model set-up + plugin + reading the view
  std::vector<char> invalid;      ///< per hom element: min J <= 0 for Gmsh
  int completely_inverted = 0;    ///< min J, max J < 0
  double min_ratio = 1.0;         ///< min over elements of min J / max J (the view's value)
};

/// A discrete Gmsh model holding the mesh's elements (all nodes on one
/// volume entity: the plugin needs only the elements' nodes).
inline void add_gmsh_model(const GmshTetMesh& mesh, const std::string& name) {
  const hom::io::MshData d = hom::io::to_msh_data(mesh);
  gmsh::model::add(name);
  gmsh::model::addDiscreteEntity(3, 1);
  std::vector<std::size_t> tags(d.nodes.size());
  std::vector<double> xyz(3 * d.nodes.size());
  for (std::size_t n = 0; n < d.nodes.size(); ++n) {
    tags[n] = static_cast<std::size_t>(d.nodes[n].tag);
    for (int a = 0; a < 3; ++a) xyz[3 * n + a] = d.nodes[n].x[a];
  }
  gmsh::model::mesh::addNodes(3, 1, tags, xyz);
  int type = 0;
  std::vector<std::size_t> element_tags, element_nodes;
  for (const auto& e : d.elements) {
    if (e.entity.dim != 3) continue;  // boundary facets
    type = e.type;
    element_tags.push_back(static_cast<std::size_t>(element_tags.size() + 1));  // hom element index + 1
    for (int k = 0; k < e.num_nodes; ++k) element_nodes.push_back(static_cast<std::size_t>(d.element_nodes[e.first + k]));
  }
  gmsh::model::mesh::addElementsByType(1, type, element_tags, element_nodes);
}

inline GmshVerdict gmsh_validity(const GmshTetMesh& mesh, const std::string& name) {
  GmshVerdict v;
  v.invalid.assign(mesh.num_elements(), 0);
  const auto t0 = std::chrono::steady_clock::now();
  hom::meshing::gmsh_call([&] {
    gmsh::option::getString("General.Version", v.version);
    add_gmsh_model(mesh, name);
    std::vector<int> before, after;
    gmsh::view::getTags(before);
    gmsh::plugin::setNumber("AnalyseMeshQuality", "JacobianDeterminant", 1);
    gmsh::plugin::setNumber("AnalyseMeshQuality", "IGEMeasure", 0);
    gmsh::plugin::setNumber("AnalyseMeshQuality", "ICNMeasure", 0);
    gmsh::plugin::setNumber("AnalyseMeshQuality", "HidingThreshold", 99);  // hide nothing
    gmsh::plugin::setNumber("AnalyseMeshQuality", "CreateView", 1);
    gmsh::plugin::setNumber("AnalyseMeshQuality", "Recompute", 1);  // the plugin caches per dimension
    gmsh::plugin::setNumber("AnalyseMeshQuality", "DimensionOfElements", 3);
    gmsh::plugin::run("AnalyseMeshQuality");
    gmsh::view::getTags(after);
    std::vector<int> created;
    for (int t : after)
      if (std::find(before.begin(), before.end(), t) == before.end()) created.push_back(t);
    if (created.size() != 1)
      throw std::runtime_error("Plugin(AnalyseMeshQuality) created " + std::to_string(created.size()) +
                               " views, expected one (min J / max J)");
    std::string type;
    std::vector<std::size_t> tags;
    std::vector<std::vector<double>> data;
    double time = 0.0;
    int components = 0;
    gmsh::view::getModelData(created[0], 0, type, tags, data, time, components);
    // The ratio is > 0 both for valid and for completely inverted elements:
    // the sign of det at the centroid (Gmsh's own Jacobian) tells them apart.
    int element_type = 0;
    {
      std::vector<int> types;
      gmsh::model::mesh::getElementTypes(types, 3, -1);
      if (types.size() != 1) throw std::runtime_error("expected one element type in the Gmsh model");
      element_type = types[0];
    }
    std::vector<std::size_t> order, ignored;
    gmsh::model::mesh::getElementsByType(element_type, order, ignored, -1);
    std::vector<double> jacobians, determinants, coords;
    gmsh::model::mesh::getJacobians(element_type, {0.25, 0.25, 0.25}, jacobians, determinants, coords, -1);
    std::vector<double> centroid_det(mesh.num_elements(), 0.0);
    for (std::size_t i = 0; i < order.size(); ++i) centroid_det.at(order[i] - 1) = determinants.at(i);
    std::vector<char> seen(mesh.num_elements(), 0);
    for (std::size_t i = 0; i < tags.size(); ++i) {
      const std::size_t e = tags[i] - 1;
      const double ratio = data.at(i).at(0);
      const bool inverted = ratio > 0.0 && centroid_det.at(e) < 0.0;
      v.invalid.at(e) = ratio <= 0.0 || inverted;
      v.completely_inverted += inverted;
      v.min_ratio = std::min(v.min_ratio, inverted ? -ratio : ratio);
      seen[e] = 1;
    }
    if (std::count(seen.begin(), seen.end(), 1) != mesh.num_elements())
      throw std::runtime_error("Plugin(AnalyseMeshQuality)'s view misses elements");
    gmsh::view::remove(created[0]);
    gmsh::model::remove();
  });
  v.time_s = seconds_since(t0);
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
  std::vector<int> disagreeing;    ///< hom element ids (first few)
  int disagreements() const { return hom_invalid_gmsh_valid + hom_valid_gmsh_invalid; }
};

inline PeerComparison compare_with_gmsh(const GmshTetMesh& mesh, const hom::MeshCertificate<hom::Simplex<3>>& c, const std::string& name) {
  PeerComparison r;
  r.gmsh = gmsh_validity(mesh, name);
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const bool g = r.gmsh.invalid[e];
    r.invalid += g;
    const auto s = c.elements[e].status;
    bool differ = false;
    if (s == hom::Certificate::certified_invalid && !g) differ = true, ++r.hom_invalid_gmsh_valid;
    if (s == hom::Certificate::certified_valid && g) differ = true, ++r.hom_valid_gmsh_invalid;
    if (s == hom::Certificate::undecided) ++(g ? r.undecided_gmsh_invalid : r.undecided_gmsh_valid);
    if (differ && r.disagreeing.size() < 10) r.disagreeing.push_back(e);
  }
  return r;
}

inline hom::io::Json peer_json(const PeerComparison& r) {
  hom::io::Json::Array ids(r.disagreeing.begin(), r.disagreeing.end());
  hom::io::Json j = hom::io::Json::object();
  j.set("tool", "gmsh")
      .set("version", r.gmsh.version)
      .set("method", "Plugin(AnalyseMeshQuality), JacobianDeterminant = 1 (Bezier bounds of det J)")
      .set("certified_invalid", r.invalid)
      .set("certified_valid", static_cast<int>(r.gmsh.invalid.size()) - r.invalid)
      .set("completely_inverted", r.gmsh.completely_inverted)
      .set("min_jacobian_ratio", r.gmsh.min_ratio)
      .set("disagreements", r.disagreements())
      .set("hom_invalid_gmsh_valid", r.hom_invalid_gmsh_valid)
      .set("hom_valid_gmsh_invalid", r.hom_valid_gmsh_invalid)
      .set("hom_undecided_gmsh_invalid", r.undecided_gmsh_invalid)
      .set("hom_undecided_gmsh_valid", r.undecided_gmsh_valid)
      .set("disagreeing_elements", hom::io::Json(std::move(ids)))
      .set("time_s", r.gmsh.time_s);
  return j;
}

}  // namespace hom::bench
