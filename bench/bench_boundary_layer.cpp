/// @file bench_boundary_layer.cpp
/// Section 6.3.3 (issue 9): curved high-order boundary-layer meshes of
/// simplices from an inviscid linear mesh and a CAD wall, through
/// hom::boundary_layer_pipeline (optimize/boundary_layer_pipeline.hpp), with
/// the statistics of every stage (inviscid, inserted, smoothed, curved,
/// optimized) as tables 6.4 and 6.5:
///
///   sphere      a sphere of diameter 1 in a far-field box (Gmsh,
///               src/meshing/cube_with_cavity), the wall described by hom's
///               8-patch exact NURBS sphere (src/cad nurbs_sphere_model: 8
///               rational B-spline octants as OccSurface, behind one wall
///               entity through PatchedSurface below), 3 layers as the
///               thesis's (24986 = 806 wall triangles x 31 tetrahedra),
///               p = 4; beside table 6.4;
///   wing        an airfoil wing section: the SD7003 profile of
///               ../shared/data/cad/sd7003.dat (--airfoil; a NACA 0012 built
///               analytically when the file is absent) extruded in z through
///               a box (src/meshing/airfoil_section, written as BREP, read and
///               meshed by src/cad so the wall is the model's own extruded
///               B-spline faces), 7 layers growing by 2 as the thesis's,
///               p = 4; beside table 6.5. The final mesh's quality is
///               also given against the equilateral ideal (absolute
///               quality): with the relative one it makes table 3.4, and
///               the curved and optimized stages at p = 2 make table 4.3
///               (the thesis's figures 3.9 and 4.9 are of tetrahedral
///               SD7003 wing meshes too). When the smoothed linear mesh is
///               still tangled the pipeline stops there (the degree-p
///               stages cannot end valid) and the claim fails. SD7003's
///               trailing edge is a 4-degree wedge: the layer nodes of its
///               stack on the wall border (on the planes z = 0 and
///               z = span) go to their full heights along the bisector,
///               which folds one layer triangle per level in each plane;
///               the pipeline's stage (c) therefore first slides the
///               border nodes on their planes against the stretched
///               ideal's faces (before it, 10 elements, levels 0-3 at
///               x = 0.977-0.991, stayed inverted; now 0 after 9
///               iterations at p = 2; 2026-12-03). At p = 4 stage (e)
///               starts with about 200 inverted elements; the pipeline's
///               whole-mesh regularization scope (the default of both
///               stages since 2026-12-03) ends valid after 56 Newton
///               iterations, 19 minutes on 2 threads, where the
///               element-wise scope's steps stayed near 2^-17.
///               The quick NACA 0012 wing gets through every stage (its
///               leading edge's stacks at the border are isoparametric,
///               boundary_layer.hpp) and ends valid: the optimizer leaves
///               10 layer elements near the box faces valid at every
///               quadrature point but folded at a node, and the
///               certify-and-repair stage mends them in one round;
///   stretching  first-layer heights giving aspect ratios about 1:10^2,
///               1:10^4, 1:10^6 and 1:10^8 on a 2D quarter annulus (inner
///               circle of diameter 1 as the wall, Circle<2>), p = 2 and 4:
///               valid or not, min quality, iterations, time. The total
///               height H and the number of layers are fixed and the growth
///               is solved from h0 (g^L - 1) / (g - 1) = H: a layer thinner
///               than the sagitta of the wall's sub-facets cannot be valid
///               with straight-sided tops (pipeline caveat), so shrinking h0
///               with a fixed growth would test geometry, not stretching.
///
/// --quick (CI-sized, about a minute on two loaded cores): p = 2 unless --p,
/// 2 sphere layers, a NACA 0012 wing (--airfoil to override) on a coarser
/// mesh, the stretching study at 1:10^2 and 1:10^6 on a coarser annulus.
///
/// The thesis's meshes are larger (43922 and 121898 tetrahedra); the default
/// sizes here keep the whole run near ten minutes on two loaded cores, so
/// its rows are printed beside hom's for scale. The high-order stage stops
/// --iterations-after-valid iterations after the mesh is valid (default 3;
/// -1 optimizes to convergence as the thesis). Stage (e) ends with the
/// certify-and-repair stage (optimize/certified.hpp; --no-certify leaves it
/// out): the quick wing's thin layer elements at the box faces are valid at
/// every quadrature point after the optimizer but fold at a node (10
/// elements certified invalid; 56 before stage (c) slid the border nodes),
/// which one repair round mends.
///
/// Output: the tables on stdout; CSV (--csv, default OUT/boundary_layer.csv)
/// and the JSON report (--json, default OUT/boundary_layer.json; one case per
/// case and stage, DESIGN.md keys plus aspect_ratio = the ideal layer's
/// largest element aspect ratio, layers, first_height, growth, "thesis"
/// rows); with --vtu-dir, VTU files of the inserted, smoothed and final
/// meshes colored by element quality. For the sphere and the wing, a planar
/// cut through the final curved mesh (bench/mesh_cut.hpp; the sphere's
/// centre plane and the wing's mid-span plane, both normal to z):
/// OUT/cut_<case>.csv, drawn by bench/plot_boundary_layer.py as
/// OUT/cut_<case>.png, the whole cut and the wall region (skipped with a
/// message without /usr/bin/python3 + matplotlib, or with --no-plot).
///
/// Claims checked (exit status 1 when one fails): the final sphere and wing
/// meshes are valid; the stretching study is valid up to 1:10^6 at every
/// degree (1:10^8 is reported, not claimed). Exit 2 on bad options.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <boost/program_options.hpp>

#include "airfoil_section.hpp"
#include "cad_mesher.hpp"
#include "cad_model.hpp"
#include "cube_with_cavity.hpp"
#include "harness.hpp"
#include "plot_script.hpp"
#include "mesh_cut.hpp"
#include "hom/detail/surface_projection.hpp"
#include "hom/geometry/circle.hpp"
#include "hom/io/certification_report.hpp"
#include "hom/io/report.hpp"
#include "hom/io/vtu.hpp"
#include "hom/mesh/structured.hpp"
#include "hom/optimize/boundary_layer_pipeline.hpp"

