/// @file bench_untangle.cpp
/// Reproduction of table 4.1 (thesis section 4.3.1, figure 4.7): untangling
/// curved high-order tetrahedral meshes of a cube of side 5 with a centred
/// spherical cavity of diameter 1, at degrees 2, 5 and 10.
///
/// Pipeline, per degree p:
///   1. linear mesh: Gmsh (OpenCASCADE box minus sphere), deterministic,
///      about 1441 tetrahedra (src/meshing/cube_with_cavity.hpp);
///   2. elevate to degree p (warp & blend nodes); the ideal is this
///      straight-sided elevated mesh (section 3.1.2);
///   3. curve the boundary: nodes of the sphere and of the six planes onto
///      their exact geometry (closest point, geometry/curve_boundary.hpp);
///   4. perturb every free (interior) node by a random vector, uniform in the
///      ball of radius  a * h_i,  h_i = the shortest straight-sided edge of the
///      elements that contain node i, a = --perturb (seeded, reproducible);
///   5. statistics of the shape quality (table 4.1 form: Min, Max, Mean,
///      Std.Dev., #inv), then optimize (chapter 4), statistics again, time,
///      iterations, peak memory, solver.
///
/// Default perturbation amplitudes a, chosen so that the number of inverted
/// elements after step 4 comes close to the thesis's (373, 1333, 1439 of
/// 1441 at p = 2, 5, 10); see `default_perturbation`. The thesis does not say
/// how it perturbed, so only the counts are matched.
///
/// Peer (--peer gmsh): the same perturbed mesh goes through Gmsh's high-order
/// optimizer (Mesh.HighOrderOptimize = --peer-mode) in a child process under
/// --peer-timeout (src/meshing/gmsh_peer.hpp); hom's quality of its result is
/// printed as a "gmsh" row beside hom's and stored as the case's "peer".
/// --peer-mode takes a list (2,3,4): each mode runs on the same input after
/// one hom run, so a slow degree (p = 10) is optimized by hom once; the first
/// mode's entry is the case's "peer", every mode's the case's "peers".
/// Off by default: Gmsh 4.8.4 needs minutes to hours on this case.
///
/// Output: the table beside the thesis's rows on stdout; CSV (untangle.csv)
/// and VTU files (point data: point-wise quality, the minimum over the
/// elements sharing a node; cell data: element quality, scaled Jacobian) in
/// --out; the JSON report of DESIGN.md in --json (default OUT/untangle.json).
/// Figure 4.7: for each degree, the cut of the initial, optimized (and Gmsh's)
/// curved mesh by the plane z through the cavity's centre
/// (untangle_pP_<stage>_cut.csv, bench/mesh_cut.hpp: the elements' degree-p
/// maps, not their vertices), drawn side by side as untangle_pP_cut.png by
/// bench/plot_cut.py (skipped with a message without /usr/bin/python3 and
/// matplotlib; --no-cut writes neither).
/// Exit status: 0 when every optimized mesh is valid, 1 if one keeps inverted
/// elements, 2 on bad options or errors.

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <boost/program_options.hpp>

#include "cube_with_cavity.hpp"
#include "gmsh_peer.hpp"
#include "gmsh_peer_report.hpp"
#include "harness.hpp"
#include "mesh_cut.hpp"
#include "plot_script.hpp"
#include "hom/geometry/curve_boundary.hpp"
#include "hom/io/report.hpp"
#include "hom/io/vtu.hpp"
#include "hom/measure/shape_measure.hpp"
#include "hom/mesh/elevate.hpp"
#include "hom/quadrature/quadrature_policy.hpp"
#include "hom/quality/mesh_quality.hpp"

#if __has_include("hom/optimize/optimize.hpp")
#include "hom/optimize/optimize.hpp"
#define HOM_HAVE_OPTIMIZER 1
#else
#define HOM_HAVE_OPTIMIZER 0
#endif

#ifndef HOM_VERSION
#define HOM_VERSION "unknown"
#endif
#ifndef HOM_PLOT_SCRIPT
#define HOM_PLOT_SCRIPT "bench/plot_cut.py"
#endif

