/// @file bench_certify.cpp
/// Certified validity (issue 8, include/hom/quality/certify.hpp) on the meshes
/// of bench_untangle's pipeline (table 4.1): the cube of side 5 with a
/// spherical cavity (src/meshing/cube_with_cavity.hpp), elevated to degree p,
/// boundary curved onto the exact geometry, free nodes perturbed (the same
/// default amplitudes as bench_untangle) and untangled with hom::optimize
/// with bench_untangle's table 4.1 settings (p-continuation, Newton-CG with
/// the Gauss-Newton model, linear stage stopped 3 sweeps after validity, stop
/// at min quality 0.96: seconds at p = 2 and 5, minutes at p = 10, so p = 10
/// is optimized only with --optimize-up-to 10).
///
/// For the perturbed ("initial") and the optimized mesh it reports how many
/// elements the quadrature-point check (element_quality, DefaultExactness)
/// calls valid while certification rejects them or cannot decide, the
/// certified minimum scaled Jacobian beside the sampled one, and the time of
/// certification relative to one evaluation of the optimizer's objective
/// (hom::make_problem(...).value, eq 4.11, the same quadrature).
///
/// Peer (--peer gmsh, the default): Gmsh's own validity analysis on the same
/// mesh, Plugin(AnalyseMeshQuality) with JacobianDeterminant = 1, in this
/// process through Gmsh's library. The mesh goes into a discrete Gmsh model
/// at Gmsh's equispaced nodes (io::to_msh_data), element tag = hom index + 1.
/// The plugin bounds det J by Bezier coefficients with adaptive subdivision
/// and stores min(J)/max(J) per element in a view; an element is invalid for
/// Gmsh when min J <= 0 <= max J (ratio <= 0) or when it is completely
/// inverted (min J, max J < 0: ratio > 0, told apart by the sign of det J at
/// the centroid, from gmsh::model::mesh::getJacobians). Where the two differ:
/// Gmsh refines until its bounds are within 1e-3 (relative to max |det| at the
/// corners) of attained values, capped at 1000 subdivisions, and then calls
/// min J = smallest Bezier coefficient, so an element it could not resolve
/// within the cap counts as invalid; hom stops at --depth levels and says
/// "undecided", and its zero is 1e-12 relative (CertifyOptions::zero_tolerance).
/// Cost (loaded 2-core machine): Gmsh takes ~4 s on the perturbed p = 5 mesh
/// and ~190 s at p = 10 (hom: 0.5 s and 17 s); --peer none skips it.
///
/// Checks (exit status 1 when one fails):
///   - no element with det <= 0 at a quadrature point or node is certified valid;
///   - at the point each certified-invalid element reports, det (recomputed
///     with hom's Lagrange Jacobian) is <= 0 up to round-off;
///   - the certified minimum scaled Jacobian is <= the sampled one;
///   - with the peer: Gmsh and hom agree on every element hom decides.
///
/// Output: table on stdout, CSV (certify.csv) and the JSON report of
/// DESIGN.md (--json, default OUT/certify.json), one case per (p, stage),
/// Gmsh's counts as the case's "peer".

#include <gmsh.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <boost/program_options.hpp>

#include "cube_with_cavity.hpp"
#include "gmsh_model.hpp"
#include "gmsh_validity.hpp"
#include "harness.hpp"
#include "hom/geometry/curve_boundary.hpp"
#include "hom/io/msh.hpp"
#include "hom/io/report.hpp"
#include "hom/measure/shape_measure.hpp"
#include "hom/mesh/elevate.hpp"
#include "hom/mesh/flat_corners.hpp"
#include "hom/optimize/mesh_problem.hpp"
#include "hom/optimize/optimize.hpp"
#include "hom/quadrature/quadrature_policy.hpp"
#include "hom/quality/certify.hpp"
#include "hom/quality/mesh_quality.hpp"
#include "meshing_error.hpp"

#ifndef HOM_VERSION
#define HOM_VERSION "unknown"
#endif

namespace fs = std::filesystem;
namespace po = boost::program_options;
using hom::meshing::compare_with_gmsh;
using hom::meshing::peer_json;
using hom::meshing::PeerComparison;
using hom::bench::seconds_since;
using Tet = hom::Simplex<3>;
using TetMesh = hom::Mesh<Tet>;