#ifndef HOM_VERSION
#define HOM_VERSION "unknown"
#endif
#ifndef HOM_PLOT_SCRIPT
#define HOM_PLOT_SCRIPT "bench/plot_boundary_layer.py"
#endif

namespace po = boost::program_options;
namespace fs = std::filesystem;
using hom::bench::fmt;

namespace {

/// Several surface patches (the 8 NURBS octants of the sphere) as one
/// SurfaceGeometry, so that one wall entity of the mesh can be curved onto
/// all of them: parameter u in [2k, 2k + 1] is patch k's own u rescaled to
/// [0, 1] (the gaps keep the patches' closed ranges apart: u = k + 1 would
/// name both patch k's last and patch k + 1's first column), v its v
/// rescaled to [0, 1]. The closest point is the nearest of
/// the patches' closest points, each by Newton's method
/// (detail/surface_projection.hpp) from the best point of a sample grid taken
/// here; patches whose (inflated) sampled bounding box is farther than the
/// best distance so far are skipped. (OccSurface::project would add
/// OpenCASCADE's global extrema for every point off the surface, which every
/// point projected while curving is: minutes at p = 4.)
class PatchedSurface {
 public:
  explicit PatchedSurface(std::vector<hom::cad::OccSurface> patches) : patches_(std::move(patches)) {
    for (const auto& s : patches_) {
      const auto ru = s.range(0), rv = s.range(1);
      if (!ru.bounded() || !rv.bounded()) throw std::invalid_argument("PatchedSurface: unbounded patch");
      Patch b{Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()),
              Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity()), {}, {}};
      for (int i = 0; i <= samples; ++i)
        for (int j = 0; j <= samples; ++j) {
          const Eigen::Vector2d uv(ru.lo + ru.length() * i / samples, rv.lo + rv.length() * j / samples);
          const Eigen::Vector3d x = s.evaluate(uv);
          b.lo = b.lo.cwiseMin(x);
          b.hi = b.hi.cwiseMax(x);
          // Starts at a degenerate side (a pole: S_u = 0) would leave Newton
          // stuck there, projecting every point near the pole onto it.
          const Eigen::Matrix<double, 3, 2> d = s.derivatives(uv);
          if (d.col(0).norm() < 1e-8 * s.size() || d.col(1).norm() < 1e-8 * s.size()) continue;
          b.uv.push_back(uv);
          b.x.push_back(x);
        }
      // The samples miss the bulge between them: inflate by a tenth of the size.
      const Eigen::Vector3d pad = Eigen::Vector3d::Constant(0.1 * (b.hi - b.lo).norm());
      b.lo -= pad;
      b.hi += pad;
      info_.push_back(std::move(b));
    }
  }

  Eigen::Vector3d evaluate(const Eigen::Vector2d& uv) const {
    const auto [k, local] = locate(uv);
    return patches_[k].evaluate(local);
  }
  Eigen::Matrix<double, 3, 2> derivatives(const Eigen::Vector2d& uv) const {
    const auto [k, local] = locate(uv);
    Eigen::Matrix<double, 3, 2> d = patches_[k].derivatives(local);
    d.col(0) *= patches_[k].range(0).length();
    d.col(1) *= patches_[k].range(1).length();
    return d;
  }
  hom::SurfaceSecondDerivatives second_derivatives(const Eigen::Vector2d& uv) const {
    const auto [k, local] = locate(uv);
    auto s = patches_[k].second_derivatives(local);
    const double a = patches_[k].range(0).length(), b = patches_[k].range(1).length();
    s.uu *= a * a;
    s.uv *= a * b;
    s.vv *= b * b;
    return s;
  }
  Eigen::Vector2d project(const Eigen::Vector3d& x) const {
    std::vector<std::pair<double, int>> order;
    for (int k = 0; k < int(patches_.size()); ++k)
      order.push_back({(x - x.cwiseMax(info_[k].lo).cwiseMin(info_[k].hi)).norm(), k});
    std::sort(order.begin(), order.end());
    double best = std::numeric_limits<double>::infinity();
    Eigen::Vector2d out(0, 0);
    for (const auto& [box_distance, k] : order) {
      if (box_distance > best) break;
      const auto& in = info_[k];
      std::size_t start = 0;
      for (std::size_t i = 1; i < in.x.size(); ++i)
        if ((in.x[i] - x).squaredNorm() < (in.x[start] - x).squaredNorm()) start = i;
      Eigen::Vector2d local = hom::detail::closest_point_newton(patches_[k], x, in.uv[start]);
      double d = (patches_[k].evaluate(local) - x).norm();
      // Newton ended on a degenerate side: OpenCASCADE's projection decides.
      const Eigen::Matrix<double, 3, 2> D = patches_[k].derivatives(local);
      if (D.col(0).norm() < 1e-6 * patches_[k].size() || D.col(1).norm() < 1e-6 * patches_[k].size()) {
        const Eigen::Vector2d occ = patches_[k].project(x);
        const double d_occ = (patches_[k].evaluate(occ) - x).norm();
        if (d_occ < d) local = occ, d = d_occ;
      }
      if (d < best) {
        best = d;
        const auto ru = patches_[k].range(0), rv = patches_[k].range(1);
        out = {2 * k + std::clamp((local[0] - ru.lo) / ru.length(), 0.0, 1.0),
               std::clamp((local[1] - rv.lo) / rv.length(), 0.0, 1.0)};
      }
    }
    return out;
  }
  hom::ParameterRange range(int k) const {
    return k == 0 ? hom::ParameterRange{0.0, 2.0 * double(patches_.size()) - 1.0, false} : hom::ParameterRange{0.0, 1.0, false};
  }

 private:
  static constexpr int samples = 12;
  struct Patch {
    Eigen::Vector3d lo, hi;            ///< inflated bounding box of the samples
    std::vector<Eigen::Vector2d> uv;   ///< sample grid
    std::vector<Eigen::Vector3d> x;    ///< S at the samples
  };
  std::pair<int, Eigen::Vector2d> locate(const Eigen::Vector2d& uv) const {
    const int k = std::clamp(int(std::floor(uv[0] / 2)), 0, int(patches_.size()) - 1);
    const auto ru = patches_[k].range(0), rv = patches_[k].range(1);
    return {k, Eigen::Vector2d(ru.lo + std::clamp(uv[0] - 2 * k, 0.0, 1.0) * ru.length(), rv.lo + uv[1] * rv.length())};
  }
  std::vector<hom::cad::OccSurface> patches_;
  std::vector<Patch> info_;
};