namespace fs = std::filesystem;
using hom::io::Json;
using Tet = hom::Simplex<3>;
using TetMesh = hom::Mesh<Tet>;

namespace {

// ---------------------------------------------------------------------------
// The thesis's numbers (table 4.1 and its caption).

using Row = hom::bench::ThesisRow;

struct ThesisCase {
  int p;
  int elements;
  int nodes;
  Row initial;
  Row smoothed;
};

constexpr ThesisCase thesis_cases[] = {
    {2, 1441, 2327, {0.00, 0.98, 0.53, 0.35, 373}, {0.96, 1.00, 1.00, 0.01, 0}},
    {5, 1441, 32382, {0.00, 0.72, 0.03, 0.11, 1333}, {0.97, 1.00, 1.00, 0.00, 0}},
    {10, 1441, 249387, {0.00, 0.21, 0.00, 0.01, 1439}, {0.96, 1.00, 1.00, 0.01, 0}},
};

const ThesisCase* thesis_case(int p) { return hom::bench::thesis_entry(thesis_cases, p); }

Json row_json(const Row& r, int elements, int nodes) {
  Json j = hom::bench::thesis_row_json(r);
  j.set("elements", elements).set("nodes", nodes);
  return j;
}

/// Relative perturbation amplitude a (step 4 of the file comment) per degree,
/// calibrated on the default mesh (1436 tetrahedra, Gmsh 4.8.4) with seed 1
/// and the default quadrature so that the inverted counts come close to the
/// thesis's:
///
///     p    a        inverted (hom, of 1436)   thesis (of 1441)
///     2    0.355    373                       373
///     5    0.0685   1336                      1333
///     10   0.0102   ~1434                     1439
///
/// The node spacing of a degree-p element is about h / p, and curving alone
/// already inverts 135 elements at p = 10 (the sphere's nodes move by up to
/// 0.028, more than the spacing 0.02 of its small elements), so much smaller
/// amplitudes tangle the higher degrees. Between calibrated degrees a is
/// interpolated geometrically; outside, the nearest value is used.
double default_perturbation(int p) {
  return hom::bench::interpolate_geometric({{2, 0.355}, {5, 0.0685}, {10, 0.0102}}, p);
}

using hom::bench::fmt;
using hom::bench::peak_rss_mb;
using hom::bench::perturb_free_nodes;
using hom::bench::seconds_since;

struct Stage {
  std::string name;
  hom::Statistics quality;
  hom::Statistics scaled_jacobian;
  double time_s = 0.0;
  int iterations = 0;
  double peak_rss_mb = 0.0;
  std::string solver;
  std::string stop_reason;
  double time_to_valid_s = -1.0;    ///< optimize() start to the first valid high-order iterate (-1: never)
  double time_to_quality_s = -1.0;  ///< ... to the first valid one with min quality >= 0.96
};

/// The rule the optimizer integrates eq 4.10 with. Statistics and validity
/// are always evaluated with the default rule (thesis: the thesis's rule), so
/// a mesh optimized with the reduced rule is judged by the richer one.
enum class Quadrature { default_rule, thesis, reduced };

std::string_view quadrature_name(Quadrature q) {
  return q == Quadrature::thesis ? "thesis" : q == Quadrature::reduced ? "reduced" : "default";
}

const hom::QuadratureRule<3>& rule_for(int p, Quadrature q) {
  return q == Quadrature::thesis ? hom::quadrature_for<Tet, hom::ThesisExactness>(p)
                                 : hom::quadrature_for<Tet, hom::DefaultExactness>(p);
}

hom::MeshQuality evaluate(const TetMesh& mesh, Quadrature q) {
  return hom::mesh_quality(mesh, hom::ShapeMeasure{}, hom::IdealKind::straight_sided, rule_for(mesh.degree(), q));
}

Stage make_stage(const std::string& name, const hom::MeshQuality& mq) {
  Stage s;
  s.name = name;
  s.quality = mq.quality_statistics();
  s.scaled_jacobian = mq.scaled_jacobian_statistics();
  s.peak_rss_mb = peak_rss_mb();
  return s;
}

void write_vtu(const fs::path& path, const TetMesh& mesh, const hom::MeshQuality& mq, Quadrature q) {
  const auto nodal = hom::nodal_mesh_quality(mesh, hom::ShapeMeasure{}, hom::IdealKind::straight_sided,
                                             rule_for(mesh.degree(), q));
  hom::io::write_vtu(path.string(), mesh, {{"quality", 1, nodal}},
                     {{"quality", 1, mq.qualities()}, {"scaled_jacobian", 1, mq.scaled_jacobians()}});
}



void print_row(const std::string& label, const hom::Statistics& s, const Row* thesis) {
  std::printf("  %-10s %6s %6s %6s %9s %6d", label.c_str(), fmt(s.min).c_str(), fmt(s.max).c_str(),
              fmt(s.mean).c_str(), fmt(s.std_dev).c_str(), s.inverted);
  if (thesis)
    std::printf("   | %6s %6s %6s %9s %6d", fmt(thesis->min).c_str(), fmt(thesis->max).c_str(),
                fmt(thesis->mean).c_str(), fmt(thesis->std_dev).c_str(), thesis->inverted);
  std::printf("\n");
}

struct Options {
  std::vector<int> degrees;
  std::string solver = "matrix-free";
  int threads = 0;
  bool pcont = false;
  std::string scope = "invalid";  ///< RegularizationScope: invalid | whole-mesh
  std::uint64_t seed = 1;
  std::optional<double> perturb;
  Quadrature quadrature = Quadrature::default_rule;
  fs::path out = "results/untangle";
  std::optional<fs::path> json;
  bool quick = false;
  bool vtu = true;
  bool cut = true;  ///< figure 4.7's cuts (file comment)
  bool verbose = false;
  bool optimize = true;
  int max_iterations = 200;
  hom::HessianForm hessian = hom::HessianForm::gauss_newton;
  int linear_after_valid = 3;
  double target_quality = 0.0;
  std::string peer = "none";   ///< --peer: none | gmsh
  double peer_timeout = 600;   ///< --peer-timeout, seconds
  std::vector<int> peer_modes = {1};  ///< --peer-mode: Mesh.HighOrderOptimize, one run per mode
};

/// OUT/untangle_pP_<stage>.vtu and OUT/untangle_pP_<stage>_cut.csv, as
/// --no-vtu and --no-cut allow.
void write_stage_files(const Options& o, int p, const std::string& stage, const TetMesh& mesh,
                       const hom::MeshQuality& mq) {
  const std::string name = "untangle_p" + std::to_string(p) + "_" + stage;
  if (o.vtu) write_vtu(o.out / (name + ".vtu"), mesh, mq, o.quadrature);
  if (o.cut) hom::bench::write_mid_z_cut_csv((o.out / (name + "_cut.csv")).string(), mesh, mq);
}

// ---------------------------------------------------------------------------
// Peer: Gmsh's high-order optimizer on the same perturbed input, in a child
// process under --peer-timeout (src/meshing/gmsh_peer.hpp), judged with the
// same hom quality call as hom's rows.

struct PeerRow {
  hom::meshing::PeerResult run;  ///< status, times, version (its mesh is dropped)
  Stage stage;                   ///< hom's statistics of Gmsh's result (when run.finished)
  double time_limit_s = 0.0;
};

/// Gmsh's result's files are named after stage "gmsh" for the first mode
/// (figure 4.7's cut shows it), "gmsh_modeM" for the others.
PeerRow run_peer(const TetMesh& perturbed, int p, int mode, const Options& o) {
  hom::meshing::GmshPeerOptions po;
  po.mode = mode;
  po.time_limit_s = o.peer_timeout;
  po.threads = o.threads;
  std::printf("p = %d: gmsh peer (Mesh.HighOrderOptimize = %d, limit %.0f s) ...\n", p, mode, o.peer_timeout);
  std::fflush(stdout);
  PeerRow row;
  row.time_limit_s = o.peer_timeout;
  row.run = hom::meshing::gmsh_high_order_optimize(perturbed, po);
  if (row.run.finished) {
    const auto q = evaluate(row.run.mesh, o.quadrature);
    row.stage = make_stage("gmsh", q);
    row.stage.time_s = row.run.time_s;
    const bool first_mode = mode == o.peer_modes.front();
    write_stage_files(o, p, first_mode ? "gmsh" : "gmsh_mode" + std::to_string(mode), row.run.mesh, q);
  }
  row.run.mesh = TetMesh();
  return row;
}

std::string peer_label(const PeerRow& r) { return hom::bench::gmsh_peer_label(r.run); }

void print_peer(const PeerRow& r) {
  if (r.run.finished) print_row("gmsh", r.stage.quality, nullptr);
  hom::bench::print_gmsh_peer_status(r.run, r.time_limit_s, r.stage.scaled_jacobian.min);
}

Json peer_json(const PeerRow& r) {
  return hom::bench::gmsh_peer_json(r.run, r.time_limit_s, r.stage.quality, r.stage.scaled_jacobian);
}

/// The peer's CSV row (stage "gmsh"; the solver column names the tool and
/// its status; quality columns empty unless it finished).
std::string peer_csv(const PeerRow& r, int p, int elements, int nodes, double perturbation, std::uint64_t seed,
                     std::string_view quadrature) {
  std::ostringstream c;
  c << p << ",gmsh," << elements << ',' << nodes << ',';
  if (r.run.finished)
    c << r.stage.quality.min << ',' << r.stage.quality.max << ',' << r.stage.quality.mean << ','
      << r.stage.quality.std_dev << ',' << r.stage.quality.inverted << ',' << r.stage.scaled_jacobian.min << ',';
  else
    c << ",,,,,,";
  c << r.run.time_s << ",," << r.run.peak_rss_mb << ",\"" << peer_label(r) << ": " << r.run.status << "\"," << perturbation
    << ',' << seed << ',' << quadrature << ",,,,,\n";
  return c.str();
}

struct CaseResult {
  int p = 0;
  int elements = 0;
  int nodes = 0;
  double perturbation = 0.0;
  std::vector<Stage> stages;
  bool valid_at_end = false;
  bool optimized = false;
  std::vector<PeerRow> peers;  ///< one per --peer-mode, in its order
};

CaseResult run_case(const TetMesh& linear, const hom::GeometryModel<3>& geometry, int p, const Options& o) {
  CaseResult r;
  r.p = p;
  const auto t_setup = std::chrono::steady_clock::now();
  TetMesh mesh = hom::elevate(linear, p);
  const auto curving = hom::curve_boundary(mesh, geometry);
  r.elements = mesh.num_elements();
  r.nodes = mesh.num_nodes();
  r.perturbation = o.perturb.value_or(default_perturbation(p));
  const double setup_s = seconds_since(t_setup);

  const auto t_curved = std::chrono::steady_clock::now();
  const auto curved = evaluate(mesh, o.quadrature);
  r.stages.push_back(make_stage("curved", curved));
  r.stages.back().time_s = seconds_since(t_curved);

  const int moved = perturb_free_nodes(mesh, r.perturbation, o.seed);
  const auto t_initial = std::chrono::steady_clock::now();
  const auto initial = evaluate(mesh, o.quadrature);
  r.stages.push_back(make_stage("initial", initial));
  r.stages.back().time_s = seconds_since(t_initial);
  std::printf("p = %d: %d elements, %d nodes (%d free, perturbed by a = %.3g x shortest incident edge, seed %llu); "
              "%d boundary nodes curved (max move %.3g); setup %.2f s\n",
              p, r.elements, r.nodes, moved, r.perturbation, static_cast<unsigned long long>(o.seed),
              curving.curve_nodes + curving.surface_nodes, curving.max_displacement, setup_s);
  std::fflush(stdout);
  write_stage_files(o, p, "initial", mesh, initial);

  if (!o.optimize) return r;
  std::optional<TetMesh> peer_input;  // the perturbed mesh, for the peer (hom optimizes `mesh` in place)
  if (o.peer != "none") peer_input = mesh;
#if HOM_HAVE_OPTIMIZER
  hom::OptimizeOptions opt;
  const std::string& solver = o.solver;
  opt.solver = hom::parse_solver_kind(solver);
  opt.p_continuation = o.pcont;
  opt.regularization_scope = hom::parse_regularization_scope(o.scope);
  opt.threads = o.threads;
  opt.max_iterations = o.max_iterations;
  opt.verbose = o.verbose;
  opt.hessian = o.hessian;
  opt.continuation_iterations_after_valid = o.linear_after_valid;
  opt.target_quality = o.target_quality;
  // Time to the table's targets (valid; valid with min quality >= 0.96), from
  // the high-order stage's progress reports.
  const auto t_opt = std::chrono::steady_clock::now();
  double to_valid = -1.0, to_096 = -1.0;
  opt.on_iteration = [&](const hom::IterationInfo& it) {
    if (it.stage != "high-order") return;
    if (it.inverted == 0 && to_valid < 0) to_valid = seconds_since(t_opt);
    if (it.inverted == 0 && it.min_quality >= 0.96 && to_096 < 0) to_096 = seconds_since(t_opt);
  };
  const auto result = o.quadrature == Quadrature::thesis    ? hom::optimize<hom::ShapeMeasure, hom::ThesisExactness>(mesh, opt)
                      : o.quadrature == Quadrature::reduced ? hom::optimize<hom::ShapeMeasure, hom::ReducedExactness>(mesh, opt)
                                                            : hom::optimize<hom::ShapeMeasure, hom::DefaultExactness>(mesh, opt);
  const auto final_quality = evaluate(mesh, o.quadrature);
  Stage s = make_stage("optimized", final_quality);
  s.time_s = result.time_s;
  s.iterations = result.result.iterations + (result.continuation ? result.continuation->iterations : 0);
  s.solver = std::string(hom::to_string(opt.solver)) + (result.continuation ? " + p-continuation" : "");
  s.stop_reason = std::string(hom::to_string(result.result.reason));
  s.time_to_valid_s = to_valid;
  s.time_to_quality_s = to_096;
  r.stages.push_back(s);
  r.optimized = true;
  r.valid_at_end = final_quality.inverted() == 0;
  write_stage_files(o, p, "optimized", mesh, final_quality);
#else
  std::printf("p = %d: the optimizer (hom/optimize/optimize.hpp) is not available in this build; "
              "stopping after the initial statistics.\n",
              p);
#endif
  if (peer_input)
    for (int mode : o.peer_modes) r.peers.push_back(run_peer(*peer_input, p, mode, o));
  return r;
}

void print_case(const CaseResult& r) {
  const ThesisCase* t = thesis_case(r.p);
  std::printf("\nTable 4.1, p = %d: %d elements, %d nodes", r.p, r.elements, r.nodes);
  if (t) std::printf(" (thesis: %d elements, %d nodes)", t->elements, t->nodes);
  std::printf("\n  %-10s %6s %6s %6s %9s %6s", "mesh", "Min", "Max", "Mean", "Std.Dev.", "#inv");
  if (t) std::printf("   | %6s %6s %6s %9s %6s  (thesis)", "Min", "Max", "Mean", "Std.Dev.", "#inv");
  std::printf("\n");
  for (const auto& s : r.stages) {
    const Row* tr = nullptr;
    if (t && s.name == "initial") tr = &t->initial;
    if (t && s.name == "optimized") tr = &t->smoothed;
    print_row(s.name == "optimized" ? "smoothed" : s.name, s.quality, tr);
  }
  for (const auto& peer : r.peers) print_peer(peer);
  for (const auto& s : r.stages)
    if (s.name == "optimized")
      std::printf("  solver %s, %d iterations (%s), %.2f s (valid after %s s, min quality >= 0.96 after %s s), "
                  "min scaled Jacobian %.3f, peak RSS %.0f MB\n",
                  s.solver.c_str(), s.iterations, s.stop_reason.c_str(), s.time_s, fmt(s.time_to_valid_s >= 0 ? s.time_to_valid_s : NAN).c_str(),
                  fmt(s.time_to_quality_s >= 0 ? s.time_to_quality_s : NAN).c_str(), s.scaled_jacobian.min, s.peak_rss_mb);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  namespace po = boost::program_options;
  Options o;
  std::string degrees, quadrature = "default", json, hessian, peer_modes = "1";
  std::uint64_t seed = 1;
  double perturb = 0.0;
  po::options_description desc(
      "bench_untangle: table 4.1 of the thesis (cube of side 5 with a spherical cavity of diameter 1,\n"
      "curved, randomly perturbed, untangled at degrees 2, 5, 10)");
  // clang-format off
  desc.add_options()
      ("help,h", "this message")
      ("p", po::value(&degrees), "degrees, comma-separated (default 2,5,10; with --quick 2,5)")
      ("solver", po::value(&o.solver)->default_value("matrix-free"),
       "newton | matrix-free | gauss-seidel (matrix-free by default: at p = 2 the assembled Newton "
       "took 93 iterations and 53 s to converge on this case, Newton-CG 27 iterations and 2.4 s)")
      ("threads", po::value(&o.threads)->default_value(0), "threads (0: OpenMP's default)")
      ("pcont", po::bool_switch(&o.pcont), "p-continuation (appendix C)")
      ("scope", po::value(&o.scope)->default_value("invalid"),
       "elements regularized while the mesh is invalid: invalid (section 4.2.2) | whole-mesh")
      ("seed", po::value(&seed)->default_value(1), "seed of the perturbation")
      ("perturb", po::value(&perturb),
       "perturbation amplitude a, relative to the shortest straight-sided edge of the elements containing each "
       "free node (default: per degree, calibrated to the thesis's inverted counts)")
      ("quadrature", po::value(&quadrature)->default_value("default"),
       "rule the optimizer integrates with: default (exactness deg det + 2) | thesis (6p - 3) | reduced (2p); "
       "statistics use the default rule (thesis: the thesis's)")
      ("hessian", po::value(&hessian)->default_value("gauss-newton"),
       "Newton model: gauss-newton (default here: a ninth of the projected model's memory and no per-point "
       "eigen-decomposition; it can stop on quality stagnation short of the optimum: at p = 10 from the unculled "
       "linear stage it stopped at 0.958 where the projected model went on to 0.9875) | projected (the library's "
       "default)")
      ("target-quality", po::value(&o.target_quality)->default_value(0.0),
       "stop once valid with min quality >= this (0: optimize to convergence)")
      ("linear-after-valid", po::value(&o.linear_after_valid)->default_value(3),
       "with --pcont: stop the linear stage this many iterations after its sub-mesh is valid (-1: converge it)")
      ("out", po::value(&o.out)->default_value("results/untangle"), "output directory (CSV, VTU, JSON)")
      ("json", po::value(&json), "JSON report (default OUT/untangle.json)")
      ("quick", po::bool_switch(&o.quick), "coarser linear mesh (CI); default degrees 2,5")
      ("no-vtu", "do not write VTU files")
      ("no-cut", "do not write the cuts of figure 4.7 (CSV, PNG)")
      ("no-optimize", "stop after the statistics of the perturbed mesh (for calibrating --perturb)")
      ("max-iterations", po::value(&o.max_iterations)->default_value(200), "optimizer iteration limit per stage")
      ("verbose,v", "optimizer progress, one line per iteration")
      ("peer", po::value(&o.peer)->default_value("none"),
       "none | gmsh: also run Gmsh's high-order optimizer on the same perturbed mesh (child process, "
       "--peer-timeout), judged by the same quality measure; its row is printed as 'gmsh', and goes to the "
       "CSV and to the JSON case of the optimized stage as \"peer\"")
      ("peer-timeout", po::value(&o.peer_timeout)->default_value(600), "wall-clock limit of the peer run, seconds")
      ("peer-mode", po::value(&peer_modes)->default_value("1"),
       "Gmsh's Mesh.HighOrderOptimize: 1 optimization, 2 elastic + optimization, 3 elastic, 4 fast curving; "
       "a list (2,3,4) runs each mode on the same input after one hom run");
  // clang-format on
  try {
    po::variables_map vm;
    po::store(po::parse_command_line(argc, argv, desc), vm);
    po::notify(vm);
    if (vm.count("help")) {
      std::cout << desc << "\n";
      return 0;
    }
    o.degrees = hom::bench::parse_int_list(degrees.empty() ? (o.quick ? "2,5" : "2,5,10") : degrees, "--p", 1, 20);
    o.peer_modes = hom::bench::parse_peer_modes(peer_modes);
    o.seed = seed;
    if (vm.count("perturb")) {
      if (!(perturb >= 0.0)) throw std::invalid_argument("--perturb must be >= 0");
      o.perturb = perturb;
    }
    if (quadrature == "thesis")
      o.quadrature = Quadrature::thesis;
    else if (quadrature == "reduced")
      o.quadrature = Quadrature::reduced;
    else if (quadrature != "default")
      throw std::invalid_argument("--quadrature: expected default, thesis or reduced, got '" + quadrature + "'");
    if (hessian == "gauss-newton")
      o.hessian = hom::HessianForm::gauss_newton;
    else if (hessian == "projected")
      o.hessian = hom::HessianForm::projected;
    else
      throw std::invalid_argument("--hessian: expected projected or gauss-newton, got '" + hessian + "'");
    if (o.solver != "newton" && o.solver != "matrix-free" && o.solver != "gauss-seidel")
      throw std::invalid_argument("--solver: expected newton, matrix-free, gauss-seidel or auto, got '" + o.solver + "'");
    if (!json.empty()) o.json = json;
    o.vtu = !vm.count("no-vtu");
    o.cut = !vm.count("no-cut");
    o.verbose = vm.count("verbose") > 0;
    o.optimize = !vm.count("no-optimize");
    (void)hom::parse_regularization_scope(o.scope);  // throws on an unknown name
    if (o.peer != "none" && o.peer != "gmsh") throw std::invalid_argument("--peer: expected none or gmsh, got '" + o.peer + "'");
    if (!(o.peer_timeout > 0)) throw std::invalid_argument("--peer-timeout must be positive");
  } catch (const std::exception& e) {
    std::cerr << "bench_untangle: " << e.what() << "\n";
    return 2;
  }
  const int threads = hom::bench::set_threads(o.threads);

  try {
    fs::create_directories(o.out);
    const auto t0 = std::chrono::steady_clock::now();
    hom::meshing::CubeWithCavityOptions mo;
    if (o.quick) {
      mo.cube_size = 2.0;
      mo.sphere_size = 0.3;
    }
    const auto model = hom::meshing::cube_with_cavity(mo);
    std::printf("bench_untangle %s: linear mesh %d tetrahedra, %d nodes (Gmsh, %.2f s; thesis: 1441 tetrahedra); "
                "quadrature %s; %d threads\n",
                HOM_VERSION, model.mesh.num_elements(), model.mesh.num_nodes(), seconds_since(t0),
                std::string(quadrature_name(o.quadrature)).c_str(), threads);
    std::fflush(stdout);

    std::vector<CaseResult> results;
    for (int p : o.degrees) {
      results.push_back(run_case(model.mesh, model.geometry, p, o));
      print_case(results.back());
      if (o.cut)
        hom::bench::run_plot_script(HOM_PLOT_SCRIPT, o.out,
                                    {"untangle_p" + std::to_string(p),
                                     "figure 4.7 analogue: cube with a spherical cavity, p = " + std::to_string(p) +
                                         ", cut z through the cavity's centre"},
                                    "matplotlib, numpy");
    }

    // CSV, one row per degree and stage.
    const std::string csv_path = (o.out / "untangle.csv").string();
    std::ostringstream csv;
    csv << "p,stage,elements,nodes,min_q,max_q,mean_q,std_q,inverted,min_scaled_jacobian,time_s,iterations,"
           "peak_rss_mb,solver,perturbation,seed,quadrature,thesis_min_q,thesis_max_q,thesis_mean_q,thesis_std_q,"
           "thesis_inverted\n";
    std::vector<Json> cases;
    for (const auto& r : results) {
      const ThesisCase* t = thesis_case(r.p);
      for (const auto& s : r.stages) {
        const Row* tr = !t ? nullptr : s.name == "initial" ? &t->initial : s.name == "optimized" ? &t->smoothed : nullptr;
        csv << r.p << ',' << s.name << ',' << r.elements << ',' << r.nodes << ',' << s.quality.min << ','
            << s.quality.max << ',' << s.quality.mean << ',' << s.quality.std_dev << ',' << s.quality.inverted << ','
            << s.scaled_jacobian.min << ',' << s.time_s << ',' << s.iterations << ',' << s.peak_rss_mb << ','
            << s.solver << ',' << r.perturbation << ',' << o.seed << ','
            << quadrature_name(o.quadrature);
        if (tr)
          csv << ',' << tr->min << ',' << tr->max << ',' << tr->mean << ',' << tr->std_dev << ',' << tr->inverted;
        else
          csv << ",,,,,";
        csv << '\n';

        hom::io::CaseHeader h{"cube_with_spherical_cavity", "tetrahedron", r.p, r.elements, r.nodes, s.name, "shape",
                              "straight-sided"};
        Json c = hom::io::quality_case(h, s.quality, s.scaled_jacobian);
        c.set("time_s", s.time_s)
            .set("iterations", s.iterations)
            .set("peak_rss_mb", s.peak_rss_mb)
            .set("solver", s.solver.empty() ? Json() : Json(s.solver))
            .set("stop_reason", s.stop_reason.empty() ? Json() : Json(s.stop_reason))
            .set("time_to_valid_s", s.time_to_valid_s >= 0 ? Json(s.time_to_valid_s) : Json())
            .set("time_to_quality_096_s", s.time_to_quality_s >= 0 ? Json(s.time_to_quality_s) : Json())
            .set("perturbation", r.perturbation)
            .set("seed", static_cast<long long>(o.seed))
            .set("quadrature", std::string(quadrature_name(o.quadrature)))
            .set("threads", threads)
            .set("p_continuation", o.pcont)
            .set("regularization_scope", o.scope)
            .set("thesis", tr ? row_json(*tr, t->elements, t->nodes) : Json())
            .set("peer", !r.peers.empty() && s.name == "optimized" ? peer_json(r.peers.front()) : Json());
        if (r.peers.size() > 1 && s.name == "optimized") {
          Json::Array peers;
          for (const auto& peer : r.peers) peers.push_back(peer_json(peer));
          c.set("peers", Json(std::move(peers)));
        }
        cases.push_back(std::move(c));
      }
      for (const auto& peer : r.peers)
        csv << peer_csv(peer, r.p, r.elements, r.nodes, r.perturbation, o.seed, quadrature_name(o.quadrature));
    }
    const std::string text = csv.str();
    hom::io::write_atomically(csv_path, [&](std::FILE* f) { hom::io::write_all(f, csv_path, text.data(), text.size()); });
    const fs::path json_path = o.json.value_or(o.out / "untangle.json");
    hom::io::write_report(json_path.string(), "bench_untangle", HOM_VERSION, std::move(cases));
    std::printf("\nwrote %s, %s%s\n", csv_path.c_str(), json_path.c_str(), o.vtu ? " and VTU files" : "");

    bool all_valid = true;
    for (const auto& r : results)
      if (r.optimized && !r.valid_at_end) all_valid = false;
    if (!all_valid) {
      std::fprintf(stderr, "bench_untangle: an optimized mesh still has inverted elements\n");
      return 1;
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_untangle: %s\n", e.what());
    return 2;
  }
}
