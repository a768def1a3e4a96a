// hom optimize IN.msh -o OUT.msh [--solver newton|matrix-free|gauss-seidel|auto]
//                                [--pcont] [--vertex-continuation] [--scope invalid|whole-mesh]
//                                [--ideal straight|equilateral]
//                                [--measure shape|oddy] [--quadrature default|thesis]
//                                [--threads N] [--max-iterations N]
//                                [--certify [--certify-depth N] [--certify-rounds N]]
//                                [--json FILE] [--vtu FILE] [-v|--verbose]
// hom optimize IN.msh --cad MODEL.step|.iges|.brep -o OUT.msh [--solver S] [--pcont]
//                                [--measure shape|oddy] [--threads N] [--max-iterations N]
//                                [--certify [--certify-depth N] [--certify-rounds N]]
//                                [--tolerance T] [--merge-small-edges L] [--json FILE] [--vtu FILE] [-v]
//
// Smooths and untangles a curved high-order mesh whose boundary is already
// curved (chapter 4): the interior nodes move to minimize the regularized
// distortion objective of eq 4.10 (element-wise regularization, eqs
// 4.12-4.14) against the chosen ideal, the boundary stays where the file puts
// it. Prints the quality table (Min, Max, Mean, Std.Dev., #inv) before and
// after, writes the optimized mesh in the input's MSH version, and
// optionally a VTU colored by quality and a JSON report (DESIGN.md).
//
// Which nodes move is the reader's classification (io/msh.hpp): nodes of the
// domain's entity are free; nodes on a geometric point, curve or surface, and
// any node on the mesh's topological boundary (a file without boundary
// information), are fixed. Sliding boundary nodes on their geometry is
// chapter 5's business.
//
// --certify makes certification (quality/certify.hpp: the sign of det D phi_P
// everywhere in each element) the final acceptance test: elements valid at the
// quadrature points but folded between them are optimized further with the
// failing points added to their quadrature (optimize/certified.hpp), and the
// certificate of the result is printed and added to the JSON with hom quality
// --certify's keys. With --cad the same stage runs on the volume or planar
// mesh after the CAD pipeline; a surface mesh is certified element by
// element, against its nodes' interpolated surface normals, and its
// folds are repaired by sliding face nodes on the CAD surface
// (surface/certified_surface.hpp); an uncertified result is not written.
//
// Exit status: 0 the optimized mesh is valid at every quadrature point (with
// --certify: every element certified valid), 3 otherwise (the outputs are
// written anyway; with --cad nothing but the JSON report is written),
// 1 unreadable input or I/O error, 2 bad options or a surface mesh.

#include <sys/resource.h>

#include <cstdio>
#include <optional>
#include <string>
#include <type_traits>

#include <boost/program_options.hpp>

#include "certify_options.hpp"
#include "command.hpp"
#include "hom/io/certification_report.hpp"
#include "hom/io/report.hpp"
#include "hom/measure/oddy_measure.hpp"
#include "hom/measure/shape_measure.hpp"
#include "hom/optimize/optimize.hpp"
#include "hom/quality/certify.hpp"
#include "hom/quality/mesh_quality.hpp"
#include "mesh_io.hpp"
#include "options.hpp"
#include "replaced_ideals_note.hpp"
#ifdef HOM_HAVE_CURVE
#include <chrono>

#include "cad_command.hpp"
#endif

namespace po = boost::program_options;

namespace {

struct OptimizeCli {
  std::string in, out;
  std::string cad;           ///< --cad MODEL: optimize on the model's geometry
  double tolerance = 1e-6;   ///< --cad: classification tolerance relative to the model's size
  double merge_small_edges = 0.0;  ///< --cad: heal the model as `hom curve --merge-small-edges` did
  std::string solver = "auto";
  std::string ideal = "straight";
  std::string measure = "shape";
  std::string quadrature = "default";
  std::string json, vtu;
  bool pcont = false;
  bool vertex_continuation = false;
  std::string scope = "invalid";
  bool verbose = false;
  int threads = 0;
  int max_iterations = 200;
  hom::tools::CertifyCli certify;
};

double peak_rss_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / 1024.0;  // Linux: kilobytes
}