static_assert(hom::SurfaceGeometry<PatchedSurface>);

/// A row of tables 6.4 / 6.5.
struct ThesisRow {
  int p, elements, nodes;
  double min_q, max_q, mean_q, std_q;
  int inverted;
};

// Table 6.4 (sphere, p = 4) and table 6.5 (SD7003 wing section, p = 4), by stage.
const std::vector<std::pair<std::string, ThesisRow>> thesis_6_4 = {
    {"inviscid", {1, 18936, 3753, 1.00, 1.00, 1.00, 0.00, 0}},
    {"inserted", {1, 43922, 8595, 0.32, 1.00, 0.61, 0.34, 0}},
    {"smoothed", {1, 43922, 8595, 0.97, 1.00, 1.00, 0.00, 0}},
    {"curved", {4, 43922, 487082, 0.00, 1.00, 0.98, 0.09, 311}},
    {"optimized", {4, 43922, 487082, 0.44, 1.00, 0.99, 0.02, 0}}};
const std::vector<std::pair<std::string, ThesisRow>> thesis_6_5 = {
    {"inviscid", {1, 7506, 12430, 1.00, 1.00, 1.00, 0.00, 0}},
    {"inserted", {1, 121898, 22205, 0.00, 1.00, 0.24, 0.18, 396}},
    {"smoothed", {1, 121898, 22205, 0.70, 1.00, 0.96, 0.04, 0}},
    {"curved", {4, 121898, 1327354, 0.00, 1.00, 0.93, 0.17, 3590}},
    {"optimized", {4, 121898, 1327354, 0.21, 1.00, 0.96, 0.04, 0}}};

struct Settings {
  fs::path out = "results/boundary_layer";
  std::string vtu_dir;
  bool quick = false;
  int threads = 0;
  int iterations_after_valid = 3;
  int max_iterations = 200;
  bool certify = true;
  hom::SolverKind solver = hom::SolverKind::newton;  ///< both optimizer stages
  bool p_continuation = false;                       ///< stage (e) (appendix C)
  /// Both stages when set; unset keeps the pipeline's default (whole-mesh,
  /// BoundaryLayerPipelineOptions).
  std::optional<hom::RegularizationScope> scope;
  bool verbose = false;
  bool plot = true;
  fs::path plot_script = HOM_PLOT_SCRIPT;
};

/// What one pipeline run is and gives, for the tables and the report.
struct RunInfo {
  std::string name, family, table, wall;
  hom::BoundaryLayerOptions layer;
  double aspect_ratio = 0.0;
  double wall_distance = std::numeric_limits<double>::quiet_NaN();  ///< max distance of final wall nodes to the wall
  const std::vector<std::pair<std::string, ThesisRow>>* thesis = nullptr;
};

class Runner {
 public:
  explicit Runner(Settings s) : s_(std::move(s)), checks_("bench_boundary_layer") {
    csv_ << "case,family,stage,p,elements,nodes,min_q,max_q,mean_q,std_q,inverted,min_sj,iterations,converged,stop_"
            "reason,time_s,aspect_ratio,first_height,growth,layers,total_height,thesis_table,thesis_min_q,thesis_max_q,"
            "thesis_mean_q,thesis_std_q,thesis_inverted\n";
  }

  const Settings& settings() const { return s_; }
  hom::bench::Checks& checks() { return checks_; }

  hom::BoundaryLayerPipelineOptions pipeline_options(const hom::BoundaryLayerOptions& layer, int p) const {
    hom::BoundaryLayerPipelineOptions o;
    o.layer = layer;
    o.p = p;
    for (auto* opt : {&o.linear_optimize, &o.high_order_optimize}) {
      opt->threads = s_.threads;
      opt->max_iterations = s_.max_iterations;
      opt->verbose = s_.verbose;
      opt->solver = s_.solver;
      if (s_.scope) opt->regularization_scope = *s_.scope;
    }
    o.high_order_optimize.p_continuation = s_.p_continuation;
    o.high_order_optimize.iterations_after_valid = s_.iterations_after_valid;
    o.high_order_optimize.certify = s_.certify;
    if (s_.verbose) o.progress = [](const std::string& st) { std::fprintf(stderr, "  stage %s done\n", st.c_str()); };
    return o;
  }

  /// The optimizer options of stage `stage` ("smoothed": (c), "optimized":
  /// (e)) as pipeline_options sets them; none for the other stages.
  std::optional<hom::OptimizeOptions> stage_optimizer(const std::string& stage, const hom::BoundaryLayerOptions& layer,
                                                      int p) const {
    if (stage == "smoothed") return pipeline_options(layer, p).linear_optimize;
    if (stage == "optimized") return pipeline_options(layer, p).high_order_optimize;
    return std::nullopt;
  }

