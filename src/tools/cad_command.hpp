#pragma once
/// @file cad_command.hpp
/// What `hom curve` and `hom optimize --cad` share: a user's mesh classified
/// on a CAD model, chapter 6's pipeline (or its optimization tail alone on a
/// curved mesh) run on it, the result checked, and the mesh written only when
/// it is valid (the VTU and JSON report always, to show what failed).

#include <sys/resource.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "cad_mesher.hpp"
#include "cad_model.hpp"
#include "curve_mesh.hpp"
#include "refine_invalid.hpp"
#include "hom/io/certification_report.hpp"
#include "hom/io/report.hpp"
#include "mesh_io.hpp"

namespace hom::tools {

/// The command's settings the pipeline and the outputs need.
struct CadCommandOptions {
  std::string command;  ///< "curve" or "optimize": names the report and the messages
  std::string out, vtu, json;
  cad::CurveOptions curve;  ///< p, measure, solver, p-continuation, threads, iterations
};

/// The options `hom curve` and `hom optimize --cad` take alike (outputs,
/// measure, solver, threads, certification), from either command's parsed
/// command line; each command adds its own (degree, p-continuation, limits).
template <class Cli>
CadCommandOptions shared_cad_command_options(std::string command, const Cli& o) {
  CadCommandOptions c;
  c.command = std::move(command);
  c.out = o.out;
  c.vtu = o.vtu;
  c.json = o.json;
  c.curve.measure = o.measure;
  c.curve.solver = o.solver;
  c.curve.threads = o.threads;
  c.curve.verbose = o.verbose;
  o.certify.apply_to(c.curve);
  return c;
}

inline double peak_rss_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / 1024.0;  // Linux: kilobytes
}

/// How many failing elements an invalid result lists.
inline constexpr int failing_elements_listed = 5;

/// Names the failing elements of an invalid result so that a user can find
/// them: up to failing_elements_listed of `elements`, the least scaled
/// Jacobian first, each with its index in the mesh (the linear mesh's element
/// order), centroid, quality, scaled Jacobian and where its nodes are:
/// interior nodes move freely, nodes on a CAD face slide on it, nodes on CAD
/// edges and vertices stay (a fold that only held nodes determine cannot be
/// undone).
template <class MeshT>
void print_failing_elements(const cad::CurveResult<MeshT>& r, std::vector<int> elements) {
  // The worst first (least scaled Jacobian), the ones a user looks at.
  const int listed = std::min(failing_elements_listed, int(elements.size()));
  const auto& sj = r.element_scaled_jacobian;
  std::partial_sort(elements.begin(), elements.begin() + listed, elements.end(),
                    [&](int a, int b) { return std::pair(sj[a], a) < std::pair(sj[b], b); });
  for (int i = 0; i < listed; ++i) {
    const int e = elements[i];
    const auto x = r.mesh.element_coordinates(e);
    const Eigen::VectorXd c = x.rowwise().mean();
    int interior = 0, on_faces = 0;
    const auto nodes = r.mesh.element(e);
    for (int k = 0; k < int(nodes.size()); ++k) {
      const NodeClass& nc = r.mesh.node_class(nodes[k]);
      interior += nc.kind == NodeKind::free;
      on_faces += nc.kind == NodeKind::on_entity && nc.entity && nc.entity->dim == 2;
    }
    std::fprintf(stderr, "  element %d: centroid (", e);
    for (int a = 0; a < int(c.size()); ++a) std::fprintf(stderr, a ? ", %.6g" : "%.6g", c[a]);
    std::fprintf(stderr, "), q %.3g, scaled Jacobian %.3g; of its %d nodes %d interior, %d on CAD faces, %d held\n",
                 r.element_quality[e], r.element_scaled_jacobian[e], int(nodes.size()), interior, on_faces,
                 int(nodes.size()) - interior - on_faces);
  }
  if (int(elements.size()) > listed) std::fprintf(stderr, "  ... and %d more\n", int(elements.size()) - listed);
}

inline void print_stage_table(const std::vector<cad::StageReport>& stages) {
  std::printf("\n  %-8s %-10s %8s %8s %7s %7s %7s %8s %5s %8s %8s\n", "part", "stage", "elements", "nodes", "Min", "Max",
              "Mean", "Std.Dev.", "#inv", "min SJ", "time s");
  for (const auto& s : stages)
    std::printf("  %-8s %-10s %8d %8d %7.4f %7.4f %7.4f %8.4f %5d %8.4f %8.2f\n", s.part.c_str(), s.stage.c_str(),
                s.elements, s.nodes, s.quality.min, s.quality.max, s.quality.mean, s.quality.std_dev, s.quality.inverted,
                s.scaled_jacobian.min, s.time_s);
  std::printf("\n");
}

/// The classification tolerance of a curved mesh's nodes, relative to the
/// model's size: a file keeps the curved elements at equispaced points, which
/// lie on the CAD only up to the interpolation error (1.4e-4 on the unit sphere
/// meshed with 316 degree-3 triangles), and hom's nodes are interpolated
/// from them. A face node is much farther than this from any CAD edge, so the
/// looser tolerance does not move it to one.
constexpr double curved_relative_tolerance = 1e-3;