void print_row(const char* label, const hom::Statistics& s) {
  std::printf("  %-16s %8.4f %8.4f %8.4f %9.4f %6d\n", label, s.min, s.max, s.mean, s.std_dev, s.inverted);
}

void print_stage(const char* stage, const hom::MeshQuality& q) {
  std::printf("%s (q_M = %.6f, eq 3.26)\n", stage, q.mesh_quality);
  print_row("quality", q.quality_statistics());
  print_row("scaled Jacobian", q.scaled_jacobian_statistics());
}

/// The MSH version and encoding the input was written in.
hom::io::MshFormat same_format_as(const hom::io::MshData& data) {
  hom::io::MshFormat f;
  f.version = data.version_major == 2 ? hom::io::MshFormat::Version::v22 : hom::io::MshFormat::Version::v41;
  f.binary = data.binary && f.version == hom::io::MshFormat::Version::v41;
  return f;
}

template <class Measure, hom::QuadraturePolicy Q, class MeshT>
int optimize_mesh(MeshT& mesh, const Measure& measure, const OptimizeCli& o, const hom::io::MshData& data) {
  using F = typename MeshT::family;
  const hom::IdealKind ideal = hom::parse_ideal_kind(o.ideal);
  const std::string ideal_name = ideal == hom::IdealKind::regular ? "equilateral" : "straight-sided";
  const auto& rule = hom::quadrature_for<F, Q>(mesh.degree());

  int free_nodes = 0;
  for (const auto& c : mesh.node_classes()) free_nodes += c.kind == hom::NodeKind::free;
  const long free_dofs = long(free_nodes) * F::dim;

  hom::OptimizeOptions opt;
  std::string solver_note;
  if (o.solver == "auto") {
    opt.solver = hom::auto_solver_kind(free_dofs);
    solver_note = " (auto: " + std::to_string(free_dofs) + (free_dofs <= hom::auto_newton_max_dofs ? " <= " : " > ") +
                  std::to_string(hom::auto_newton_max_dofs) + " free coordinates)";
  } else {
    opt.solver = hom::parse_solver_kind(o.solver);
  }
  opt.ideal = ideal;
  opt.p_continuation = o.pcont;
  opt.vertex_continuation = o.vertex_continuation;
  opt.regularization_scope = hom::parse_regularization_scope(o.scope);
  opt.threads = o.threads;
  opt.max_iterations = o.max_iterations;
  opt.verbose = o.verbose;
  o.certify.apply_to(opt);

  std::printf("%s: %s of degree %d, %d elements, %d nodes (%d free, %ld free coordinates)\n", o.in.c_str(),
              std::string(F::name).c_str(), mesh.degree(), mesh.num_elements(), mesh.num_nodes(), free_nodes, free_dofs);
  std::printf("measure %s, ideal %s, quadrature %s (exact to degree %d, %d points per element)\n\n",
              std::string(Measure::name).c_str(), ideal_name.c_str(), o.quadrature.c_str(), rule.exactness, rule.size());
  // A straight-sided ideal is only an ideal when it is valid (remark 3.1): an
  // element whose vertices are tangled would be its own inverted target and
  // stay inverted, so those are measured against the regular element
  // (straight_sided_or_regular).
  const int replaced_ideals = ideal == hom::IdealKind::straight_sided ? hom::count_replaced_ideals(mesh) : 0;
  hom::tools::print_replaced_ideals_note(replaced_ideals);
  if (replaced_ideals > 0) std::printf("\n");
  std::printf("  %-16s %8s %8s %8s %9s %6s\n", "", "Min", "Max", "Mean", "Std.Dev.", "#inv");
  const hom::MeshQuality initial = hom::mesh_quality(mesh, measure, ideal, rule);
  print_stage("initial", initial);
  std::fflush(stdout);

  std::optional<hom::OptimizeResult> result;
  if (free_nodes > 0) result = hom::optimize<Measure, Q>(mesh, opt, measure);
  const hom::MeshQuality final_q = hom::mesh_quality(mesh, measure, ideal, rule);
  print_stage("optimized", final_q);
  std::printf("\n");

  const std::string solver_name = std::string(hom::to_string(opt.solver));
  if (!result) {
    std::printf("no free nodes: every node is fixed, nothing to optimize\n");
  } else {
    if (result->continuation) {
      const auto& c = *result->continuation;
      std::printf("%s continuation: %s, %d iterations, stopped on %s, %d -> %d inverted (sub-)elements\n",
                  result->continuation_policy.c_str(), c.solver.c_str(), c.iterations,
                  std::string(hom::to_string(c.reason)).c_str(), c.initial_inverted, c.inverted);
    } else if (o.vertex_continuation) {
      std::printf("vertex-mesh continuation: the vertex mesh is valid, nothing to do\n");
    } else if (o.pcont) {
      std::printf("p-continuation (app. C): the linear sub-mesh is valid, nothing to do\n");
    }
    const auto& r = result->result;
    std::printf("solver %s%s: %d iterations, stopped on %s (%s), %.3f s\n", solver_name.c_str(), solver_note.c_str(),
                r.iterations, std::string(hom::to_string(r.reason)).c_str(), r.converged ? "converged" : "not converged",
                result->time_s);
  }
  std::printf("%s\n", final_q.inverted() ? "INVALID: some elements still have det <= 0 at a quadrature point"
                                         : "valid at every quadrature point");

  // The certify stage's outcome (or, with no free nodes, the certificate alone).
  std::optional<hom::CertificationOutcome> certification;
  if (o.certify.on) {
    if (result) {
      certification = result->certification;
    } else {
      hom::CertifyOptions co;
      co.max_depth = o.certify.depth;
      co.threads = o.threads;
      certification = hom::certification_outcome(hom::certify_mesh(mesh, co).elements, hom::RepairStop::no_free_nodes);
    }
  }
  if (certification) hom::io::print_certification(*certification, o.certify.depth);

  // Outputs only once the optimization is done, each written atomically.
  hom::io::write_msh(o.out, mesh, same_format_as(data));
  std::printf("wrote %s\n", o.out.c_str());
  if (!o.vtu.empty()) {
    std::vector<double> inverted, sjac;
    for (const auto& e : final_q.elements) {
      inverted.push_back(e.valid ? 0.0 : 1.0);
      sjac.push_back(e.scaled_jacobian());
    }
    hom::io::VtuOptions vo;
    vo.interpolate_point_data = false;
    hom::io::write_vtu(o.vtu, mesh,
                       {{"pointwise_quality", 1, hom::nodal_mesh_quality(mesh, measure, ideal, rule)},
                        hom::tools::node_kind_field(mesh)},
                       {{"quality", 1, final_q.qualities()}, {"scaled_jacobian", 1, sjac}, {"inverted", 1, inverted}}, vo);
    std::printf("wrote %s\n", o.vtu.c_str());
  }
  if (!o.json.empty()) {
    auto make_case = [&](const char* stage, const hom::MeshQuality& q) {
      hom::io::CaseHeader h{o.in, std::string(F::name), mesh.degree(), mesh.num_elements(), mesh.num_nodes(),
                            stage, std::string(Measure::name), ideal_name};
      auto c = hom::io::quality_case(h, q.quality_statistics(), q.scaled_jacobian_statistics());
      c.set("mesh_quality", q.mesh_quality)
          .set("quadrature", o.quadrature)
          .set("quadrature_exactness", rule.exactness)
          .set("free_nodes", free_nodes)
          .set("inverted_ideals", replaced_ideals);  // measured against the equilateral element
      return c;
    };
    auto optimized = make_case("optimized", final_q);
    const int continuation_iterations = result && result->continuation ? result->continuation->iterations : 0;
    optimized.set("output", o.out)
        .set("solver", solver_name)
        .set("auto_solver", o.solver == "auto")
        .set("p_continuation", o.pcont)
        .set("vertex_continuation", o.vertex_continuation)
        .set("regularization_scope", o.scope)
        .set("threads", o.threads)
        .set("iterations", result ? result->result.iterations + continuation_iterations : 0)
        .set("continuation_iterations", continuation_iterations)
        .set("stop_reason", result ? hom::io::Json(std::string(hom::to_string(result->result.reason))) : hom::io::Json())
        .set("converged", result ? result->result.converged : true)
        .set("time_s", result ? result->time_s : 0.0)
        .set("peak_rss_mb", peak_rss_mb());
    if (certification) hom::io::add_certification(optimized, *certification, o.certify.depth);
    hom::io::write_report(o.json, "hom optimize", HOM_VERSION, {make_case("initial", initial), std::move(optimized)});
    std::printf("wrote %s\n", o.json.c_str());
  }
  return final_q.inverted() || (certification && !certification->certified()) ? 3 : 0;
}