  /// Prints the table of one run and records its CSV rows and JSON cases.
  template <int Dim>
  void report(const RunInfo& info, const hom::BoundaryLayerPipelineResult<Dim>& r) {
    const double rss = hom::bench::peak_rss_mb();
    std::printf("   %-9s %2s %7s %8s %6s %6s %6s %6s %6s %7s %5s %8s", "stage", "p", "elems", "nodes", "Min", "Max", "Mean",
                "Std", "#inv", "min SJ", "iter", "time s");
    if (info.thesis) std::printf("   | table %s: %6s %8s %5s %5s %5s %5s %5s", info.table.c_str(), "elems", "nodes", "Min",
                                 "Max", "Mean", "Std", "#inv");
    std::printf("\n");
    for (const auto& st : r.stages) {
      const ThesisRow* th = nullptr;
      if (info.thesis)
        for (const auto& [name, row] : *info.thesis)
          if (name == st.name) th = &row;
      const auto& q = st.quality;
      print_statistics(st.name, st.p, st.elements, st.nodes, q, st.scaled_jacobian.min);
      std::printf(" %5d %8.2f", st.iterations, st.time_s);
      if (th)
        std::printf("   | %*s %6d %8d %5.2f %5.2f %5.2f %5.2f %5d", int(info.table.size()) + 7, "", th->elements, th->nodes,
                    th->min_q, th->max_q, th->mean_q, th->std_q, th->inverted);
      std::printf("\n");
      const auto& L = info.layer;
      csv_ << info.name << ',' << info.family << ',' << st.name << ',' << st.p << ',' << st.elements << ',' << st.nodes
           << ',' << q.min << ',' << q.max << ',' << q.mean << ',' << q.std_dev << ',' << q.inverted << ','
           << st.scaled_jacobian.min << ',' << st.iterations << ',' << st.converged << ',' << st.stop_reason << ','
           << st.time_s << ',' << info.aspect_ratio << ',' << L.first_height << ',' << L.growth << ',' << L.layers << ','
           << L.total_height() << ',' << (th ? info.table : "") << ',' << (th ? fmt(th->min_q) : "") << ','
           << (th ? fmt(th->max_q) : "") << ',' << (th ? fmt(th->mean_q) : "") << ',' << (th ? fmt(th->std_q) : "") << ','
           << (th ? std::to_string(th->inverted) : "") << '\n';
      hom::io::CaseHeader h{info.name, info.family, st.p, st.elements, st.nodes, st.name, "shape", st.ideal};
      auto j = hom::io::quality_case(h, st.quality, st.scaled_jacobian);
      j.set("time_s", st.time_s)
          .set("iterations", st.iterations)
          .set("converged", st.converged)
          .set("peak_rss_mb", rss)
          .set("threads", s_.threads)
          .set("aspect_ratio", info.aspect_ratio)
          .set("layers", L.layers)
          .set("first_height", L.first_height)
          .set("growth", L.growth)
          .set("total_height", L.total_height())
          .set("extrusion_fraction", L.extrusion_fraction)
          .set("wall", info.wall);
      if (!st.stop_reason.empty()) j.set("stop_reason", st.stop_reason);
      if (const auto opt = stage_optimizer(st.name, info.layer, st.p))
        j.set("solver", std::string(hom::to_string(opt->solver)))
            .set("p_continuation", opt->p_continuation)
            .set("regularization_scope", std::string(hom::to_string(opt->regularization_scope)));
      if (st.name == "optimized" && std::isfinite(info.wall_distance)) j.set("wall_max_distance", info.wall_distance);
      if (st.name == "optimized" && r.certification) {
        j.set("certified", r.certification->certified());
        hom::io::add_certification(j, *r.certification, hom::OptimizeOptions{}.certify_depth);
      }
      if (th) {
        auto t = hom::io::Json::object();
        t.set("table", info.table)
            .set("p", th->p)
            .set("elements", th->elements)
            .set("nodes", th->nodes)
            .set("min_q", th->min_q)
            .set("max_q", th->max_q)
            .set("mean_q", th->mean_q)
            .set("std_q", th->std_q)
            .set("inverted", th->inverted);
        j.set("thesis", t);
      }
      cases_.push_back(std::move(j));
    }
    std::fflush(stdout);
  }

  /// Table 3.4: the final mesh's absolute quality, against the equilateral
  /// ideal (section 3.3.2.2), printed under the table of report(), whose
  /// "optimized" row is the relative quality (against the smoothed linear
  /// mesh). One JSON case: stage "optimized", ideal "equilateral".
  template <int Dim>
  void report_absolute(const RunInfo& info, const hom::BoundaryLayerPipelineResult<Dim>& r) {
    if (r.stopped_after_smoothing) return;
    const auto q = hom::mesh_quality(r.mesh, hom::ShapeMeasure{}, hom::IdealKind::regular,
                                     hom::quadrature_for<hom::Simplex<Dim>, hom::DefaultExactness>(r.mesh.degree()));
    const hom::Statistics s = q.quality_statistics(), sj = q.scaled_jacobian_statistics();
    print_statistics("optimized", r.mesh.degree(), r.mesh.num_elements(), r.mesh.num_nodes(), s, sj.min);
    std::printf("   (absolute: equilateral ideal)\n");
    hom::io::CaseHeader h{info.name, info.family, r.mesh.degree(), r.mesh.num_elements(), r.mesh.num_nodes(),
                          "optimized", "shape", "equilateral"};
    cases_.push_back(hom::io::quality_case(h, s, sj).set("aspect_ratio", info.aspect_ratio).set("wall", info.wall));
    std::fflush(stdout);
  }

  /// The certify stage of (e) (on unless --no-certify), when it ran.
  template <int Dim>
  void report_certification(const hom::BoundaryLayerPipelineResult<Dim>& r) const {
    if (r.certification) hom::io::print_certification(*r.certification, hom::OptimizeOptions{}.certify_depth);
  }

  /// One row of the stage table: stage, p, size, quality statistics, min scaled Jacobian (no newline).
  static void print_statistics(const std::string& stage, int p, int elements, int nodes, const hom::Statistics& q,
                               double min_sj) {
    std::printf("   %-9s %2d %7d %8d %6.3f %6.3f %6.3f %6.3f %6d %7.3f", stage.c_str(), p, elements, nodes, q.min, q.max,
                q.mean, q.std_dev, q.inverted, min_sj);
  }

