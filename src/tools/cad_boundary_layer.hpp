#pragma once
/// @file cad_boundary_layer.hpp
/// `hom curve --bl-first H`: chapter 6's boundary layer (section 6.3.3,
/// optimize/boundary_layer_pipeline.hpp) in the CAD pipeline. A linear
/// tetrahedral mesh classified on a CAD model (meshed by Gmsh or the user's)
/// gets layers of stretched tetrahedra on its wall faces, is smoothed against
/// the stretched ideal, elevated to degree p with its wall nodes on the CAD
/// faces themselves (CadModel::geometry_model: OpenCASCADE surfaces, NURBS
/// included) and optimized. As everywhere in `hom curve`, the result is
/// checked before anything is written: no inverted element, every wall node
/// on its CAD face and, with --certify, every element certified valid (after
/// the certify-and-repair stage that then ends stage (e)).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "boundary_layer_report.hpp"
#include "cad_command.hpp"
#include "cad_model.hpp"
#include "hom/io/certification_report.hpp"
#include "hom/optimize/boundary_layer_pipeline.hpp"
#include "hom/optimize/certified.hpp"
#include "mesh_io.hpp"

namespace hom::tools {

struct CadBoundaryLayerOptions {
  BoundaryLayerOptions layer;
  std::vector<int> walls;  ///< CAD face tags; empty: default_walls()
  int max_iterations = 200;
};

/// The faces whose parametric centre is off the model's bounding box: the
/// body inside a far-field box (the default wall of an external flow).
inline std::vector<int> faces_off_bounding_box(const cad::CadModel& cad) {
  const auto box = cad.bounding_box();
  const double tol = 1e-7 * cad.size();
  std::vector<int> faces;
  for (int f = 1; f <= cad.num_faces(); ++f) {
    const auto s = cad.surface(f);
    const auto ru = s.range(0), rv = s.range(1);
    const Eigen::Vector3d x = s.evaluate({ru.lo + 0.5 * ru.length(), rv.lo + 0.5 * rv.length()});
    bool on_box = false;
    for (int i = 0; i < 3; ++i) on_box = on_box || std::abs(x[i] - box[0][i]) < tol || std::abs(x[i] - box[1][i]) < tol;
    if (!on_box) faces.push_back(f);
  }
  return faces;
}

/// The CAD faces that carry boundary facets of `mesh`: those of the solids
/// meshed (all of them, or those of --solids).
inline std::set<int> meshed_faces(const Mesh<Simplex<3>>& mesh) {
  std::set<int> faces;
  for (const auto& f : mesh.boundary_facets()) faces.insert(f.entity_tag);
  return faces;
}

/// The default wall of an external flow, a body inside a far-field domain:
/// the faces of the solids' cavities (inner shells) or, for a model whose
/// body is cut into the outer shell (a wing section spanning a box), the
/// faces off the bounding box; of these, the faces of the meshed solids.
inline std::vector<int> default_walls(const cad::CadModel& cad, const std::set<int>& meshed) {
  auto of_mesh = [&](std::vector<int> faces) {
    std::erase_if(faces, [&](int f) { return !meshed.count(f); });
    return faces;
  };
  auto faces = of_mesh(cad.inner_shell_faces());
  if (faces.empty()) faces = of_mesh(faces_off_bounding_box(cad));
  if (faces.empty())
    throw UsageError("curve: " + cad.name() +
                     ": the meshed solids have no cavity and every face of theirs lies on the model's bounding box, so "
                     "there is no default wall: name it with --bl-walls");
  return faces;
}

/// The wall faces: the given tags, checked (faces of the model that bound
/// the meshed solids), or the default.
inline std::vector<int> wall_faces(const cad::CadModel& cad, const std::vector<int>& given, const std::set<int>& meshed) {
  if (given.empty()) return default_walls(cad, meshed);
  std::set<int> faces;
  for (int f : given) {
    if (f < 1 || f > cad.num_faces())
      throw UsageError("curve: --bl-walls " + std::to_string(f) + ": " + cad.name() + " has faces 1.." +
                       std::to_string(cad.num_faces()));
    if (!meshed.count(f))
      throw UsageError("curve: --bl-walls " + std::to_string(f) + ": face " + std::to_string(f) +
                       " bounds no meshed solid (the linear mesh has no facet on it)");
    faces.insert(f);
  }
  return {faces.begin(), faces.end()};
}

/// Largest distance of the result's wall-facet nodes to their CAD faces.
inline double wall_distance(const Mesh<Simplex<3>>& mesh, const std::vector<int>& walls, const cad::CadModel& cad) {
  double d = 0.0;
  for (const auto& f : mesh.boundary_facets()) {
    if (std::find(walls.begin(), walls.end(), f.entity_tag) == walls.end()) continue;
    const auto s = cad.surface(f.entity_tag);
    for (int n : mesh.facet_node_ids(f)) {
      const Eigen::Vector3d x = mesh.node(n);
      d = std::max(d, (s.evaluate(s.project(x)) - x).norm());
    }
  }
  return d;
}

/// Runs the boundary-layer pipeline on `linear` (a linear tetrahedral mesh
/// classified on `cad`), checks the result and writes it. Returns the exit
/// status: 0 written, 3 invalid (only the JSON report written).
inline int boundary_layer_and_write(const cad::CadModel& cad, const Mesh<Simplex<3>>& linear,
                                    const CadBoundaryLayerOptions& bl, const CadCommandOptions& o) {
  const auto walls = wall_faces(cad, bl.walls, meshed_faces(linear));
  BoundaryLayerPipelineOptions opt;
  opt.layer = bl.layer;
  opt.p = o.curve.p;
  for (auto* s : {&opt.linear_optimize, &opt.high_order_optimize}) {
    s->threads = o.curve.threads;
    s->max_iterations = bl.max_iterations;
    s->verbose = o.curve.verbose;
  }
  // --certify: stage (e) ends with certify-and-repair (optimize/certified.hpp).
  opt.high_order_optimize.certify = o.curve.certify;
  opt.high_order_optimize.certify_depth = o.curve.certify_depth;
  opt.high_order_optimize.certify_rounds = o.curve.certify_rounds;
  opt.progress = [](const std::string& stage) {
    std::printf("  stage %s done\n", stage.c_str());
    std::fflush(stdout);
  };
  std::printf("linear volume mesh: %d tetrahedra, %d nodes; wall faces:", linear.num_elements(), linear.num_nodes());
  for (int w : walls) std::printf(" %d (%s)", w, cad.surface(w).type().c_str());
  std::printf("\nboundary layer: %d layers, first height %g, growth %g (total %g), p = %d\n", bl.layer.layers,
              bl.layer.first_height, bl.layer.growth, bl.layer.total_height(), opt.p);
  std::fflush(stdout);
  const auto r = boundary_layer_pipeline<3>(linear, walls, cad.geometry_model(), opt);
  std::printf("\n");
  print_boundary_layer_stages(r.stages);
  std::printf("\nlargest aspect ratio of the ideal layer elements: %.4g\n", r.layer.max_aspect_ratio);
  // A wall node off its face by more than the model's tolerance would make
  // the mesh disagree with the CAD it claims to fit.
  const double distance = wall_distance(r.mesh, walls, cad);
  const double allowed = 1e-6 * cad.size();
  std::printf("wall on the CAD: largest distance of a wall node to its face %.3g\n", distance);
  const std::optional<CertificationOutcome>& certification = r.certification;
  if (certification) io::print_certification(*certification, o.curve.certify_depth);
  const bool on_cad = distance <= allowed;
  const bool valid = r.valid && on_cad && (!certification || certification->certified());
  const char* cmd = o.command.c_str();
  if (r.stopped_after_smoothing)
    std::fprintf(stderr, "hom: %s: INVALID result: %s; nothing written\n", cmd, smoothed_tangled_message(r).c_str());
  else if (!r.valid)
    std::fprintf(stderr, "hom: %s: INVALID result: %d of %d elements inverted after optimization; nothing written\n", cmd,
                 r.stages.back().quality.inverted, r.mesh.num_elements());
  else if (!on_cad)
    std::fprintf(stderr, "hom: %s: INVALID result: a wall node is %.3g from its CAD face (allowed %.3g); nothing written\n",
                 cmd, distance, allowed);
  else if (!valid)
    std::fprintf(stderr,
                 "hom: %s: NOT CERTIFIED: %d of %d elements are not certified valid after the repair rounds (det D "
                 "phi_P may vanish between quadrature points); nothing written\n",
                 cmd, int(certification->uncertified.size()), r.mesh.num_elements());
  else
    std::printf("valid: no inverted element, every wall node on its CAD face%s\n",
                certification ? ", every element certified valid everywhere" : "");

  auto cases = boundary_layer_cases<3>(cad.name(), r, bl.layer);
  cases.back()
      .set("valid", valid)
      .set("max_cad_distance", distance)
      .set("output", valid ? io::Json(o.out) : io::Json());
  if (certification) io::add_certification(cases.back(), *certification, o.curve.certify_depth);
  if (valid) {
    io::write_msh(o.out, r.mesh, {});
    std::printf("wrote %s\n", o.out.c_str());
    if (!o.vtu.empty()) {
      write_boundary_layer_vtu(o.vtu, r);
      std::printf("wrote %s\n", o.vtu.c_str());
    }
  }
  if (!o.json.empty()) {
    io::write_report(o.json, "hom " + o.command, HOM_VERSION, std::move(cases));
    std::printf("wrote %s\n", o.json.c_str());
  }
  return valid ? 0 : 3;
}

}  // namespace hom::tools