template <class Measure, class MeshT>
int with_quadrature(MeshT& mesh, const Measure& measure, const OptimizeCli& o, const hom::io::MshData& data) {
  if (o.quadrature == "thesis") return optimize_mesh<Measure, hom::ThesisExactness>(mesh, measure, o, data);
  return optimize_mesh<Measure, hom::DefaultExactness>(mesh, measure, o, data);
}

#ifdef HOM_HAVE_CURVE
/// hom optimize IN.msh --cad MODEL: the mesh classified on the model and
/// optimized there (cad_command.hpp, as `hom curve MODEL --mesh CURVED.msh`).
int optimize_on_cad(const OptimizeCli& o) {
  const auto t0 = std::chrono::steady_clock::now();
  // (CadError names the file)
  const hom::cad::CadModel cad = hom::cad::read_cad(o.cad, {.merge_small_edges = o.merge_small_edges});
  std::printf("%s\n", cad.summary().c_str());
  for (const auto& h : cad.healing()) std::printf("  healed: %s\n", h.c_str());
  auto c = hom::tools::shared_cad_command_options("optimize", o);
  c.curve.pcont = o.pcont ? hom::cad::CurveOptions::Continuation::on : hom::cad::CurveOptions::Continuation::automatic;
  c.curve.max_iterations = o.max_iterations;
  c.curve.surface_max_iterations = o.max_iterations;
  const auto data = hom::io::read_msh_data(o.in);
  return hom::tools::with_mesh<hom::WarpBlend>(data, [&](auto& mesh) -> int {
    using F = typename std::decay_t<decltype(mesh)>::family;
    if constexpr (!F::is_simplex && F::dim == 3) {
      throw hom::tools::UsageError("optimize: " + o.in + " is a hexahedral mesh; --cad handles tetrahedra, and "
                                   "triangles or quadrilaterals on surfaces or in the plane");
    } else {
      if (mesh.degree() < 2)
        throw hom::tools::UsageError("optimize: " + o.in + " is a linear mesh; curve it onto the model with 'hom curve " +
                                     o.cad + " --mesh " + o.in + " --p P'");
      hom::tools::classify_user_mesh(mesh, cad, o.tolerance * cad.size());
      const double t_read = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      return hom::tools::curve_and_write(cad, mesh, c, t_read);
    }
  });
}
#endif