/// Classifies a user's mesh on `cad` by projection (cad::classify) within
/// `tolerance` (absolute; a curved mesh within at least
/// curved_relative_tolerance x the model's size). A planar mesh (2D elements
/// in z = 0) is classified as a surface mesh in 3D and the classification
/// copied back; the nodes inside its planar face move freely.
template <class MeshT>
void classify_user_mesh(MeshT& mesh, const cad::CadModel& cad, double tolerance) {
  if (mesh.degree() > 1) tolerance = std::max(tolerance, curved_relative_tolerance * cad.size());
  if constexpr (MeshT::space_dim == 3) {
    cad::classify(mesh, cad, tolerance);
  } else {
    using F = typename MeshT::family;
    typename Mesh<F, WarpBlend, 3>::Coordinates X = Eigen::Matrix3Xd::Zero(3, mesh.num_nodes());
    X.topRows(2) = mesh.nodes();
    Mesh<F, WarpBlend, 3> lifted(mesh.degree(), X, mesh.elements());
    cad::classify(lifted, cad, tolerance);
    mesh.node_classes() = lifted.node_classes();
    mesh.element_entities() = lifted.element_entities();
    mesh.entities() = lifted.entities();
    for (auto& c : mesh.node_classes())
      if (c.entity && c.entity->dim == 2) c.kind = NodeKind::free;
  }
}

