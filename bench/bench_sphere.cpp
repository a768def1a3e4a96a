/// @file bench_sphere.cpp
/// Reproduction of tables 3.2 and 3.3 (thesis section 3.3.2.1, figures 3.7,
/// 3.8: a tangled hollow sphere smoothed, relative and absolute shape quality)
/// and of table D.4 (appendix D.3, figure D.5: a degree-4 hexahedral mesh with
/// every element inverted, untangled). The meshes are built analytically
/// (bench/sphere_mesh.hpp), no mesher needed.
///
/// Hollow sphere (inner radius 1, outer radius 3, 160 tetrahedra; the
/// thesis's node counts 302, 2042, 6502 at p = 2, 4, 6), per degree p:
///   1. elevate the linear mesh to degree p (warp & blend nodes); the ideal is
///      this straight-sided mesh (relative quality, section 3.1.2);
///   2. curve: boundary nodes radially onto the spheres (curve_boundary), the
///      free nodes with them (radial map of the polyhedral shell onto the
///      exact one, sphere_mesh.hpp): a valid curved mesh ("curved");
///   3. tangle: the thesis only says "we tangle them"; every free node moves
///      by a random vector of the ball of radius a * h_i (h_i: shortest
///      straight-sided edge of the elements containing node i; seeded), with a
///      per degree chosen so that the number of inverted elements comes close
///      to the thesis's 59, 16, 15 ("initial", figures 3.7(a-c));
///   4. smooth (chapter 4) against the straight-sided ideal ("smoothed",
///      figures 3.7(d-f)).
/// Statistics (Min, Max, Mean, Std.Dev., #inv of the element shape quality)
/// against the straight-sided ideal (table 3.2) and the regular tetrahedron
/// (IdealKind::regular, table 3.3), for every stage.
///
/// Table D.4: the thesis's CAD part is not described; here a 270-degree thick
/// ring (radii 1 and 2, height 1) of 2 x 17 x 2 = 68 hexahedra (the thesis's
/// count), degree 4, boundary curved onto its cylinders, every free node
/// perturbed (a = --hex-perturb, default 0.35; all 68 inverted), untangled.
/// Rows: ideal (the straight-sided mesh), curved, initial, smoothed.
///
/// Claim checks (exit status 0 only if all hold and every optimized mesh is
/// valid), from the thesis's text:
///   sphere, each p: the tangled mesh has inverted elements; the smoothed mesh
///     has none ("all the inverted elements have been untangled"); min and
///     mean relative quality improve ("the overall quality statistics
///     improved"); smoothed relative mean >= 0.95 ("almost all the elements
///     are of quality one"); the absolute measure flags the same invalid
///     elements as the relative one ("the absolute measure detects the same
///     invalid elements"); smoothed absolute mean below the relative mean
///     ("the obtained quality values are lower");
///   D.4: the ideal scores 1; all 68 elements inverted after the perturbation;
///     smoothed mesh valid with minimum quality >= 0.96 (the table).
///
/// Output: tables beside the thesis's on stdout; --out gets sphere.csv, VTU
/// files (point data: point-wise quality, the minimum over the elements
/// sharing a node, relative and absolute; cell data: element qualities and
/// scaled Jacobian) and the JSON report of DESIGN.md (--json, default
/// OUT/sphere.json) with "thesis" entries. Exit: 0 all good, 1 a check
/// failed, 2 bad options or errors.


#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <boost/program_options.hpp>

#include "hom/io/report.hpp"
#include "hom/io/vtu.hpp"
#include "hom/measure/shape_measure.hpp"
#include "hom/optimize/optimize.hpp"
#include "hom/quality/mesh_quality.hpp"
#include "harness.hpp"
#include "sphere_mesh.hpp"

#ifndef HOM_VERSION
#define HOM_VERSION "unknown"
#endif

namespace fs = std::filesystem;
using hom::io::Json;
using hom::bench::HexMesh;
using hom::bench::TetMesh;