void check_options(OptimizeCli& o) {
  using hom::tools::UsageError;
  if (o.in.empty()) throw UsageError("optimize: need an input mesh (see 'hom optimize --help')");
  if (o.out.empty()) throw UsageError("optimize: need an output file: -o OUT.msh");
  if (!hom::tools::ends_with(o.in, ".msh")) throw UsageError("optimize: can only read .msh files, not '" + o.in + "'");
  if (!hom::tools::ends_with(o.out, ".msh")) throw UsageError("optimize: -o file name must end in .msh, got '" + o.out + "'");
  if (o.solver != "auto") {
    try {
      hom::parse_solver_kind(o.solver);
    } catch (const std::invalid_argument&) {
      throw UsageError("optimize: --solver must be newton, matrix-free, gauss-seidel or auto, got '" + o.solver + "'");
    }
  }
  if (o.measure != "shape" && o.measure != "oddy")
    throw UsageError("optimize: --measure must be shape or oddy, got '" + o.measure + "'");
  if (o.quadrature != "default" && o.quadrature != "thesis")
    throw UsageError("optimize: --quadrature must be default or thesis, got '" + o.quadrature + "'");
  try {
    hom::parse_ideal_kind(o.ideal);
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("optimize: ") + e.what());
  }
  if (o.scope != "invalid" && o.scope != "whole-mesh")
    throw UsageError("optimize: --scope must be invalid or whole-mesh, got '" + o.scope + "'");
  if (o.threads < 0) throw UsageError("optimize: --threads must be >= 0 (0: OpenMP's default)");
  if (o.max_iterations < 1) throw UsageError("optimize: --max-iterations must be >= 1");
  o.certify.check("optimize");
  if (!o.vtu.empty() && !hom::tools::ends_with(o.vtu, ".vtu")) throw UsageError("optimize: --vtu file name must end in .vtu");
  if (!o.cad.empty()) {
    // On a CAD model every element is measured against its straight-sided
    // counterpart with the default quadrature (hom::cad::optimize_on_cad).
    auto refuse = [&](bool given, const char* what) {
      if (given) throw UsageError(std::string("optimize: ") + what + " is not available with --cad");
    };
    refuse(o.ideal != "straight", "--ideal equilateral");
    refuse(o.quadrature != "default", "--quadrature thesis");
    refuse(o.scope != "invalid", "--scope whole-mesh");
    refuse(o.vertex_continuation, "--vertex-continuation");
    if (!(o.tolerance > 0)) throw UsageError("optimize: --tolerance must be positive");
    if (!(o.merge_small_edges >= 0)) throw UsageError("optimize: --merge-small-edges must be >= 0 (0: off)");
  } else if (o.merge_small_edges != 0) {
    throw UsageError("optimize: --merge-small-edges heals a --cad model; there is none");
  }
  if (o.vtu == o.out || (!o.json.empty() && (o.json == o.out || o.json == o.vtu)))
    throw UsageError("optimize: -o, --vtu and --json must name different files");
}