/// Curves `input` (a linear mesh of the model) or, when it is already curved,
/// only optimizes it on the model (cad::optimize_on_cad), checks the result
/// and writes it. The check: every element valid at every quadrature point,
/// det D phi > 0 at every node (>= 0 on surfaces, whose normal vanishes at a
/// pole), every boundary node on its CAD entity and, with
/// CurveOptions::certify, every element certified valid. An invalid result writes
/// no mesh: only the JSON report, which says what happened, and the VTU, whose
/// fields mark the failing elements. Returns the exit status: 0 written, 3 invalid.
/// With `retry` (another try may follow), an invalid result also puts the
/// balls around its failing elements (balls_around) there; its report and
/// VTU are written all the same (the next try's overwrite them), so that a
/// next try whose meshing fails leaves them.
template <class MeshT>
int curve_and_write(const cad::CadModel& cad, const MeshT& input, const CadCommandOptions& o, double t_linear,
                    std::vector<cad::LocalSize>* retry = nullptr) {
  using F = typename MeshT::family;
  constexpr int S = MeshT::space_dim;
  cad::CurveOptions co = o.curve;
  co.progress = [](const std::string& line) {
    std::printf("  %s\n", line.c_str());
    std::fflush(stdout);
  };
  const std::string kind = MeshT::dim == 3 ? "volume" : S == 2 ? "planar" : "surface";
  const bool curved = input.degree() > 1;
  std::printf("%s %s mesh: %d %s elements of degree %d, %d nodes (%.2f s)\n", curved ? "curved" : "linear",
              kind.c_str(), input.num_elements(), std::string(F::name).c_str(), input.degree(), input.num_nodes(),
              t_linear);
  if (curved) co.p = input.degree();
  auto r = curved ? cad::optimize_on_cad<F, S>(cad, input, co) : cad::curve_mesh<F, S>(cad, input, co);
  if (!r.stages.empty()) r.stages.front().time_s += t_linear;
  // det D phi is also sampled at the nodes (the scaled Jacobian): a negative
  // value there is a fold that no quadrature point sees (typically an element
  // corner on a curved boundary opened beyond 180 degrees); a zero one a
  // corner of 180 degrees or, on a surface, a pole (allowed there).
  const int folded_at_nodes = cad::count_folded_at_nodes(r);
  const cad::FailingElements failing = cad::failing_elements(r);
  print_stage_table(r.stages);
  const double rss = peak_rss_mb();
  std::printf("boundary on the CAD: %d nodes checked, largest distance %.3g\n", r.conformity.checked,
              r.conformity.max_distance);
  if (r.certification) io::print_certification(*r.certification, co.certify_depth);
  const bool valid = failing.why == cad::Failure::none;
  const char* cmd = o.command.c_str();
  if (!valid) {
    const int n = int(failing.elements.size());
    switch (failing.why) {
      case cad::Failure::faces_uncertified:
        std::fprintf(stderr,
                     "hom: %s: NOT CERTIFIED: %d elements have a boundary triangle not certified valid on its CAD "
                     "face, so the volume stage was skipped for another try; no mesh written\n",
                     cmd, n);
        break;
      case cad::Failure::inverted:
        std::fprintf(stderr, "hom: %s: INVALID result: %d of %d elements inverted after optimization; no mesh "
                     "written\n", cmd, r.inverted, r.mesh.num_elements());
        break;
      case cad::Failure::off_cad:
        std::fprintf(stderr, "hom: %s: INVALID result: %s; no mesh written\n", cmd, r.conformity.problem.c_str());
        break;
      case cad::Failure::uncertified:
        std::fprintf(stderr,
                     "hom: %s: NOT CERTIFIED: %d of %d elements are not certified valid (det D phi_P may vanish "
                     "between quadrature points); no mesh written\n",
                     cmd, int(r.certification->uncertified.size()), r.mesh.num_elements());
        break;
      default:
        std::fprintf(stderr,
                     "hom: %s: INVALID result: %d elements have det D phi <= 0 at a node (their quadrature points "
                     "are valid: a fold at an element corner); no mesh written\n",
                     cmd, n);
    }
    if (failing.why != cad::Failure::folded_at_node && n > 0) {
      const char* why = failing.why == cad::Failure::faces_uncertified
                            ? "on uncertified CAD faces"
                            : "inverted, not certified or folded at a node";
      if (n > failing_elements_listed)
        std::fprintf(stderr, "  %d elements fail in all (%s), the %d with the least scaled Jacobian:\n", n, why,
                     failing_elements_listed);
      else
        std::fprintf(stderr, "  %d elements fail in all (%s):\n", n, why);
    }
    print_failing_elements(r, failing.elements);
    if (retry) *retry = cad::balls_around(r.mesh, failing.elements);
  } else {
    std::printf("valid: every element valid at every quadrature point and node%s, every boundary node on its CAD entity\n",
                r.certification ? " and certified valid everywhere" : "");
  }

  const std::string program = "hom " + o.command;
  auto json_cases = [&]() {
    std::vector<io::Json> cases;
    for (const auto& s : r.stages) {
      // The surface part of a volume mesh is its boundary triangles.
      const std::string family =
          s.part == "surface" ? std::string(MeshT::dim == 3 ? "triangle" : F::name) : std::string(F::name);
      io::CaseHeader h{cad.name(), family, co.p, s.elements, s.nodes, s.stage, co.measure, "straight-sided"};
      auto c = io::quality_case(h, s.quality, s.scaled_jacobian);
      c.set("part", s.part)
          .set("time_s", s.time_s)
          .set("iterations", s.iterations)
          .set("peak_rss_mb", rss)
          .set("threads", co.threads);
      if (!s.solver.empty()) c.set("solver", s.solver).set("stop_reason", s.stop_reason);
      if (s.part == "surface" && s.stage == "optimized") c.set("faces_not_converged", s.faces_not_converged);
      if (s.stage == "optimized") c.set("p_continuation", s.p_continuation);
      cases.push_back(std::move(c));
    }
    if (!cases.empty()) {
      cases.back()
          .set("valid", valid)
          .set("elements_folded_at_nodes", folded_at_nodes)
          .set("max_cad_distance", r.conformity.max_distance)
          .set("output", valid ? io::Json(o.out) : io::Json());
      if (r.certification) io::add_certification(cases.back(), *r.certification, co.certify_depth);
    }
    return cases;
  };
  // The VTU is a picture, not a mesh a solver reads: an invalid result is
  // written there too (never to -o), so that its failing elements can be
  // found in ParaView by the fields inverted, folded_at_node and uncertified.
  auto write_quality_vtu = [&](const MeshT& mesh) {
    std::vector<double> inverted, folded, uncertified(r.element_valid.size(), 0.0);
    for (int e = 0; e < int(r.element_valid.size()); ++e) {
      inverted.push_back(r.element_valid[e] ? 0.0 : 1.0);
      folded.push_back(cad::folded_at_node(r, e) ? 1.0 : 0.0);
    }
    if (r.certification)
      for (int e : r.certification->uncertified) uncertified[e] = 1.0;
    io::VtuOptions vo;
    vo.interpolate_point_data = false;
    io::write_vtu(o.vtu, mesh, {node_kind_field(mesh)},
                  {{"quality", 1, r.element_quality},
                   {"scaled_jacobian", 1, r.element_scaled_jacobian},
                   {"inverted", 1, inverted},
                   {"folded_at_node", 1, folded},
                   {"uncertified", 1, uncertified}},
                  vo);
  };
  if (!valid) {
    if (!o.vtu.empty()) {
      write_quality_vtu(r.mesh);
      std::printf("wrote %s (the invalid result, for inspection: fields inverted, folded_at_node, uncertified)\n",
                  o.vtu.c_str());
    }
    if (!o.json.empty()) io::write_report(o.json, program, HOM_VERSION, json_cases());
    return 3;
  }

  auto mesh = std::move(r.mesh);
  cad::add_physical_groups(mesh);
  auto data = io::to_msh_data(mesh);
  const double gap = cad::add_cad_parameters(data, cad);
  io::write_msh_data(o.out, data, {});
  std::printf("wrote %s (MSH 4.1, entities, physical groups and parametric coordinates; Gmsh's equispaced nodes of the "
              "curved elements lie within %.2g of the CAD)\n",
              o.out.c_str(), gap);
  if (!o.vtu.empty()) {
    write_quality_vtu(mesh);
    std::printf("wrote %s\n", o.vtu.c_str());
  }
  if (!o.json.empty()) {
    io::write_report(o.json, program, HOM_VERSION, json_cases());
    std::printf("wrote %s\n", o.json.c_str());
  }
  return 0;
}

}  // namespace hom::tools