  /// VTU files of the inserted, smoothed and final meshes (--vtu-dir).
  template <int Dim>
  void write_vtu(const std::string& name, const hom::BoundaryLayerPipelineResult<Dim>& r) const {
    if (s_.vtu_dir.empty()) return;
    fs::create_directories(s_.vtu_dir);
    auto one = [&](const std::string& stage, const hom::Mesh<hom::Simplex<Dim>>& m, const hom::IdealMesh<hom::Simplex<Dim>>& ideal) {
      const auto q = hom::mesh_quality(m, hom::ShapeMeasure{}, ideal,
                                       hom::quadrature_for<hom::Simplex<Dim>, hom::DefaultExactness>(m.degree()));
      std::vector<double> level;
      for (const auto& l : r.layer.level) level.push_back(l ? double(*l) : -1.0);
      hom::io::VtuOptions vo;
      vo.interpolate_point_data = false;
      hom::io::write_vtu((fs::path(s_.vtu_dir) / (name + "_" + stage + ".vtu")).string(), m, {},
                         {{"quality", 1, q.qualities()}, {"scaled_jacobian", 1, q.scaled_jacobians()}, {"level", 1, level}},
                         vo);
    };
    one("inserted", r.layer.mesh, r.layer.ideal);
    one("smoothed", r.smoothed, r.layer.ideal);
    if (!r.stopped_after_smoothing) one("optimized_p" + std::to_string(r.mesh.degree()), r.mesh, r.final_ideal());
  }

  /// OUT/cut_<name>.csv: the cut of a case's final mesh by `plane`, with the
  /// element quality of the table's last stage (`ideal` is what that stage
  /// measures against).
  void write_cut(const std::string& name, const hom::Mesh<hom::Simplex<3>>& m, const hom::IdealMesh<hom::Simplex<3>>& ideal,
                 const std::vector<std::optional<int>>& level, const hom::bench::CutPlane& plane) {
    const auto q = hom::mesh_quality(m, hom::ShapeMeasure{}, ideal,
                                     hom::quadrature_for<hom::Simplex<3>, hom::DefaultExactness>(m.degree()));
    const auto polygons = hom::bench::cut_mesh(m, plane, hom::bench::cut_lattice_degree(m.degree()));
    fs::create_directories(s_.out);
    const fs::path path = s_.out / ("cut_" + name + ".csv");
    hom::bench::write_cut_csv(path.string(), polygons, q, level);
    std::printf("   cut: %zu polygons -> %s\n", polygons.size(), path.string().c_str());
    cuts_.push_back(name);
  }

  /// Draws the cuts written so far (cut_<case>.png beside the CSVs). A
  /// missing Python, matplotlib or script only skips the figures: the harness
  /// reproduces tables, the figures are a convenience.
  void plot_cuts() const {
    if (s_.plot && !cuts_.empty()) hom::bench::run_plot_script(s_.plot_script, s_.out, cuts_, "matplotlib, numpy");
  }

  int finish(const std::string& csv, const std::string& json) {
    fs::create_directories(s_.out);
    const std::string cpath = csv.empty() ? (s_.out / "boundary_layer.csv").string() : csv;
    const std::string jpath = json.empty() ? (s_.out / "boundary_layer.json").string() : json;
    {
      std::ofstream f(cpath);
      f << csv_.str();
    }
    hom::io::write_report(jpath, "bench_boundary_layer", HOM_VERSION, cases_, checks_.all());
    std::printf("\nwrote %s and %s\n", cpath.c_str(), jpath.c_str());
    std::printf("%d checks, %zu failed\n", checks_.count(), checks_.failures().size());
    for (const auto& f : checks_.failures()) std::printf("  FAILED: %s\n", f.c_str());
    return checks_.failures().empty() ? 0 : 1;
  }

 private:
  Settings s_;
  hom::bench::Checks checks_;
  std::ostringstream csv_;
  std::vector<hom::io::Json> cases_;
  std::vector<std::string> cuts_;  ///< cases whose cut CSV was written
};

/// Largest distance of the final mesh's wall-facet nodes to `surface`
/// (a check that they were put on the wall geometry).
template <int Dim, class Distance>
double wall_distance(const hom::Mesh<hom::Simplex<Dim>>& m, const std::vector<int>& walls, Distance&& distance) {
  double d = 0.0;
  for (const auto& f : m.boundary_facets())
    if (std::find(walls.begin(), walls.end(), f.entity_tag) != walls.end())
      for (int n : m.facet_node_ids(f)) d = std::max(d, distance(m.node(n)));
  return d;
}

// --- sphere (table 6.4) ------------------------------------------------------