namespace {

// ---------------------------------------------------------------------------
// hom's certificate against its own quadrature-point check.

struct StageResult {
  std::string stage;
  hom::MeshQuality quality;
  hom::MeshCertificate<Tet> certificate;
  int quadrature_valid_certified_invalid = 0;
  int quadrature_valid_undecided = 0;
  int sampled_nonpositive_certified_valid = 0;  // must stay 0
  int quadrature_valid_node_nonpositive = 0;    // of those quad-valid but certified invalid: det <= 0 at a node
  int invalid_point_positive = 0;               // certified invalid, but hom's det there > 0 (must stay 0)
  double certify_s = 0.0, objective_s = 0.0;
  double optimize_s = -1.0;  // optimized stage: optimizer wall time
  int iterations = 0;
  std::optional<PeerComparison> peer;
};

StageResult evaluate(const std::string& stage, const TetMesh& mesh, const hom::CertifyOptions& co) {
  StageResult r;
  r.stage = stage;
  r.quality = hom::mesh_quality(mesh, hom::ShapeMeasure{});
  auto t0 = std::chrono::steady_clock::now();
  r.certificate = hom::certify_mesh(mesh, co);
  r.certify_s = seconds_since(t0);
  // One evaluation of the optimizer's objective (eq 4.11) with the same
  // quadrature, as the unit of cost (the problem's set-up is not timed).
  const auto problem = hom::make_problem<hom::ShapeMeasure, hom::DefaultExactness>(
      mesh, hom::make_ideal_mesh(mesh, hom::IdealKind::straight_sided));
  t0 = std::chrono::steady_clock::now();
  volatile double f = problem.value(mesh.nodes());
  (void)f;
  r.objective_s = seconds_since(t0);
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const auto& q = r.quality.elements[e];
    const auto s = r.certificate.elements[e].status;
    if (q.valid && s == hom::Certificate::certified_invalid) {
      ++r.quadrature_valid_certified_invalid;
      r.quadrature_valid_node_nonpositive += q.min_det <= 0.0;
    }
    if (s == hom::Certificate::certified_invalid) {
      // The attained value, recomputed with hom's Lagrange Jacobian.
      const auto& c = r.certificate.elements[e];
      const double det = mesh.jacobian(e, *c.invalid_point).determinant();
      const double scale = std::max(std::abs(c.min_det_bound), std::abs(c.max_det_bound));
      r.invalid_point_positive += det > 1e-10 * scale;
    }
    if (q.valid && s == hom::Certificate::undecided) ++r.quadrature_valid_undecided;
    if (q.min_det <= 0.0 && s == hom::Certificate::certified_valid) ++r.sampled_nonpositive_certified_valid;
  }
  return r;
}