namespace {

// ---------------------------------------------------------------------------
// The thesis's numbers.

using Row = hom::bench::ThesisRow;

struct ThesisSphere {
  int p;
  int nodes;
  Row relative_initial, relative_smoothed;  // table 3.2
  Row absolute_initial, absolute_smoothed;  // table 3.3
};

constexpr ThesisSphere thesis_sphere[] = {
    {2, 302, {0.00, 0.97, 0.51, 0.40, 59}, {0.91, 0.99, 0.98, 0.02, 0}, {0.00, 0.92, 0.46, 0.36, 59},
     {0.57, 0.97, 0.77, 0.11, 0}},
    {4, 2042, {0.00, 0.97, 0.81, 0.28, 16}, {0.95, 1.00, 0.99, 0.01, 0}, {0.00, 0.95, 0.74, 0.19, 16},
     {0.65, 0.97, 0.81, 0.09, 0}},
    {6, 6502, {0.00, 0.96, 0.81, 0.27, 15}, {0.95, 1.00, 0.99, 0.01, 0}, {0.00, 0.92, 0.69, 0.24, 15},
     {0.64, 0.98, 0.81, 0.09, 0}},
};
constexpr int thesis_sphere_elements = 160;

const ThesisSphere* thesis_sphere_case(int p) { return hom::bench::thesis_entry(thesis_sphere, p); }

// Table D.4 (degree 4, 68 hexahedra; the thesis gives no node count).
constexpr int thesis_hex_p = 4;
constexpr int thesis_hex_elements = 68;
constexpr Row thesis_hex_ideal{1.00, 1.00, 1.00, 0.00, 0};
constexpr Row thesis_hex_initial{0.00, 0.00, 0.00, 0.00, 68};
constexpr Row thesis_hex_smoothed{0.96, 1.00, 0.99, 0.005, 0};
constexpr double thesis_hex_min_quality = 0.96;

Json row_json(const Row& r, int elements, std::optional<int> nodes) {
  Json j = hom::bench::thesis_row_json(r);
  j.set("elements", elements).set("nodes", nodes ? Json(*nodes) : Json());
  return j;
}

/// Tangling amplitude a per degree (seed 1, default quadrature), chosen so
/// that the inverted counts match the thesis's (bench_sphere --no-optimize
/// --case sphere --p P --perturb A):
///
///     p   a        inverted   mean relative q    thesis: inverted, mean q
///     2   0.462    59         0.44               59, 0.51
///     4   0.063    16         0.81               16, 0.81
///     6   0.0245   15         0.85               15, 0.81
///
/// The counts are steep in a (p = 4: 12 at 0.06, 22 at 0.065), so another
/// seed gives other counts. The node spacing of a degree-p element is about
/// h / p, so higher degrees tangle with smaller amplitudes. Between these
/// degrees a is interpolated geometrically; outside, the nearest value is used.
double default_sphere_perturbation(int p) {
  return hom::bench::interpolate_geometric({{2, 0.462}, {4, 0.063}, {6, 0.0245}}, p);
}

/// Table D.4: 0.2 already inverts all 68 elements (0.15: 67); 0.35 leaves a margin.
constexpr double default_hex_perturbation = 0.35;

// ---------------------------------------------------------------------------

using hom::bench::fmt;
using hom::bench::peak_rss_mb;
using hom::bench::seconds_since;

struct Options {
  std::vector<int> degrees;
  std::string solver = "newton";
  int threads = 0;
  bool pcont = false;
  std::uint64_t seed = 1;
  std::optional<double> perturb;
  double hex_perturb = default_hex_perturbation;
  fs::path out = "results/sphere";
  std::optional<fs::path> json;
  bool quick = false;
  bool vtu = true;
  bool verbose = false;
  bool optimize = true;
  bool run_sphere = true;
  bool run_hex = true;
  int max_iterations = 200;
};

/// One row: the statistics of a mesh at one stage, against one or two ideals.
struct Stage {
  std::string name;  // curved, initial, smoothed, ideal
  hom::Statistics relative, relative_sj;
  std::optional<hom::Statistics> absolute;
  std::vector<bool> relative_invalid, absolute_invalid;
  double time_s = 0.0;
  int iterations = 0;
  std::string solver, stop_reason;
  double peak_rss_mb = 0.0;
};

template <class MeshT>
Stage evaluate(const std::string& name, const MeshT& mesh, bool absolute) {
  Stage s;
  s.name = name;
  const auto rel = hom::mesh_quality(mesh, hom::ShapeMeasure{}, hom::IdealKind::straight_sided);
  s.relative = rel.quality_statistics();
  s.relative_sj = rel.scaled_jacobian_statistics();
  s.relative_invalid = rel.invalid();
  if (absolute) {
    const auto abs = hom::mesh_quality(mesh, hom::ShapeMeasure{}, hom::IdealKind::regular);
    s.absolute = abs.quality_statistics();
    s.absolute_invalid = abs.invalid();
  }
  s.peak_rss_mb = peak_rss_mb();
  return s;
}

template <class MeshT>
void write_vtu(const fs::path& path, const MeshT& mesh, bool absolute) {
  const auto& rule = hom::quadrature_for<typename MeshT::family, hom::DefaultExactness>(mesh.degree());
  const auto rel = hom::mesh_quality(mesh, hom::ShapeMeasure{}, hom::IdealKind::straight_sided, rule);
  std::vector<hom::io::VtuField> point{
      {"quality_relative", 1, hom::nodal_mesh_quality(mesh, hom::ShapeMeasure{}, hom::IdealKind::straight_sided, rule)}};
  std::vector<hom::io::VtuField> cell{{"quality_relative", 1, rel.qualities()},
                                      {"scaled_jacobian", 1, rel.scaled_jacobians()}};
  if (absolute) {
    const auto abs = hom::mesh_quality(mesh, hom::ShapeMeasure{}, hom::IdealKind::regular, rule);
    point.push_back({"quality_absolute", 1, hom::nodal_mesh_quality(mesh, hom::ShapeMeasure{}, hom::IdealKind::regular, rule)});
    cell.push_back({"quality_absolute", 1, abs.qualities()});
  }
  hom::io::write_vtu(path.string(), mesh, point, cell);
}

/// Optimizes against the straight-sided ideal; fills the stage's run data.
template <class MeshT>
void smooth(MeshT& mesh, const Options& o, Stage& s) {
  hom::OptimizeOptions opt;
  opt.solver = hom::parse_solver_kind(o.solver);
  opt.p_continuation = o.pcont;
  opt.threads = o.threads;
  opt.max_iterations = o.max_iterations;
  opt.verbose = o.verbose;
  opt.ideal = hom::IdealKind::straight_sided;
  const auto r = hom::optimize(mesh, opt);
  s.time_s = r.time_s;
  s.iterations = r.result.iterations + (r.continuation ? r.continuation->iterations : 0);
  s.solver = std::string(hom::to_string(opt.solver)) + (r.continuation ? " + p-continuation" : "");
  s.stop_reason = std::string(hom::to_string(r.result.reason));
}

struct Check {
  std::string claim;
  bool passed;
  std::string detail;
};

struct CaseResult {
  std::string name;    // hollow_sphere, hex_ring
  std::string family;  // tetrahedron, hexahedron
  int p = 0;
  int elements = 0;
  int nodes = 0;
  int free_nodes = 0;
  double perturbation = 0.0;
  std::optional<int> boundary_only_inverted;  // sphere: curving the boundary nodes alone
  std::vector<Stage> stages;
  std::vector<Check> checks;
  bool optimized = false;
  bool valid_at_end = false;
};

const Stage* find_stage(const CaseResult& r, const std::string& name) {
  for (const auto& s : r.stages)
    if (s.name == name) return &s;
  return nullptr;
}

// ---------------------------------------------------------------------------

CaseResult run_sphere(const hom::bench::MeshWithGeometry<TetMesh>& linear, int p, const Options& o) {
  CaseResult r;
  r.name = "hollow_sphere";
  r.family = "tetrahedron";
  r.p = p;
  const auto t0 = std::chrono::steady_clock::now();
  TetMesh mesh = hom::bench::curved_hollow_sphere(linear, p);
  r.boundary_only_inverted =
      hom::mesh_quality(hom::bench::curved_mesh(linear, p), hom::ShapeMeasure{}).inverted();
  r.elements = mesh.num_elements();
  r.nodes = mesh.num_nodes();
  for (const auto& c : mesh.node_classes()) r.free_nodes += c.kind == hom::NodeKind::free;
  r.perturbation = o.perturb.value_or(default_sphere_perturbation(p));
  r.stages.push_back(evaluate("curved", mesh, true));
  r.stages.back().time_s = seconds_since(t0);

  hom::bench::perturb_free_nodes(mesh, r.perturbation, o.seed);
  r.stages.push_back(evaluate("initial", mesh, true));
  std::printf("hollow sphere p = %d: %d elements, %d nodes (%d free, perturbed by a = %.3g x shortest incident edge, "
              "seed %llu); curving only the boundary nodes would invert %d\n",
              p, r.elements, r.nodes, r.free_nodes, r.perturbation, static_cast<unsigned long long>(o.seed),
              *r.boundary_only_inverted);
  std::fflush(stdout);
  if (o.vtu) write_vtu(o.out / ("sphere_p" + std::to_string(p) + "_initial.vtu"), mesh, true);
  if (!o.optimize) return r;

  Stage s;
  smooth(mesh, o, s);
  Stage e = evaluate("smoothed", mesh, true);
  e.time_s = s.time_s;
  e.iterations = s.iterations;
  e.solver = s.solver;
  e.stop_reason = s.stop_reason;
  r.stages.push_back(e);
  r.optimized = true;
  r.valid_at_end = e.relative.inverted == 0;
  if (o.vtu) write_vtu(o.out / ("sphere_p" + std::to_string(p) + "_smoothed.vtu"), mesh, true);

  // Claim checks (file comment).
  const Stage& ini = r.stages[1];
  const std::string tag = "sphere p=" + std::to_string(p) + ": ";
  r.checks.push_back({tag + "tangled mesh has inverted elements", ini.relative.inverted > 0,
                      std::to_string(ini.relative.inverted) + " inverted"});
  r.checks.push_back({tag + "smoothed mesh valid (all inverted elements untangled)", e.relative.inverted == 0,
                      std::to_string(e.relative.inverted) + " inverted"});
  r.checks.push_back({tag + "smoothing improves min and mean relative quality",
                      e.relative.min > ini.relative.min && e.relative.mean > ini.relative.mean,
                      "min " + fmt(ini.relative.min) + " -> " + fmt(e.relative.min) + ", mean " +
                          fmt(ini.relative.mean) + " -> " + fmt(e.relative.mean)});
  r.checks.push_back({tag + "smoothed relative mean >= 0.95 (almost all elements of quality one)",
                      e.relative.mean >= 0.95, "mean " + fmt(e.relative.mean, 3)});
  r.checks.push_back({tag + "absolute measure flags the same invalid elements as the relative one",
                      ini.relative_invalid == ini.absolute_invalid && e.relative_invalid == e.absolute_invalid,
                      std::to_string(ini.absolute->inverted) + " / " + std::to_string(e.absolute->inverted) +
                          " inverted (initial / smoothed)"});
  r.checks.push_back({tag + "smoothed absolute mean below the relative mean", e.absolute->mean < e.relative.mean,
                      fmt(e.absolute->mean, 3) + " < " + fmt(e.relative.mean, 3)});
  return r;
}

CaseResult run_hex(const Options& o) {
  CaseResult r;
  r.name = "hex_ring";
  r.family = "hexahedron";
  r.p = thesis_hex_p;
  const auto ring = hom::bench::hex_ring();
  const HexMesh straight = hom::elevate(ring.mesh, r.p);
  r.stages.push_back(evaluate("ideal", straight, false));
  const auto t0 = std::chrono::steady_clock::now();
  HexMesh mesh = hom::bench::curved_mesh(ring, r.p);
  r.elements = mesh.num_elements();
  r.nodes = mesh.num_nodes();
  for (const auto& c : mesh.node_classes()) r.free_nodes += c.kind == hom::NodeKind::free;
  r.perturbation = o.hex_perturb;
  r.stages.push_back(evaluate("curved", mesh, false));
  r.stages.back().time_s = seconds_since(t0);
  hom::bench::perturb_free_nodes(mesh, r.perturbation, o.seed);
  r.stages.push_back(evaluate("initial", mesh, false));
  std::printf("hexahedral ring p = %d: %d elements, %d nodes (%d free, perturbed by a = %.3g x shortest incident "
              "edge, seed %llu)\n",
              r.p, r.elements, r.nodes, r.free_nodes, r.perturbation, static_cast<unsigned long long>(o.seed));
  std::fflush(stdout);
  if (o.vtu) write_vtu(o.out / "hex_ring_p4_initial.vtu", mesh, false);

  const Stage& ideal = r.stages[0];
  const Stage& ini = r.stages[2];
  r.checks.push_back({"D.4: the straight-sided ideal scores 1", ideal.relative.min >= 1.0 - 1e-12,
                      "min " + fmt(ideal.relative.min, 14)});
  r.checks.push_back({"D.4: every element inverted after the perturbation", ini.relative.inverted == r.elements,
                      std::to_string(ini.relative.inverted) + " of " + std::to_string(r.elements)});
  if (!o.optimize) return r;

  Stage s;
  smooth(mesh, o, s);
  Stage e = evaluate("smoothed", mesh, false);
  e.time_s = s.time_s;
  e.iterations = s.iterations;
  e.solver = s.solver;
  e.stop_reason = s.stop_reason;
  r.stages.push_back(e);
  r.optimized = true;
  r.valid_at_end = e.relative.inverted == 0;
  if (o.vtu) write_vtu(o.out / "hex_ring_p4_smoothed.vtu", mesh, false);
  r.checks.push_back({"D.4: smoothed mesh valid", e.relative.inverted == 0,
                      std::to_string(e.relative.inverted) + " inverted"});
  r.checks.push_back({"D.4: smoothed minimum quality >= 0.96", e.relative.min >= thesis_hex_min_quality,
                      "min " + fmt(e.relative.min, 3)});
  return r;
}

// ---------------------------------------------------------------------------
// Tables.

void print_header(bool thesis_nodes) {
  std::printf("  %2s %6s %-9s %6s %6s %6s %9s %5s   | %s%6s %6s %6s %9s %5s  (thesis)\n", "p", "#nodes", "mesh", "Min",
              "Max", "Mean", "Std.Dev.", "#inv", thesis_nodes ? "#nodes " : "", "Min", "Max", "Mean", "Std.Dev.",
              "#inv");
}

void print_row(int p, int nodes, const std::string& label, const hom::Statistics& s, const Row* t,
               std::optional<int> thesis_nodes) {
  std::printf("  %2d %6d %-9s %6s %6s %6s %9s %5d", p, nodes, label.c_str(), fmt(s.min).c_str(), fmt(s.max).c_str(),
              fmt(s.mean).c_str(), fmt(s.std_dev).c_str(), s.inverted);
  if (t) {
    std::printf("   | ");
    if (thesis_nodes) std::printf("%6d ", *thesis_nodes);
    std::printf("%6s %6s %6s %9s %5d", fmt(t->min).c_str(), fmt(t->max).c_str(), fmt(t->mean).c_str(),
                fmt(t->std_dev, t->std_dev < 0.01 && t->std_dev > 0 ? 3 : 2).c_str(), t->inverted);
  }
  std::printf("\n");
}

const Row* sphere_thesis_row(int p, const std::string& stage, bool absolute) {
  const ThesisSphere* t = thesis_sphere_case(p);
  if (!t) return nullptr;
  if (stage == "initial") return absolute ? &t->absolute_initial : &t->relative_initial;
  if (stage == "smoothed") return absolute ? &t->absolute_smoothed : &t->relative_smoothed;
  return nullptr;
}

const Row* hex_thesis_row(const std::string& stage) {
  if (stage == "ideal") return &thesis_hex_ideal;
  if (stage == "initial") return &thesis_hex_initial;
  if (stage == "smoothed") return &thesis_hex_smoothed;
  return nullptr;
}

void print_sphere_table(const std::vector<CaseResult>& results, bool absolute) {
  std::printf("\nTable %s: hollow sphere, %s quality (ideal: %s), %d tetrahedra (thesis %d)\n", absolute ? "3.3" : "3.2",
              absolute ? "absolute" : "relative", absolute ? "regular tetrahedron" : "straight-sided mesh",
              results.empty() ? 0 : results.front().elements, thesis_sphere_elements);
  print_header(true);
  for (const auto& r : results) {
    if (r.name != "hollow_sphere") continue;
    const ThesisSphere* t = thesis_sphere_case(r.p);
    for (const auto& s : r.stages)
      print_row(r.p, r.nodes, s.name, absolute ? *s.absolute : s.relative, sphere_thesis_row(r.p, s.name, absolute),
                t ? std::optional<int>(t->nodes) : std::nullopt);
  }
}

void print_hex_table(const CaseResult& r) {
  std::printf("\nTable D.4: hexahedral mesh of degree %d, %d elements (thesis %d), relative quality\n", r.p, r.elements,
              thesis_hex_elements);
  print_header(false);
  for (const auto& s : r.stages) print_row(r.p, r.nodes, s.name, s.relative, hex_thesis_row(s.name), std::nullopt);
}

void print_runs(const std::vector<CaseResult>& results) {
  std::printf("\nSmoothing runs (relative ideal):\n");
  for (const auto& r : results)
    if (const Stage* s = find_stage(r, "smoothed"))
      std::printf("  %-13s p = %d: solver %s, %d iterations (%s), %.2f s, min scaled Jacobian %.3f, peak RSS %.0f MB\n",
                  r.name.c_str(), r.p, s->solver.c_str(), s->iterations, s->stop_reason.c_str(), s->time_s,
                  s->relative_sj.min, s->peak_rss_mb);
}

void write_outputs(const std::vector<CaseResult>& results, const Options& o, int threads) {
  const std::string csv_path = (o.out / "sphere.csv").string();
  std::ostringstream csv;
  csv << "case,table,p,stage,ideal,elements,nodes,min_q,max_q,mean_q,std_q,inverted,min_scaled_jacobian,time_s,"
         "iterations,solver,perturbation,seed,thesis_min_q,thesis_max_q,thesis_mean_q,thesis_std_q,thesis_inverted\n";
  std::vector<Json> cases;
  for (const auto& r : results) {
    const bool sphere = r.name == "hollow_sphere";
    for (const auto& s : r.stages)
      for (bool absolute : {false, true}) {
        if (absolute && !s.absolute) continue;
        const hom::Statistics& q = absolute ? *s.absolute : s.relative;
        const Row* t = sphere ? sphere_thesis_row(r.p, s.name, absolute) : hex_thesis_row(s.name);
        const std::string table = sphere ? (absolute ? "3.3" : "3.2") : "D.4";
        const std::string ideal = absolute ? "equilateral" : "straight-sided";
        csv << r.name << ',' << table << ',' << r.p << ',' << s.name << ',' << ideal << ',' << r.elements << ','
            << r.nodes << ',' << q.min << ',' << q.max << ',' << q.mean << ',' << q.std_dev << ',' << q.inverted << ','
            << s.relative_sj.min << ',' << s.time_s << ','
            << s.iterations << ',' << s.solver << ',' << r.perturbation << ',' << o.seed;
        if (t)
          csv << ',' << t->min << ',' << t->max << ',' << t->mean << ',' << t->std_dev << ',' << t->inverted;
        else
          csv << ",,,,,";
        csv << '\n';

        hom::io::CaseHeader h{r.name, r.family, r.p, r.elements, r.nodes, s.name, "shape", ideal};
        // The scaled Jacobian does not depend on the ideal: the same for both rows.
        Json c = hom::io::quality_case(h, q, s.relative_sj);
        std::optional<int> thesis_nodes;
        if (const ThesisSphere* ts = sphere ? thesis_sphere_case(r.p) : nullptr) thesis_nodes = ts->nodes;
        c.set("table", table)
            .set("time_s", s.time_s)
            .set("iterations", s.iterations)
            .set("peak_rss_mb", s.peak_rss_mb)
            .set("solver", s.solver.empty() ? Json() : Json(s.solver))
            .set("stop_reason", s.stop_reason.empty() ? Json() : Json(s.stop_reason))
            .set("perturbation", s.name == "initial" || s.name == "smoothed" ? Json(r.perturbation) : Json())
            .set("seed", static_cast<long long>(o.seed))
            .set("quadrature", "default")
            .set("threads", threads)
            .set("free_nodes", r.free_nodes)
            .set("boundary_only_inverted", r.boundary_only_inverted ? Json(*r.boundary_only_inverted) : Json())
            .set("thesis", t ? row_json(*t, sphere ? thesis_sphere_elements : thesis_hex_elements, thesis_nodes) : Json());
        if (s.name == "smoothed" && !absolute) {
          Json checks = Json::array();
          for (const auto& k : r.checks) {
            Json j = Json::object();
            j.set("claim", k.claim).set("passed", k.passed).set("detail", k.detail);
            checks.push(std::move(j));
          }
          c.set("checks", std::move(checks));
        }
        cases.push_back(std::move(c));
      }
  }
  const std::string text = csv.str();
  hom::io::write_atomically(csv_path, [&](std::FILE* f) { hom::io::write_all(f, csv_path, text.data(), text.size()); });
  const fs::path json_path = o.json.value_or(o.out / "sphere.json");
  hom::io::write_report(json_path.string(), "bench_sphere", HOM_VERSION, std::move(cases));
  std::printf("\nwrote %s, %s%s\n", csv_path.c_str(), json_path.c_str(), o.vtu ? " and VTU files" : "");
}

}  // namespace