void run_sphere(Runner& run, int p, bool analytic_wall) {
  const bool quick = run.settings().quick;
  std::printf("\n== sphere: diameter 1 in a box, wall = 8 exact NURBS octants (nurbs_sphere_model), p = %d\n", p);
  hom::meshing::CubeWithCavityOptions mo;
  // Scaled down from the thesis's 18936 tetrahedra (sphere size ~0.08) to
  // keep p = 4 within minutes; a coarser wall (0.4) leaves the layer thinner
  // than the sub-facets' curving allows (inverted at (d), slow (e)).
  mo.side = 2.0;
  mo.cube_size = 0.8;
  mo.sphere_size = 0.3;
  const auto t0 = std::chrono::steady_clock::now();
  const auto cav = hom::meshing::cube_with_cavity(mo);
  std::printf("   inviscid mesh: %d tetrahedra, %d nodes (Gmsh, %.2f s)\n", cav.mesh.num_elements(), cav.mesh.num_nodes(),
              hom::bench::seconds_since(t0));
  const auto nurbs = hom::cad::nurbs_sphere_model(cav.center, cav.radius);
  std::vector<hom::cad::OccSurface> octants;
  for (int f = 1; f <= nurbs.num_faces(); ++f) octants.push_back(nurbs.surface(f));
  std::printf("   wall CAD: %s (%d patches, %s)\n", nurbs.summary().c_str(), int(octants.size()),
              octants.front().type().c_str());
  hom::GeometryModel<3> geometry = cav.geometry;  // the box's planes and edges, the exact sphere
  if (analytic_wall)
    std::printf("   --sphere-wall analytic: the wall is hom::Sphere, not the NURBS octants\n");
  else
    geometry.add_surface(cav.sphere_tag, PatchedSurface(octants));
  // Thesis: 3 layers (24986 inserted = 806 wall triangles x (12 x 2 + 7)).
  // First height 0.01 (aspect ratio ~ 10 on sub-facets of ~0.15), growth 2:
  // H = 0.07, above the sub-facets' sagitta (~0.006).
  RunInfo info{"sphere", "tetrahedron", "6.4",
               analytic_wall ? "hom::Sphere (analytic)" : "nurbs_sphere_model (8 rational B-spline octants)", {}, 0, 0,
               &thesis_6_4};
  info.layer = {.first_height = 0.01, .growth = 2.0, .layers = quick ? 2 : 3};
  const auto r = hom::boundary_layer_pipeline<3>(cav.mesh, {cav.sphere_tag}, geometry, run.pipeline_options(info.layer, p));
  info.aspect_ratio = r.layer.max_aspect_ratio;
  info.wall_distance = wall_distance<3>(r.mesh, {cav.sphere_tag},
                                        [&](const Eigen::Vector3d& x) { return std::abs((x - cav.center).norm() - cav.radius); });
  std::printf("   layers %d, first height %g, growth %g, H %g, %d wall facets, max aspect ratio %.3g, total %.1f s\n",
              info.layer.layers, info.layer.first_height, info.layer.growth, info.layer.total_height(),
              r.layer.num_wall_facets, info.aspect_ratio, r.time_s);
  run.report(info, r);
  run.report_certification(r);
  std::printf("   final wall nodes: max | |x - c| - r | = %.2e\n", info.wall_distance);
  run.write_vtu("sphere", r);
  run.write_cut("sphere", r.mesh, r.final_ideal(), r.layer.level, hom::bench::CutPlane::normal_z(cav.center));
  run.checks().expect(r.valid, "sphere p = " + std::to_string(p) + ": final boundary-layer mesh valid (0 inverted, det > 0 at every node)");
}

// --- wing (table 6.5) --------------------------------------------------------

void run_wing(Runner& run, int p, const std::string& airfoil) {
  const bool quick = run.settings().quick;
  std::vector<Eigen::Vector2d> profile;
  std::string profile_name;
  if (airfoil != "naca0012" && fs::exists(airfoil)) {
    profile = hom::meshing::read_selig_airfoil(airfoil);
    profile_name = "SD7003 (" + airfoil + ")";
  } else {
    profile = hom::meshing::naca_00xx(0.12, 41);
    profile_name = airfoil == "naca0012" ? "NACA 0012 (analytic)" : "NACA 0012 (analytic; " + airfoil + " not found)";
  }
  std::printf("\n== wing: %s, %zu points, extruded wing section in a box, p = %d\n", profile_name.c_str(), profile.size(), p);
  hom::meshing::AirfoilSectionOptions ao;
  ao.profile = profile;
  ao.span = 0.15;
  ao.lo = {-1.5, -1.5};
  ao.hi = {2.5, 1.5};
  fs::create_directories(run.settings().out);
  const std::string brep = (run.settings().out / "wing_section.brep").string();
  hom::meshing::write_airfoil_section_brep(ao, brep);
  const auto cad = hom::cad::read_cad(brep);
  std::printf("   %s\n", cad.summary().c_str());
  // The wall: every face off the box's six planes (the profile's faces).
  auto on_box = [&](const Eigen::Vector3d& x) {
    const double tol = 1e-9;
    return std::abs(x[0] - ao.lo[0]) < tol || std::abs(x[0] - ao.hi[0]) < tol || std::abs(x[1] - ao.lo[1]) < tol ||
           std::abs(x[1] - ao.hi[1]) < tol || std::abs(x[2]) < tol || std::abs(x[2] - ao.span) < tol;
  };
  std::vector<int> walls;
  for (int f = 1; f <= cad.num_faces(); ++f) {
    const auto g = cad.surface(f);
    const auto ru = g.range(0), rv = g.range(1);
    if (!on_box(g.evaluate({ru.lo + 0.5 * ru.length(), rv.lo + 0.5 * rv.length()}))) walls.push_back(f);
  }
  hom::cad::CadMeshOptions mo;
  const double wing_size = quick ? 0.15 : 0.12, far_size = 0.8;
  mo.size = far_size;
  for (int v = 1; v <= cad.num_vertices(); ++v)  // the box's corners coarse, the profile's ends fine
    mo.vertex_sizes[v] = std::abs(cad.vertex(v)[0] - 0.5) > 1.5 ? far_size : wing_size;
  const auto t0 = std::chrono::steady_clock::now();
  const auto mesh = hom::cad::mesh_cad<hom::Simplex<3>>(cad, mo);
  std::printf("   inviscid mesh: %d tetrahedra, %d nodes (Gmsh, %.2f s), wall faces:", mesh.num_elements(), mesh.num_nodes(),
              hom::bench::seconds_since(t0));
  for (int w : walls) std::printf(" %d (%s)", w, cad.surface(w).type().c_str());
  std::printf("\n");
  // 7 layers growing by 2 (thesis). First height 2e-4 chords: H = 127 h0 =
  // 0.0254, above the sagitta of the sub-facets except at the leading edge.
  RunInfo info{"wing", "tetrahedron", "6.5", "extruded B-spline faces of the BREP", {}, 0, 0, &thesis_6_5};
  info.layer = {.first_height = 2e-4, .growth = 2.0, .layers = 7};
  const auto geometry = cad.geometry_model();
  const auto mid_span = hom::bench::CutPlane::normal_z(Eigen::Vector3d(0.0, 0.0, 0.5 * ao.span));
  auto finish = [&](const hom::BoundaryLayerPipelineResult<3>& r) {
    info.aspect_ratio = r.layer.max_aspect_ratio;
    std::printf("   layers %d, first height %g, growth %g, H %g, %d wall facets, max aspect ratio %.3g, total %.1f s\n",
                info.layer.layers, info.layer.first_height, info.layer.growth, info.layer.total_height(),
                r.layer.num_wall_facets, info.aspect_ratio, r.time_s);
    run.report(info, r);
    run.report_absolute(info, r);
    run.report_certification(r);
    run.write_vtu("wing", r);
  };
  // When the smoothed linear mesh is still tangled the pipeline stops there
  // (stop_if_smoothed_invalid): the degree-p stages cannot end valid.
  const auto r = hom::boundary_layer_pipeline<3>(mesh, walls, geometry, run.pipeline_options(info.layer, p));
  info.wall_distance = wall_distance<3>(r.mesh, walls, [&](const Eigen::Vector3d& x) {
    return (hom::detail::project_to_nearest_wall<3>(geometry, walls, x) - x).norm();
  });
  finish(r);
  // The cut is of the table's last mesh, with its quality.
  run.write_cut("wing", r.mesh, r.final_ideal(), r.layer.level, mid_span);
  if (r.stopped_after_smoothing)
    std::printf("   the smoothed linear mesh has %d inverted elements: stages (d) and (e) at p = %d not run\n",
                r.stages.back().quality.inverted, p);
  else
    std::printf("   final wall nodes: max distance to the wall faces %.2e\n", info.wall_distance);
  run.checks().expect(r.valid, "wing p = " + std::to_string(p) + ": final boundary-layer mesh valid (0 inverted, det > 0 at every node)");
}