void print_stage(int p, const StageResult& r) {
  const auto& c = r.certificate;
  std::printf("  p = %2d %-9s  quad-inverted %5d | hom certified valid %5d invalid %5d undecided %4d (depth %d) | "
              "quad-valid but cert. invalid %4d (det <= 0 at a node: %d), undecided %4d | min SJ sampled %8.4f "
              "certified >= %8.4f | certify %.3f s = %.1f x objective (%.4f s)\n",
              p, r.stage.c_str(), r.quality.inverted(), c.valid, c.invalid, c.undecided, c.max_depth,
              r.quadrature_valid_certified_invalid, r.quadrature_valid_node_nonpositive, r.quadrature_valid_undecided,
              r.quality.scaled_jacobian_statistics().min, c.min_scaled_jacobian, r.certify_s,
              r.certify_s / r.objective_s, r.objective_s);
  if (r.peer) {
    const auto& g = *r.peer;
    std::printf("  p = %2d %-9s  gmsh %s invalid %5d (completely inverted %d) vs hom certified invalid %5d | "
                "disagreements %d (hom invalid/gmsh valid %d, hom valid/gmsh invalid %d)",
                p, r.stage.c_str(), g.gmsh.version.c_str(), g.invalid, g.gmsh.completely_inverted, c.invalid,
                g.disagreements(), g.hom_invalid_gmsh_valid, g.hom_valid_gmsh_invalid);
    if (!g.disagreeing.empty()) {
      std::printf(", elements");
      for (int e : g.disagreeing) std::printf(" %d", e);
    }
    std::printf(" | hom undecided: gmsh invalid %d, valid %d | gmsh %.2f s\n", g.undecided_gmsh_invalid,
                g.undecided_gmsh_valid, g.gmsh.time_s);
  }
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  std::string degrees = "2,5", out = "results/certify", json, peer = "gmsh";
  int depth = hom::CertifyOptions{}.max_depth, threads = 0, max_iterations = 200, optimize_up_to = 5;
  int linear_after_valid = 3;
  double target_quality = 0.96;
  unsigned long long seed = 1;
  bool quick = false, keep_flat_corners = false;
  po::options_description opts("bench_certify [options]: certified validity on bench_untangle's meshes\n\noptions");
  // clang-format off
  opts.add_options()
      ("help,h", "show this help")
      ("p", po::value(&degrees)->default_value(degrees), "degrees, comma-separated (1..10)")
      ("depth", po::value(&depth)->default_value(depth), "certification subdivision depth")
      ("threads", po::value(&threads)->default_value(0), "threads (0: OpenMP's default)")
      ("max-iterations", po::value(&max_iterations)->default_value(max_iterations), "optimizer iterations per stage")
      ("optimize-up-to", po::value(&optimize_up_to)->default_value(optimize_up_to),
       "optimize only degrees up to this one (higher ones: the perturbed mesh only; p = 10 takes minutes)")
      ("target-quality", po::value(&target_quality)->default_value(target_quality),
       "stop the optimizer once valid with min quality >= this (bench_untangle's table 4.1 target; 0: converge)")
      ("linear-after-valid", po::value(&linear_after_valid)->default_value(linear_after_valid),
       "p-continuation: stop the linear stage this many iterations after its sub-mesh is valid (-1: converge it)")
      ("peer", po::value(&peer)->default_value(peer),
       "gmsh: Gmsh's Plugin(AnalyseMeshQuality) on the same meshes, element by element | none")
      ("seed", po::value(&seed)->default_value(1), "seed of the perturbation")
      ("quick", po::bool_switch(&quick), "coarser cube (fewer elements), for a smoke test")
      ("keep-flat-corners", po::bool_switch(&keep_flat_corners),
       "do not split the linear tetrahedra with a flat corner (three edges on the sphere) before curving")
      ("out", po::value(&out)->default_value(out), "output directory")
      ("json", po::value(&json), "JSON report (default OUT/certify.json)");
  // clang-format on
  std::vector<int> ps;
  try {
    po::variables_map vm;
    po::store(po::parse_command_line(argc, argv, opts), vm);
    po::notify(vm);
    if (vm.count("help")) {
      std::cout << opts << "\n";
      return 0;
    }
    ps = hom::bench::parse_int_list(degrees, "--p", 1, 10);
    if (depth < 0 || depth > 20) throw std::invalid_argument("--depth must be in 0..20");
    if (peer != "gmsh" && peer != "none") throw std::invalid_argument("--peer: expected gmsh or none, got '" + peer + "'");
  } catch (const std::exception& e) {
    std::cerr << "bench_certify: " << e.what() << "\n";
    return 2;
  }
  if (json.empty()) json = (fs::path(out) / "certify.json").string();

  hom::bench::Checks checks("bench_certify");
  std::vector<hom::io::Json> cases;
  try {
    fs::create_directories(out);
    hom::meshing::CubeWithCavityOptions mo;
    if (quick) {
      mo.cube_size = 2.0;
      mo.sphere_size = 0.3;
    }
    auto model = hom::meshing::cube_with_cavity(mo);
    // A tetrahedron whose three edges at a vertex lie on the sphere has
    // det = 0 there once they are curved, which no interior node can mend
    // (mesh/flat_corners.hpp); the quick mesh has one, the table 4.1 mesh none.
    if (!keep_flat_corners) {
      const auto s = hom::split_flat_corners(model.mesh);
      if (s.corners > 0)
        std::printf("linear mesh: %d flat corners split (%d edges, %d elements at their centroid)\n", s.corners,
                    s.edges_split, s.centroid_splits);
    }
    std::optional<hom::meshing::GmshSession> gmsh_session;
    if (peer == "gmsh") gmsh_session.emplace();
    std::printf("bench_certify %s: linear mesh %d tetrahedra; certification depth %d; peer %s; timings on this machine\n",
                HOM_VERSION, model.mesh.num_elements(), depth, peer.c_str());
    std::ofstream csv(fs::path(out) / "certify.csv");
    csv << "p,stage,elements,nodes,quadrature_inverted,certified_valid,certified_invalid,undecided,max_depth,"
           "quadrature_valid_certified_invalid,quadrature_valid_undecided,min_scaled_jacobian,"
           "certified_min_scaled_jacobian,certify_s,objective_s,optimize_s,gmsh_invalid,gmsh_disagreements,gmsh_s\n";
    hom::CertifyOptions co;
    co.max_depth = depth;
    co.threads = threads;
    for (int p : ps) {
      const auto t_setup = std::chrono::steady_clock::now();
      TetMesh mesh = hom::elevate(model.mesh, p);
      hom::curve_boundary(mesh, model.geometry);
      // bench_untangle's default amplitudes (its `default_perturbation`).
      const double a = hom::bench::interpolate_geometric({{2, 0.355}, {5, 0.0685}, {10, 0.0102}}, p);
      hom::bench::perturb_free_nodes(mesh, a, seed);
      std::printf("p = %d: %d elements, %d nodes, perturbation %.3g (setup %.1f s)\n", p, mesh.num_elements(),
                  mesh.num_nodes(), a, seconds_since(t_setup));
      std::fflush(stdout);
      std::vector<StageResult> stages;
      auto run_stage = [&](const std::string& stage) {
        stages.push_back(evaluate(stage, mesh, co));
        if (gmsh_session)
          stages.back().peer = compare_with_gmsh(mesh, stages.back().certificate, "hom_certify_p" + std::to_string(p) + "_" + stage);
        print_stage(p, stages.back());
      };
      run_stage("initial");
      if (p <= optimize_up_to) {
        // bench_untangle's table 4.1 settings.
        hom::OptimizeOptions opt;
        opt.solver = hom::SolverKind::matrix_free_newton;
        opt.hessian = hom::HessianForm::gauss_newton;
        opt.p_continuation = true;
        opt.continuation_iterations_after_valid = linear_after_valid;
        opt.target_quality = target_quality;
        opt.threads = threads;
        opt.max_iterations = max_iterations;
        const auto result = hom::optimize<hom::ShapeMeasure, hom::DefaultExactness>(mesh, opt);
        const int iterations = result.result.iterations + (result.continuation ? result.continuation->iterations : 0);
        std::printf("  optimized in %.1f s (%s + p-continuation, %d iterations, %s, %d inverted at quadrature points)\n",
                    result.time_s, std::string(hom::to_string(opt.solver)).c_str(), iterations,
                    std::string(hom::to_string(result.result.reason)).c_str(), result.result.inverted);
        std::fflush(stdout);
        run_stage("optimized");
        stages.back().optimize_s = result.time_s;
        stages.back().iterations = iterations;
      }
      for (const auto& s : stages) {
        const auto& c = s.certificate;
        const std::string where = "p = " + std::to_string(p) + ", " + s.stage;
        checks.expect(s.sampled_nonpositive_certified_valid == 0,
                      where + ": no element with det <= 0 at a quadrature point or node is certified valid");
        checks.expect(s.invalid_point_positive == 0,
                      where + ": det <= 0 (hom's Lagrange Jacobian) at every certified-invalid element's point");
        checks.expect(c.min_scaled_jacobian <= s.quality.scaled_jacobian_statistics().min + 1e-12,
                      where + ": certified min scaled Jacobian <= sampled min scaled Jacobian");
        if (s.peer)
          checks.expect(s.peer->disagreements() == 0,
                        where + ": Gmsh's Plugin(AnalyseMeshQuality) and hom agree on every element hom decides");
        hom::io::CaseHeader h{"cube_with_cavity", "tetrahedron", p, mesh.num_elements(), mesh.num_nodes(), s.stage,
                              "shape", "straight-sided"};
        auto j = hom::io::quality_case(h, s.quality.quality_statistics(), s.quality.scaled_jacobian_statistics());
        j.set("certified_valid", c.valid)
            .set("certified_invalid", c.invalid)
            .set("undecided", c.undecided)
            .set("certified_min_scaled_jacobian", c.min_scaled_jacobian)
            .set("certify_max_depth", depth)
            .set("certify_depth_used", c.max_depth)
            .set("quadrature_valid_certified_invalid", s.quadrature_valid_certified_invalid)
            .set("quadrature_valid_undecided", s.quadrature_valid_undecided)
            .set("quadrature_valid_node_nonpositive", s.quadrature_valid_node_nonpositive)
            .set("time_s", s.certify_s)
            .set("objective_time_s", s.objective_s)
            .set("certify_over_objective", s.certify_s / s.objective_s)
            .set("optimize_time_s", s.optimize_s >= 0 ? hom::io::Json(s.optimize_s) : hom::io::Json())
            .set("iterations", s.iterations)
            .set("peak_rss_mb", hom::bench::peak_rss_mb())
            .set("peer", s.peer ? peer_json(*s.peer) : hom::io::Json());
        cases.push_back(std::move(j));
        csv << p << ',' << s.stage << ',' << mesh.num_elements() << ',' << mesh.num_nodes() << ','
            << s.quality.inverted() << ',' << c.valid << ',' << c.invalid << ',' << c.undecided << ',' << c.max_depth
            << ',' << s.quadrature_valid_certified_invalid << ',' << s.quadrature_valid_undecided << ','
            << s.quality.scaled_jacobian_statistics().min << ',' << c.min_scaled_jacobian << ',' << s.certify_s << ','
            << s.objective_s << ',';
        if (s.optimize_s >= 0) csv << s.optimize_s;
        csv << ',';
        if (s.peer) csv << s.peer->invalid << ',' << s.peer->disagreements() << ',' << s.peer->gmsh.time_s;
        else csv << ",,";
        csv << '\n';
      }
    }
    hom::io::write_report(json, "bench_certify", HOM_VERSION, cases, checks.all());
    std::printf("wrote %s and %s\n", json.c_str(), (fs::path(out) / "certify.csv").string().c_str());
  } catch (const std::exception& e) {
    std::cerr << "bench_certify: " << e.what() << "\n";
    return 2;
  }
  return checks.failures().empty() ? 0 : 1;
}