int main(int argc, char** argv) {
  namespace po = boost::program_options;
  Options o;
  std::string degrees, json, which = "all";
  std::uint64_t seed = 1;
  double perturb = 0.0;
  po::options_description desc(
      "bench_sphere: tables 3.2 and 3.3 (hollow sphere, radii 1 and 3, 160 tetrahedra, tangled and smoothed at\n"
      "degrees 2, 4, 6; relative and absolute quality) and table D.4 (68 hexahedra of degree 4, all inverted,\n"
      "untangled) of the thesis");
  // clang-format off
  desc.add_options()
      ("help,h", "this message")
      ("p", po::value(&degrees), "hollow-sphere degrees, comma-separated (default 2,4,6; with --quick 2,4); "
                                 "table D.4 is always degree 4")
      ("solver", po::value(&o.solver)->default_value("newton"), "newton | matrix-free | gauss-seidel")
      ("threads", po::value(&o.threads)->default_value(0), "threads (0: OpenMP's default)")
      ("pcont", po::bool_switch(&o.pcont), "p-continuation (appendix C)")
      ("seed", po::value(&seed)->default_value(1), "seed of the perturbations")
      ("perturb", po::value(&perturb),
       "hollow sphere: tangling amplitude a, relative to the shortest straight-sided edge of the elements containing "
       "each free node (default: per degree, calibrated to the thesis's inverted counts)")
      ("hex-perturb", po::value(&o.hex_perturb)->default_value(default_hex_perturbation),
       "table D.4: perturbation amplitude, same meaning")
      ("case", po::value(&which)->default_value("all"), "sphere | hex | all")
      ("out", po::value(&o.out)->default_value("results/sphere"), "output directory (CSV, VTU, JSON)")
      ("json", po::value(&json), "JSON report (default OUT/sphere.json)")
      ("quick", po::bool_switch(&o.quick), "hollow sphere at degrees 2,4 only (CI)")
      ("no-vtu", "do not write VTU files")
      ("no-optimize", "stop after the statistics of the tangled meshes (for calibrating --perturb)")
      ("max-iterations", po::value(&o.max_iterations)->default_value(200), "optimizer iteration limit per stage")
      ("verbose,v", "optimizer progress, one line per iteration");
  // clang-format on
  try {
    po::variables_map vm;
    po::store(po::parse_command_line(argc, argv, desc), vm);
    po::notify(vm);
    if (vm.count("help")) {
      std::cout << desc << "\n";
      return 0;
    }
    o.degrees = hom::bench::parse_int_list(degrees.empty() ? (o.quick ? "2,4" : "2,4,6") : degrees, "--p", 1, 12);
    o.seed = seed;
    if (vm.count("perturb")) {
      if (!(perturb >= 0.0)) throw std::invalid_argument("--perturb must be >= 0");
      o.perturb = perturb;
    }
    if (!(o.hex_perturb >= 0.0)) throw std::invalid_argument("--hex-perturb must be >= 0");
    hom::parse_solver_kind(o.solver);  // throws on an unknown name
    if (which != "all" && which != "sphere" && which != "hex")
      throw std::invalid_argument("--case: expected sphere, hex or all, got '" + which + "'");
    o.run_sphere = which != "hex";
    o.run_hex = which != "sphere";
    if (o.threads < 0) throw std::invalid_argument("--threads must be >= 0");
    if (o.max_iterations < 1) throw std::invalid_argument("--max-iterations must be >= 1");
    if (!json.empty()) o.json = json;
    o.vtu = !vm.count("no-vtu");
    o.verbose = vm.count("verbose") > 0;
    o.optimize = !vm.count("no-optimize");
  } catch (const std::exception& e) {
    std::cerr << "bench_sphere: " << e.what() << "\n";
    return 2;
  }
  const int threads = hom::bench::set_threads(o.threads);

  try {
    fs::create_directories(o.out);
    std::printf("bench_sphere %s: quadrature default (deg det + 2), solver %s, %d threads\n", HOM_VERSION,
                o.solver.c_str(), threads);
    std::vector<CaseResult> results;
    if (o.run_sphere) {
      const auto linear = hom::bench::hollow_sphere();
      for (int p : o.degrees) results.push_back(run_sphere(linear, p, o));
      print_sphere_table(results, false);
      print_sphere_table(results, true);
    }
    if (o.run_hex) {
      results.push_back(run_hex(o));
      print_hex_table(results.back());
    }
    if (o.optimize) print_runs(results);

    write_outputs(results, o, threads);

    bool ok = true;
    std::printf("\nClaim checks:\n");
    for (const auto& r : results) {
      for (const auto& c : r.checks) {
        std::printf("  [%s] %s (%s)\n", c.passed ? "PASS" : "FAIL", c.claim.c_str(), c.detail.c_str());
        ok = ok && c.passed;
      }
      if (r.optimized && !r.valid_at_end) ok = false;
    }
    if (!ok) {
      std::fprintf(stderr, "bench_sphere: a claim check failed or an optimized mesh is invalid\n");
      return 1;
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_sphere: %s\n", e.what());
    return 2;
  }
}