// --- stretching study --------------------------------------------------------

/// Quarter annulus 0.5 <= r <= 1.5, 0 <= theta <= pi / 2 of triangles (the
/// structured (r, theta) box mapped to Cartesian coordinates); the inner
/// circle (box side r = lo, tag 1) is the wall.
hom::Mesh<hom::Simplex<2>> quarter_annulus(int nr, int nt) {
  auto m = hom::structured_mesh<hom::Simplex<2>>({nr, nt}, Eigen::Vector2d(0.5, 0.0), Eigen::Vector2d(1.5, std::numbers::pi / 2));
  for (int i = 0; i < m.num_nodes(); ++i) {
    const Eigen::Vector2d q = m.node(i);
    m.node(i) = Eigen::Vector2d(q[0] * std::cos(q[1]), q[0] * std::sin(q[1]));
  }
  m.reset_ideal();
  return m;
}

/// The growth g >= 1 with h0 (g^L - 1) / (g - 1) = H (bisection in log g).
double growth_for(double h0, int layers, double H) {
  auto total = [&](double g) { return g == 1.0 ? h0 * layers : h0 * (std::pow(g, layers) - 1) / (g - 1); };
  if (total(1.0) >= H) return 1.0;
  double lo = 0.0, hi = std::log(1e9);
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (total(std::exp(mid)) < H ? lo : hi) = mid;
  }
  return std::exp(0.5 * (lo + hi));
}