int run(int argc, char** argv) {
  OptimizeCli o;
  po::options_description opts(
      "hom optimize IN.msh -o OUT.msh [options]\n\n"
      "Smooth and untangle a curved high-order mesh whose boundary is already curved (thesis\n"
      "chapter 4): the interior nodes move to minimize the regularized distortion of eq 4.10\n"
      "against the ideal mesh; the boundary stays as it is. Nodes the file puts on a geometric\n"
      "point, curve or surface, and any node on the mesh's boundary (files without boundary\n"
      "elements or entities), are fixed; the other nodes move. OUT.msh is written in IN's MSH\n"
      "version and encoding.\n"
      "With --cad MODEL the mesh is classified on the model and optimized on it (chapters 5-6):\n"
      "nodes on CAD faces slide on their surfaces, nodes on CAD edges stay, interior nodes move.\n"
      "This is how surface meshes (2D elements in 3D) are optimized; the result is written only\n"
      "when it is valid and every boundary node lies on the CAD.\n"
      "Exit status: 0 the result is valid, 3 some elements are still inverted (with --certify:\n"
      "or not certified valid; outputs are written anyway), 1 unreadable input, 2 bad options.\n\noptions");
  opts.add_options()("help,h", "show this help")                                               //
      ("output,o", po::value(&o.out), "optimized mesh (.msh)")                                 //
      ("solver", po::value(&o.solver)->default_value("auto"),
       "newton | matrix-free | gauss-seidel | auto (newton up to 20000 free coordinates, matrix-free above)")  //
      ("pcont", po::bool_switch(&o.pcont), "p-continuation (appendix C): untangle the linear sub-mesh first")  //
      ("vertex-continuation", po::bool_switch(&o.vertex_continuation),
       "untangle the mesh of element vertices first and place the free high-order nodes straight-sided on it "
       "(large boundary motions)")  //
      ("scope", po::value(&o.scope)->default_value("invalid"),
       "elements regularized while the mesh is invalid: invalid (section 4.2.2) | whole-mesh (more robust on "
       "heavy tangles)")  //
      ("ideal", po::value(&o.ideal)->default_value("straight"),
       "ideal element: straight (each element's straight-sided counterpart) | equilateral")  //
      ("measure", po::value(&o.measure)->default_value("shape"), "distortion measure: shape | oddy")  //
      ("quadrature", po::value(&o.quadrature)->default_value("default"),
       "quadrature: default | thesis (exact to degree 6p-3)")                                       //
      ("threads", po::value(&o.threads)->default_value(0), "threads (0: OpenMP's default)")       //
      ("max-iterations", po::value(&o.max_iterations)->default_value(200), "iteration limit per stage")  //
      ("cad", po::value(&o.cad), "CAD model (.step, .iges, .brep) the mesh lies on: optimize on it")  //
      ("tolerance", po::value(&o.tolerance)->default_value(1e-6),
       "--cad: classification tolerance, relative to the model's size")                       //
      ("merge-small-edges", po::value(&o.merge_small_edges)->default_value(0.0),
       "--cad: heal the model as hom curve --merge-small-edges L did (CAD edges shorter than L dropped), so that "
       "the mesh's entity tags are the model's (0: off)")  //
      ("json", po::value(&o.json), "write the statistics before and after as JSON")               //
      ("vtu", po::value(&o.vtu), "write the optimized mesh colored by quality (ParaView)")        //
      ("verbose,v", po::bool_switch(&o.verbose), "one progress line per iteration (stderr)");
  o.certify.declare(opts,
                    "certification as the final acceptance test: certify the sign of det everywhere in each element "
                    "(Bernstein bounds) and keep optimizing elements that fold between quadrature points");
  po::variables_map vm;
  if (!hom::tools::parse_options("optimize", argc, argv, opts, {{"input", po::value(&o.in)}}, vm)) return 0;
  check_options(o);
  if (!o.cad.empty()) {
#ifdef HOM_HAVE_CURVE
    return optimize_on_cad(o);
#else
    throw hom::tools::UsageError("optimize: --cad needs hom built with OpenCASCADE and Gmsh (src/cad, src/curve)");
#endif
  }

  const auto data = hom::io::read_msh_data(o.in);
  return hom::tools::with_mesh<hom::WarpBlend>(data, [&](auto& mesh) -> int {
    using M = std::decay_t<decltype(mesh)>;
    if constexpr (M::space_dim != M::dim) {
      throw hom::tools::UsageError("optimize: " + o.in +
                                   " is a surface mesh (2D elements in 3D): its nodes slide on a surface, so give "
                                   "the surface with --cad MODEL.step|.iges|.brep");
    } else {
      if (o.measure == "oddy") return with_quadrature(mesh, hom::OddyMeasure{}, o, data);
      return with_quadrature(mesh, hom::ShapeMeasure{}, o, data);
    }
  });
}

const hom::tools::RegisterCommand reg{{"optimize", "Smooth and untangle a curved high-order mesh (chapter 4)", run}};

}  // namespace