void run_stretching(Runner& run, const std::vector<int>& degrees) {
  const bool quick = run.settings().quick;
  const int nt = quick ? 8 : 12;
  const auto in = quarter_annulus(4, nt);
  const int wall = 1;  // r = 0.5
  const hom::Circle<2> circle(Eigen::Vector2d::Zero(), 0.5);
  hom::GeometryModel<2> geometry;
  geometry.add_curve(wall, circle);
  const hom::WallProjection<2> project = [&](const Eigen::Vector2d& x, const std::vector<int>&) {
    return circle.evaluate(circle.project(x));
  };
  const int layers = quick ? 6 : 8;
  const double H = 0.1;  // total height: 40% of the first ring of the annulus
  const std::vector<int> exponents = quick ? std::vector<int>{2, 6} : std::vector<int>{2, 4, 6, 8};
  std::printf("\n== stretching: quarter annulus (circle of diameter 1 as wall), %d triangles, %d layers, H = %g\n",
              in.num_elements(), layers, H);
  struct Row {
    int exponent, p;
    double ar, h0, growth, min_smoothed, min_final;
    int inv_curved, inv_final, it_c, it_e;
    double time;
    bool valid;
  };
  std::vector<Row> rows;
  for (int e : exponents) {
    const double target = std::pow(10.0, e);
    // h0 for the target aspect ratio: the first level's aspect ratio is about
    // (sub-facet length) / h0, so rescale h0 by measured / target (twice).
    hom::BoundaryLayerOptions layer;
    layer.layers = layers;
    layer.first_height = (std::numbers::pi / 4 / nt) / target;
    double ar = 0.0;
    for (int k = 0; k < 3; ++k) {
      layer.growth = growth_for(layer.first_height, layers, H);
      ar = hom::insert_boundary_layer(in, {wall}, layer, project).max_aspect_ratio;
      if (k < 2) layer.first_height *= ar / target;
    }
    for (int p : degrees) {
      RunInfo info{"stretching_ar1e" + std::to_string(e) + "_p" + std::to_string(p), "triangle", "", "circle", layer, 0, 0,
                   nullptr};
      const auto r = hom::boundary_layer_pipeline<2>(in, {wall}, geometry, run.pipeline_options(layer, p));
      info.aspect_ratio = r.layer.max_aspect_ratio;
      std::printf("\n   aspect ratio %.3g (target 1e%d), h0 %.3g, growth %.4g, p = %d\n", info.aspect_ratio, e,
                  layer.first_height, layer.growth, p);
      run.report(info, r);
      run.report_certification(r);
      run.write_vtu(info.name, r);
      // Stopped at a tangled (c): no (d) and (e) (NaN, -1).
      const auto& st = r.stages;
      const bool all = !r.stopped_after_smoothing;
      rows.push_back({e, p, info.aspect_ratio, layer.first_height, layer.growth, st[2].quality.min,
                      all ? st[4].quality.min : std::nan(""), all ? st[3].quality.inverted : -1,
                      all ? st[4].quality.inverted : -1, st[2].iterations, all ? st[4].iterations : 0, r.time_s, r.valid});
      if (e <= 6)
        run.checks().expect(r.valid, "stretching 1:1e" + std::to_string(e) + " p = " + std::to_string(p) +
                                         ": final boundary-layer mesh valid (0 inverted, det > 0 at every node)");
    }
  }
  std::printf("\n   stretching summary (smoothed = stage c at p = 1, final = stage e)\n");
  std::printf("   %8s %10s %10s %9s %2s %6s %8s %8s %9s %7s %7s %8s\n", "target", "aspect", "h0", "growth", "p", "valid",
              "min (c)", "#inv (d)", "min final", "it (c)", "it (e)", "time s");
  for (const auto& w : rows)
    std::printf("   %8s %10.3g %10.3g %9.4g %2d %6s %8.3f %8d %9.3f %7d %7d %8.2f\n", ("1e" + std::to_string(w.exponent)).c_str(),
                w.ar, w.h0, w.growth, w.p, w.valid ? "yes" : "NO", w.min_smoothed, w.inv_curved, w.min_final, w.it_c, w.it_e,
                w.time);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  Settings s;
  std::vector<std::string> names;
  std::string csv, json, airfoil, sphere_wall, solver, scope;
  int p = 4;
  po::options_description desc(
      "bench_boundary_layer [options]: section 6.3.3's curved boundary layers (tables 6.4, 6.5) and the\n"
      "stretching study of issue 9 (see the file comment)");
  desc.add_options()("help,h", "show this help")                                                            //
      ("case", po::value(&names)->composing(), "case to run (repeatable): sphere, wing, stretching (default all)")  //
      ("p", po::value(&p)->default_value(4), "degree of the sphere and wing cases (the stretching study: 2 and p)")  //
      ("threads", po::value(&s.threads)->default_value(0), "threads (0: OpenMP's default)")                //
      ("out", po::value<std::string>()->default_value("results/boundary_layer"), "output directory")       //
      ("csv", po::value(&csv), "CSV table (default OUT/boundary_layer.csv)")                               //
      ("json", po::value(&json), "JSON report (default OUT/boundary_layer.json)")                          //
      ("vtu-dir", po::value(&s.vtu_dir), "write VTU files of the inserted, smoothed and final meshes here")  //
      ("airfoil", po::value(&airfoil)->default_value("../shared/data/cad/sd7003.dat"),
       "Selig airfoil file of the wing case, or naca0012 (also when the file is absent, and with --quick)")  //
      ("sphere-wall", po::value(&sphere_wall)->default_value("nurbs"),
       "sphere case's wall geometry: nurbs (the 8 NURBS octants) or analytic (hom::Sphere)")  //
      ("quick", po::bool_switch(&s.quick), "CI-sized: p = 2 unless --p, coarser wing, fewer layers and aspect ratios")  //
      ("iterations-after-valid", po::value(&s.iterations_after_valid)->default_value(3),
       "high-order stage: stop once valid this many iterations (-1: optimize to convergence)")  //
      ("max-iterations", po::value(&s.max_iterations)->default_value(200), "per optimizer stage")  //
      ("solver", po::value(&solver)->default_value("newton"),
       "solver of stages (c) and (e): newton, matrix-free or gauss-seidel")  //
      ("p-continuation", po::bool_switch(&s.p_continuation),
       "stage (e): untangle the linear sub-mesh first (appendix C)")  //
      ("regularization-scope", po::value(&scope),
       "elements regularized while the mesh is invalid, stages (c) and (e): invalid or whole-mesh (default: the "
       "pipeline's, whole-mesh)")  //
      ("no-certify", 
       "no certify-and-repair stage after stage (e) (Bernstein bounds; on by default)")  //
      ("verbose,v", po::bool_switch(&s.verbose), "optimizer progress on stderr")  //
      ("no-plot", "do not draw the cut figures (the cut CSVs are still written)")  //
      ("plot-script", po::value<std::string>()->default_value(s.plot_script.string()), "path of plot_boundary_layer.py");
  try {
    po::variables_map vm;
    po::store(po::parse_command_line(argc, argv, desc), vm);
    po::notify(vm);
    if (vm.count("help")) {
      std::cout << desc << "\n";
      return 0;
    }
    s.out = vm["out"].as<std::string>();
    s.plot = !vm.count("no-plot");
    s.certify = !vm.count("no-certify");
    s.solver = hom::parse_solver_kind(solver);
    if (vm.count("regularization-scope")) s.scope = hom::parse_regularization_scope(scope);
    s.plot_script = vm["plot-script"].as<std::string>();
    if (s.quick && vm["p"].defaulted()) p = 2;
    if (s.quick && vm["airfoil"].defaulted()) airfoil = "naca0012";
    if (sphere_wall != "nurbs" && sphere_wall != "analytic") throw std::invalid_argument("--sphere-wall: nurbs or analytic");
    if (p < 1 || p > 10) throw std::invalid_argument("--p must be in 1..10");
    for (const auto& n : names)
      if (n != "sphere" && n != "wing" && n != "stretching") throw std::invalid_argument("unknown case '" + n + "'");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_boundary_layer: %s\n", e.what());
    return 2;
  }
  auto selected = [&](const std::string& n) { return names.empty() || std::find(names.begin(), names.end(), n) != names.end(); };
  std::printf("bench_boundary_layer %s: shape measure, threads %d, high-order stage stops %d iterations after valid%s\n",
              HOM_VERSION, s.threads, s.iterations_after_valid, s.quick ? ", quick" : "");
  Runner run(s);
  const auto start = std::chrono::steady_clock::now();
  auto guarded = [&](const std::string& name, auto&& f) {
    try {
      f();
    } catch (const std::exception& e) {
      std::printf("   %s FAILED: %s\n", name.c_str(), e.what());
      run.checks().expect(false, name + ": " + e.what());
    }
  };
  if (selected("sphere")) guarded("sphere", [&] { run_sphere(run, p, sphere_wall == "analytic"); });
  if (selected("wing")) guarded("wing", [&] { run_wing(run, p, airfoil); });
  if (selected("stretching"))
    guarded("stretching", [&] { run_stretching(run, p == 2 ? std::vector<int>{2} : std::vector<int>{2, p}); });
  run.plot_cuts();
  std::printf("\ntotal %.1f s, peak memory %.0f MB\n", hom::bench::seconds_since(start), hom::bench::peak_rss_mb());
  return run.finish(csv, json);
}
