/// @file bench_measures.cpp
/// Reproduction harness for the behaviour of the distortion and quality
/// measures (issue 4, "Reproduction of the thesis"):
///
///   - figure 3.4 and table 3.1 (section 3.3.1): a degree-3 triangle whose
///     vertex x3, edge node x4 or face node x10 moves along one axis; shape and
///     Oddy element quality (eqs 3.2, 3.3, 3.23, 3.24) against the position,
///     and the curved element at the three locations of table 3.1;
///   - figures 3.5 and 3.6: level sets of both qualities when the free node
///     moves in the plane, equispaced and warp & blend nodes; the feasible
///     regions (q > 0) of both measures coincide and are ordered
///     vertex > edge > face;
///   - figures 4.5 and 4.6 (section 4.2.2): the linear triangle x0 = (0, 0.5),
///     x1 = (0, -0.5), x2 = (x, 0) against the equilateral ideal: distortion
///     (eq 3.2 with |sigma|), regularized distortion (eq 3.5, delta = 0.05) and
///     the qualities, on the line and in the plane;
///   - figure D.3 (appendix D.2): the level-set study for a degree-2
///     quadrilateral with vertices (+-1, +-1).
///
/// Writes CSV files into --out (default results/measures), prints a summary,
/// optionally a JSON report (--json, DESIGN.md schema) and the PNG figures
/// (--plot, through bench/plot_measures.py). The claims the thesis states are
/// checked; a violated claim makes the exit status non-zero.
///
/// Conventions (see also the comments at each study):
///   - The physical element of each study is the straight-sided element with
///     the node set's reference nodes mapped onto it, and it is its own ideal,
///     so the unperturbed configuration has q = 1 for both measures.
///   - Quadrature: ThesisExactness (6p - 3 on triangles), so validity is
///     decided at the same kind of points the thesis uses.
///   - Thesis node numbering of the cubic triangle (section 3.3.1) against
///     hom's layout (vertices, edge (0,1), edge (1,2), edge (0,2) from vertex 0,
///     interior): x1..x10 -> 0, 1, 2, 3, 4, 5, 6, 8, 7, 9 (the thesis runs the
///     third edge from x3 to x1, hom from vertex 0 to vertex 2).

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <Eigen/Dense>
#include <boost/program_options.hpp>

#include "hom/basis/lagrange.hpp"
#include "hom/element/cube.hpp"
#include "hom/element/simplex.hpp"
#include "hom/measure/oddy_measure.hpp"
#include "hom/measure/regularization.hpp"
#include "hom/measure/shape_measure.hpp"
#include "hom/nodes/equispaced.hpp"
#include "hom/nodes/gauss_lobatto.hpp"
#include "hom/nodes/warp_blend.hpp"
#include "hom/quadrature/quadrature_policy.hpp"
#include "hom/quality/element_quality.hpp"
#include "hom/quality/ideal.hpp"
#include "hom/quality/tabulation.hpp"

#ifndef HOM_VERSION
#define HOM_VERSION "unknown"
#endif
#ifndef HOM_PLOT_SCRIPT
#define HOM_PLOT_SCRIPT "bench/plot_measures.py"
#endif

#include "harness.hpp"
#include "plot_script.hpp"
#include "hom/io/json.hpp"
#include "hom/io/report.hpp"

namespace {

using namespace hom;
using hom::io::Json;
namespace fs = std::filesystem;

constexpr double sqrt3 = std::numbers::sqrt3;
constexpr double inf = std::numeric_limits<double>::infinity();
using Quadrature = ThesisExactness;

Json point_json(double x, double y) { return Json::array({x, y}); }

// --------------------------------------------------------------------------
// Output: every file is written to a temporary name and renamed, so a failed
// run leaves no partial file behind.

class OutputFile {
 public:
  explicit OutputFile(fs::path path) : path_(std::move(path)), tmp_(path_.string() + ".tmp") {
    os_.open(tmp_);
    if (!os_) throw std::runtime_error("cannot write " + tmp_.string());
    os_ << std::setprecision(10);
  }
  std::ofstream& stream() { return os_; }
  void commit() {
    os_.close();
    if (!os_) throw std::runtime_error("error writing " + tmp_.string());
    fs::rename(tmp_, path_);
  }

 private:
  fs::path path_, tmp_;
  std::ofstream os_;
};

// --------------------------------------------------------------------------
// Checks of the thesis's claims.

using hom::bench::Checks;

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// --------------------------------------------------------------------------
// A planar element of the studies: nodes of a node set on a straight-sided
// element, which is also the ideal.

using Nodes2 = ElementNodes<2>;

/// Linear / bilinear vertex shape functions at reference point xi (the map of
/// the straight-sided element, the same map ideal.hpp differentiates).
template <ElementFamily Family>
Eigen::Matrix<double, Family::num_vertices, 1> vertex_shape_values(const typename Family::Point& xi) {
  Eigen::Matrix<double, Family::num_vertices, 1> n;
  if constexpr (Family::is_simplex) {
    n[0] = 1.0 - xi.sum();
    for (int k = 0; k < Family::dim; ++k) n[k + 1] = xi[k];
  } else {
    for (int v = 0; v < Family::num_vertices; ++v) {
      const auto c = Family::vertex_corner(v);
      double value = 1.0;
      for (int a = 0; a < Family::dim; ++a) value *= (1.0 + (c[a] ? 1.0 : -1.0) * xi[a]) / 2.0;
      n[v] = value;
    }
  }
  return n;
}

struct Qualities {
  double shape = 0.0, oddy = 0.0;
};

template <ElementFamily Family>
struct PlanarElement {
  static_assert(Family::dim == 2, "the measure studies are planar");
  std::string node_set;
  int degree = 0;
  const Tabulation<Family>* tab = nullptr;
  IdealVertices<Family> ideal;
  Nodes2 nodes;                    ///< physical nodes of the unperturbed (ideal) element
  /// samples x n: Lagrange values at the reference points of the drawing:
  /// curve 0 is the boundary loop, curves 1.. are reference grid lines (their
  /// images show where the element folds).
  Eigen::MatrixXd drawing_basis;
  std::vector<int> curve_start;  ///< first sample of each curve, plus the total at the end

  Qualities quality(const Nodes2& X) const {
    return {element_quality<Family>(*tab, X, ideal, ShapeMeasure{}).quality,
            element_quality<Family>(*tab, X, ideal, OddyMeasure{}).quality};
  }
  /// The drawing curves of the element with nodes X (columns; see curve_start).
  Eigen::Matrix<double, 2, Eigen::Dynamic> drawing(const Nodes2& X) const { return X * drawing_basis.transpose(); }
};

template <ElementFamily Family, NodeSet Nodes>
PlanarElement<Family> make_planar_element(int p, const IdealVertices<Family>& vertices, int samples_per_edge) {
  PlanarElement<Family> e;
  e.node_set = std::string(Nodes::name);
  e.degree = p;
  e.tab = &tabulation<Family, Nodes>(p, quadrature_for<Family, Quadrature>(p));
  e.ideal = vertices;
  const auto ref = Nodes::template points<Family>(p);
  e.nodes.resize(2, static_cast<Eigen::Index>(ref.size()));
  for (std::size_t i = 0; i < ref.size(); ++i) e.nodes.col(i) = vertices * vertex_shape_values<Family>(ref[i]);

  using Point = typename Family::Point;
  std::vector<Point> pts;
  auto segment = [&](const Point& a, const Point& b, bool close) {
    for (int s = 0; s < samples_per_edge; ++s) pts.push_back(a + (b - a) * (double(s) / samples_per_edge));
    if (close) pts.push_back(b);
  };
  // Curve 0: the boundary loop v0 -> v1 -> ... -> v0.
  constexpr int nv = Family::num_vertices;
  e.curve_start.push_back(0);
  for (int v = 0; v < nv; ++v) segment(Family::vertex(v), Family::vertex((v + 1) % nv), v + 1 == nv);
  // Reference grid lines, 1/6 apart: lambda_a = k/6 on the triangle, xi_a = const on the square.
  constexpr int m = 6;
  for (int k = 1; k < m; ++k) {
    const double c = double(k) / m;
    if constexpr (Family::is_simplex) {
      for (int a = 0; a < 3; ++a) {
        const Point va = Family::vertex(a), vb = Family::vertex((a + 1) % 3), vc = Family::vertex((a + 2) % 3);
        e.curve_start.push_back(static_cast<int>(pts.size()));
        segment(c * va + (1 - c) * vb, c * va + (1 - c) * vc, true);
      }
    } else {
      const Point v0 = Family::vertex(0), v1 = Family::vertex(1), v2 = Family::vertex(2), v3 = Family::vertex(3);
      e.curve_start.push_back(static_cast<int>(pts.size()));
      segment(v0 + c * (v1 - v0), v3 + c * (v2 - v3), true);
      e.curve_start.push_back(static_cast<int>(pts.size()));
      segment(v0 + c * (v3 - v0), v1 + c * (v2 - v1), true);
    }
  }
  e.curve_start.push_back(static_cast<int>(pts.size()));
  e.drawing_basis = lagrange_basis<Family, Nodes>(p).values(pts);
  return e;
}

// --------------------------------------------------------------------------
// Free nodes, the three locations of table 3.1 and the level-set windows.

struct Window {
  double x0, x1, y0, y1;
};

struct FreeNode {
  std::string key;    ///< "vertex", "edge", "face"
  std::string label;  ///< thesis name: x3, x4, x10
  int node;           ///< hom local node number
  int axis;           ///< direction of the one-dimensional sweep (0: x, 1: y)
  double lo, hi;      ///< range of the sweep
  double location1, location3;  ///< table 3.1 (location 2 is the node's own position)
  Window window;      ///< level-set window (contains the feasible region where it is bounded)
};

/// Table 3.1 and section 3.3.1 for the cubic triangle. Location 2 is the node's
/// own position in each node set (equispaced: exactly the table's values);
/// locations 1 and 3 keep the table's coordinate along the sweep axis.
///
/// Why the vertex's feasible region is a horizontal strip for equispaced nodes.
/// Moving one node j by d changes the map by d N_j, so D phi = D phi_0 + d grad N_j^T,
/// a rank-one update: det D phi = det D phi_0 (1 + grad N_j . D phi_0^{-1} d). The
/// equispaced cubic vertex function depends on lambda_2 only, N_2 = lambda_2 (3 lambda_2 - 1)
/// (3 lambda_2 - 2) / 2, and grad_x lambda_2 = (0, 2/sqrt(3)) on the equilateral
/// element, so validity depends on the vertical displacement only: the region is
/// unbounded in x (its area in the window is a lower bound), and moving x3 along x
/// (figure 3.4(a), (d)) never tangles the element: the map is the shear
/// (x, y) -> (x + d N_2(y), y), with det D phi = det D phi_0. Warp & blend nodes
/// break that structure (their N_2 is not a function of lambda_2 alone), and their
/// vertex region is bounded.
std::vector<FreeNode> triangle_free_nodes() {
  return {
      {"vertex", "x3", 2, 0, -2.0, 3.0, -1.0, 2.0, {-5.0, 6.0, -0.5, 3.5}},
      {"edge", "x4", 3, 1, -2.0, 2.0, -1.5, 1.5, {-0.5, 2.0, -3.0, 1.0}},
      {"face", "x10", 9, 1, -1.5, 2.0, -1.0, 1.5, {0.1, 0.9, 0.0, 0.7}},
  };
}

/// Figure D.3: quadrilateral of degree 2 on [-1, 1]^2 (hom node 2 = vertex
/// (1, 1), node 4 = midpoint of edge (0, 1) at (0, -1), node 8 = centre).
/// No one-dimensional sweep is reproduced for it (lo/hi unused).
std::vector<FreeNode> quadrilateral_free_nodes() {
  return {
      {"vertex", "vertex (1,1)", 2, 0, 0.0, 0.0, 0.0, 0.0, {-3.0, 6.0, -3.0, 6.0}},
      {"edge", "edge (0,-1)", 4, 1, 0.0, 0.0, 0.0, 0.0, {-2.0, 2.0, -5.0, 0.5}},
      {"face", "face (0,0)", 8, 1, 0.0, 0.0, 0.0, 0.0, {-1.2, 1.2, -1.2, 1.2}},
  };
}

// --------------------------------------------------------------------------
// CSV of element drawings: figure, node_set, free_node, location, kind, curve, index, x, y
// with kind "boundary" (curve 0), "line" (images of reference grid lines),
// "node" and "free" (the free node).

template <ElementFamily Family>
void write_element(std::ostream& os, const std::string& figure, const PlanarElement<Family>& e, const std::string& free,
                   int free_node, int location, const Nodes2& X) {
  const auto b = e.drawing(X);
  const std::string prefix = figure + ',' + e.node_set + ',' + free + ',' + std::to_string(location) + ',';
  for (std::size_t c = 0; c + 1 < e.curve_start.size(); ++c)
    for (int i = e.curve_start[c]; i < e.curve_start[c + 1]; ++i)
      os << prefix << (c == 0 ? "boundary," : "line,") << c << ',' << i - e.curve_start[c] << ',' << b(0, i) << ','
         << b(1, i) << '\n';
  for (Eigen::Index i = 0; i < X.cols(); ++i)
    os << prefix << (i == free_node ? "free" : "node") << ",-1," << i << ',' << X(0, i) << ',' << X(1, i) << '\n';
}

// --------------------------------------------------------------------------
// Figure 3.4 and table 3.1.

struct Configuration {
  std::string node_set, free_node;
  int location;
  double x, y;
  Qualities q;
};

struct Fig34Result {
  std::vector<Configuration> configurations;
  int curve_samples = 0;
  int curve_mismatch = 0;    ///< sweep points where exactly one measure is zero
  int oddy_above_shape = 0;  ///< sweep points with q_oddy > q_shape (never, Oddy is stricter)
  double vertex_sweep_min_q = 1.0;  ///< smallest q_shape of the equispaced x3 sweep (> 0: never tangled)
  double time_s = 0.0;
};

template <ElementFamily Family>
void sweep_triangle(const PlanarElement<Family>& e, const std::vector<FreeNode>& free_nodes, int samples,
                    std::ostream& curves, std::ostream& elements, Fig34Result& r) {
  for (const FreeNode& f : free_nodes) {
    Nodes2 X = e.nodes;
    for (int s = 0; s < samples; ++s) {
      const double t = f.lo + (f.hi - f.lo) * s / (samples - 1);
      X(f.axis, f.node) = t;
      const Qualities q = e.quality(X);
      curves << e.node_set << ',' << f.key << ',' << t << ',' << q.shape << ',' << q.oddy << '\n';
      ++r.curve_samples;
      r.curve_mismatch += (q.shape > 0) != (q.oddy > 0);
      r.oddy_above_shape += q.oddy > q.shape * (1 + 1e-12);
      if (f.key == "vertex" && e.node_set == Equispaced::name) r.vertex_sweep_min_q = std::min(r.vertex_sweep_min_q, q.shape);
    }
    const double own = e.nodes(f.axis, f.node);
    const double loc[3] = {f.location1, own, f.location3};
    for (int l = 0; l < 3; ++l) {
      X = e.nodes;
      X(f.axis, f.node) = loc[l];
      const Qualities q = e.quality(X);
      r.configurations.push_back({e.node_set, f.key, l + 1, X(0, f.node), X(1, f.node), q});
      write_element(elements, "fig3_4", e, f.key, f.node, l + 1, X);
    }
  }
}

// --------------------------------------------------------------------------
// Level sets (figures 3.5, 3.6, D.3).

struct LevelSet {
  std::string free_node, label;
  Window window;
  int n = 0;
  double area_shape = 0.0, area_oddy = 0.0;
  int feasible = 0;          ///< grid points with q_shape > 0
  int mismatch = 0;          ///< grid points where exactly one measure is > 0
  int border_feasible = 0;   ///< feasible points on the window's border (area truncated if > 0)
  int oddy_above_shape = 0;  ///< points with q_oddy > q_shape
  int rows_mixed = 0;        ///< grid rows (fixed y) whose validity depends on x
  double max_shape = 0.0, max_oddy = 0.0;
  double argmax_x = 0.0, argmax_y = 0.0;  ///< where q_shape is largest
};

/// Samples both qualities on an n x n grid of nodes (window corners included)
/// when node f.node moves; area = (#points with q > 0) dx dy.
template <ElementFamily Family>
LevelSet level_set(const PlanarElement<Family>& e, const FreeNode& f, int n, std::ostream& csv) {
  LevelSet ls;
  ls.free_node = f.key;
  ls.label = f.label;
  ls.window = f.window;
  ls.n = n;
  const Window& w = f.window;
  const double dx = (w.x1 - w.x0) / (n - 1), dy = (w.y1 - w.y0) / (n - 1);
  Nodes2 X = e.nodes;
  int feasible_oddy = 0;
  for (int j = 0; j < n; ++j) {
    int row_feasible = 0;
    for (int i = 0; i < n; ++i) {
      const double x = w.x0 + (w.x1 - w.x0) * i / (n - 1), y = w.y0 + (w.y1 - w.y0) * j / (n - 1);
      X(0, f.node) = x;
      X(1, f.node) = y;
      const Qualities q = e.quality(X);
      csv << f.key << ',' << x << ',' << y << ',' << q.shape << ',' << q.oddy << '\n';
      ls.feasible += q.shape > 0;
      row_feasible += q.shape > 0;
      feasible_oddy += q.oddy > 0;
      ls.mismatch += (q.shape > 0) != (q.oddy > 0);
      ls.oddy_above_shape += q.oddy > q.shape * (1 + 1e-12);
      if ((q.shape > 0 || q.oddy > 0) && (i == 0 || j == 0 || i == n - 1 || j == n - 1)) ++ls.border_feasible;
      if (q.shape > ls.max_shape) {
        ls.max_shape = q.shape;
        ls.argmax_x = x;
        ls.argmax_y = y;
      }
      ls.max_oddy = std::max(ls.max_oddy, q.oddy);
    }
    ls.rows_mixed += row_feasible > 0 && row_feasible < n;
  }
  ls.area_shape = ls.feasible * dx * dy;
  ls.area_oddy = feasible_oddy * dx * dy;
  return ls;
}

struct LevelSetStudy {
  std::string name, figure, family, node_set;
  int p = 0, nodes = 0;
  std::vector<LevelSet> sets;
  double time_s = 0.0;
};

template <ElementFamily Family>
LevelSetStudy level_set_study(const std::string& name, const std::string& figure, const PlanarElement<Family>& e,
                              const std::vector<FreeNode>& free_nodes, int n, const fs::path& out,
                              std::ostream& elements) {
  const auto t0 = Clock::now();
  LevelSetStudy s;
  s.name = name;
  s.figure = figure;
  s.family = std::string(Family::name);
  s.node_set = e.node_set;
  s.p = e.degree;
  s.nodes = static_cast<int>(e.nodes.cols());
  OutputFile csv(out / (name + "_levelsets.csv"));
  csv.stream() << "free_node,x,y,shape,oddy\n";
  for (const FreeNode& f : free_nodes) {
    s.sets.push_back(level_set(e, f, n, csv.stream()));
    write_element(elements, name, e, f.key, f.node, 0, e.nodes);
  }
  csv.commit();
  s.time_s = seconds_since(t0);
  return s;
}

/// The claims of section 3.3.1 (and appendix D.2): both measures share the
/// feasible region, Oddy is the stricter one, the ideal scores 1, and the
/// feasible areas are ordered vertex > edge > face. The edge's and the face's
/// regions must lie inside their windows (exact areas); the vertex's may be
/// unbounded (its area is then a lower bound, which still decides the order).
void check_level_set_study(const LevelSetStudy& s, Checks& checks, bool check_order) {
  for (std::size_t k = 0; k < s.sets.size(); ++k) {
    const LevelSet& ls = s.sets[k];
    checks.expect(ls.mismatch == 0, s.name + " " + ls.free_node + ": shape and Oddy feasible regions differ at " +
                                        std::to_string(ls.mismatch) + " grid points");
    if (ls.free_node != "vertex")
      checks.expect(ls.border_feasible == 0, s.name + " " + ls.free_node +
                                                 ": feasible region reaches the window border (" +
                                                 std::to_string(ls.border_feasible) + " points); area truncated");
    checks.expect(ls.oddy_above_shape == 0, s.name + " " + ls.free_node + ": Oddy quality above shape quality at " +
                                                std::to_string(ls.oddy_above_shape) + " points");
    checks.expect(std::abs(ls.max_shape - 1.0) < 1e-9 || ls.max_shape < 1.0,
                  s.name + " " + ls.free_node + ": shape quality above 1");
  }
  if (check_order && s.sets.size() == 3)
    checks.expect(s.sets[0].area_shape > s.sets[1].area_shape && s.sets[1].area_shape > s.sets[2].area_shape,
                  s.name + ": feasible areas not ordered vertex > edge > face");
}

Json level_set_case(const LevelSetStudy& s, bool order_claimed) {
  Json c = Json::object();
  c.set("name", s.name)
      .set("stage", "level sets")
      .set("figure", s.figure)
      .set("family", s.family)
      .set("p", s.p)
      .set("elements", 1)
      .set("nodes", s.nodes)
      .set("node_set", s.node_set)
      .set("measure", Json::array({"shape", "oddy"}))
      .set("ideal", "the unperturbed straight-sided element")
      .set("quadrature", std::string(Quadrature::name))
      .set("grid", s.sets.empty() ? 0 : s.sets.front().n);
  Json sets = Json::array();
  for (const LevelSet& ls : s.sets) {
    Json j = Json::object();
    j.set("free_node", ls.free_node)
        .set("label", ls.label)
        .set("window", Json::array({ls.window.x0, ls.window.x1, ls.window.y0, ls.window.y1}))
        .set("feasible_area_shape", ls.area_shape)
        .set("feasible_area_oddy", ls.area_oddy)
        .set("feasible_mismatch", ls.mismatch)
        .set("feasible_on_border", ls.border_feasible)
        .set("feasible_area_is_lower_bound", ls.border_feasible > 0)
        .set("oddy_above_shape", ls.oddy_above_shape)
        .set("max_q_shape", ls.max_shape)
        .set("max_q_oddy", ls.max_oddy)
        .set("argmax_q_shape", point_json(ls.argmax_x, ls.argmax_y));
    sets.push(std::move(j));
  }
  c.set("free_nodes", std::move(sets));
  Json thesis = Json::object();
  thesis.set("feasible_regions_coincide", true);
  if (order_claimed) thesis.set("feasible_area_order", "vertex > edge > face");
  thesis.set("ideal_quality", 1.0);
  c.set("thesis", std::move(thesis));
  c.set("time_s", s.time_s);
  return c;
}

// --------------------------------------------------------------------------
// Figures 4.5 and 4.6: linear triangle, x2 free, equilateral ideal.
//
// Orientation. hom's reference triangle (0,0), (1,0), (0,1) is counter-clockwise
// and so is regular_ideal_vertices. Taking the thesis's nodes in their order as
// hom's vertices 0, 1, 2, i.e. x0 = (0, 0.5), x1 = (0, -0.5), x2 = (x, y), gives
// det [x1 - x0, x2 - x0] = det [(0, -1), (x, y - 0.5)] = x: the triangle is
// counter-clockwise (valid) exactly for x > 0, as the thesis states ("only
// 0 < x < inf correspond to valid configurations"). No reordering is needed.

struct LinearTriangle {
  IdealVertices<Simplex<2>> ideal = regular_ideal_vertices<Simplex<2>>();
  Eigen::Matrix2d ideal_inverse = ideal_jacobian<Simplex<2>>(ideal, Simplex<2>::Point::Zero()).inverse();

  Nodes2 nodes(double x, double y) const {
    Nodes2 X(2, 3);
    X << 0.0, 0.0, x,  //
        0.5, -0.5, y;
    return X;
  }
  /// J = D phi_E = D phi_P (D phi_I)^{-1} (eq A.2).
  Eigen::Matrix2d jacobian(double x, double y) const {
    const Nodes2 X = nodes(x, y);
    Eigen::Matrix2d P;
    P.col(0) = X.col(1) - X.col(0);
    P.col(1) = X.col(2) - X.col(0);
    return P * ideal_inverse;
  }
};

struct Distortions {
  double eta_abs, eta_clamped, eta_reg;
};

Distortions linear_distortions(const LinearTriangle& t, double x, double y, double delta) {
  const Eigen::Matrix2d J = t.jacobian(x, y);
  const ShapeMeasure m;
  return {m.value(J, AbsoluteDeterminant{}), m.value(J, ClampedDeterminant{}),
          m.value(J, RegularizedDeterminant{delta})};
}

double inverse(double eta) { return std::isfinite(eta) ? 1.0 / eta : 0.0; }

struct Fig45Result {
  double delta = 0.05;
  int samples = 0;
  std::vector<double> reg_minima, abs_minima;  ///< discrete local minima (x) of the sampled curves
  double reg_minimum_x = 0.0, reg_minimum_eta = 0.0;  ///< refined (golden section)
  double eta_reg_at_0 = 0.0;
  double lemma31_max_difference = 0.0;  ///< |q (p = 1 element) - q (linear measure)|
  bool clamped_infinite_left = true;    ///< eta_clamped = inf for every sampled x <= 0
  bool clamped_finite_right = true;
  double time_s = 0.0;
};

Fig45Result figure_4_5(int samples, const fs::path& out, Checks& checks) {
  const auto t0 = Clock::now();
  Fig45Result r;
  r.samples = samples;
  const LinearTriangle tri;
  // Lemma 3.1 cross-check: for p = 1 the element quality is the linear one.
  const auto& tab = tabulation<Simplex<2>, Equispaced>(1, quadrature_for<Simplex<2>, Quadrature>(1));

  std::vector<double> xs(samples), reg(samples), abs(samples);
  OutputFile csv(out / "fig4_5.csv");
  csv.stream() << "x,eta_abs,eta_clamped,eta_reg,q_abs,q_clamped,q_reg\n";
  for (int s = 0; s < samples; ++s) {
    const double x = -5.0 + 10.0 * s / (samples - 1);
    const Distortions d = linear_distortions(tri, x, 0.0, r.delta);
    xs[s] = x;
    reg[s] = d.eta_reg;
    abs[s] = d.eta_abs;
    csv.stream() << x << ',' << d.eta_abs << ',' << d.eta_clamped << ',' << d.eta_reg << ',' << inverse(d.eta_abs)
                 << ',' << inverse(d.eta_clamped) << ',' << inverse(d.eta_reg) << '\n';
    if (x <= 0.0 && std::isfinite(d.eta_clamped)) r.clamped_infinite_left = false;
    if (x > 0.0 && !std::isfinite(d.eta_clamped)) r.clamped_finite_right = false;
    const double q_elem = element_quality<Simplex<2>>(tab, tri.nodes(x, 0.0), tri.ideal, ShapeMeasure{}).quality;
    r.lemma31_max_difference = std::max(r.lemma31_max_difference, std::abs(q_elem - inverse(d.eta_clamped)));
  }
  csv.commit();
  for (int s = 1; s + 1 < samples; ++s) {
    if (reg[s] < reg[s - 1] && reg[s] < reg[s + 1]) r.reg_minima.push_back(xs[s]);
    if (std::isfinite(abs[s]) && abs[s] < abs[s - 1] && abs[s] < abs[s + 1]) r.abs_minima.push_back(xs[s]);
  }
  // Golden-section refinement of the regularized minimum around the sampled one.
  if (r.reg_minima.size() == 1) {
    const double h = 10.0 / (samples - 1);
    double a = r.reg_minima[0] - h, b = r.reg_minima[0] + h;
    const double g = (std::sqrt(5.0) - 1.0) / 2.0;
    auto f = [&](double x) { return linear_distortions(tri, x, 0.0, r.delta).eta_reg; };
    double c = b - g * (b - a), d = a + g * (b - a);
    for (int it = 0; it < 100; ++it) {
      if (f(c) < f(d))
        b = d;
      else
        a = c;
      c = b - g * (b - a);
      d = a + g * (b - a);
    }
    r.reg_minimum_x = 0.5 * (a + b);
    r.reg_minimum_eta = f(r.reg_minimum_x);
  }
  r.eta_reg_at_0 = linear_distortions(tri, 0.0, 0.0, r.delta).eta_reg;

  const double h = sqrt3 / 2.0;
  checks.expect(r.reg_minima.size() == 1, "fig4_5: regularized distortion has " + std::to_string(r.reg_minima.size()) +
                                              " local minima on [-5, 5], expected 1");
  checks.expect(std::abs(r.reg_minimum_x - h) < 0.05, "fig4_5: regularized minimum not within 0.05 of sqrt(3)/2");
  checks.expect(std::isfinite(r.eta_reg_at_0), "fig4_5: regularized distortion not finite at x = 0");
  checks.expect(r.clamped_infinite_left && r.clamped_finite_right,
                "fig4_5: clamped distortion is not infinite exactly for x <= 0");
  checks.expect(r.abs_minima.size() == 2 && std::abs(r.abs_minima[0] + h) < 10.0 / samples &&
                    std::abs(r.abs_minima.back() - h) < 10.0 / samples,
                "fig4_5: |sigma| distortion does not have its two minima at +-sqrt(3)/2");
  checks.expect(std::abs(linear_distortions(tri, h, 0.0, r.delta).eta_abs - 1.0) < 1e-12 &&
                    std::abs(linear_distortions(tri, -h, 0.0, r.delta).eta_abs - 1.0) < 1e-12,
                "fig4_5: eta(+-sqrt(3)/2) != 1");
  checks.expect(r.lemma31_max_difference < 1e-12, "fig4_5: p = 1 element quality differs from the linear measure");
  r.time_s = seconds_since(t0);
  return r;
}

struct Fig46Result {
  int n = 0;
  Window window{-3.0, 3.0, -3.0, 3.0};
  std::vector<std::pair<double, double>> abs_minima, reg_minima;
  double time_s = 0.0;
};

/// Strict discrete local minima of an n x n grid (8 neighbours, interior points).
std::vector<std::pair<int, int>> grid_minima(const std::vector<double>& v, int n) {
  std::vector<std::pair<int, int>> m;
  for (int j = 1; j + 1 < n; ++j)
    for (int i = 1; i + 1 < n; ++i) {
      const double c = v[j * n + i];
      if (!std::isfinite(c)) continue;
      bool minimum = true;
      for (int dj = -1; dj <= 1 && minimum; ++dj)
        for (int di = -1; di <= 1; ++di)
          if ((di || dj) && !(c < v[(j + dj) * n + i + di])) {
            minimum = false;
            break;
          }
      if (minimum) m.emplace_back(i, j);
    }
  return m;
}

Fig46Result figure_4_6(int n, double delta, const fs::path& out, Checks& checks) {
  const auto t0 = Clock::now();
  Fig46Result r;
  r.n = n;
  const LinearTriangle tri;
  const Window& w = r.window;
  std::vector<double> abs(n * n), reg(n * n);
  OutputFile csv(out / "fig4_6.csv");
  csv.stream() << "x,y,eta_abs,eta_clamped,eta_reg,q_clamped,q_reg\n";
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double x = w.x0 + (w.x1 - w.x0) * i / (n - 1), y = w.y0 + (w.y1 - w.y0) * j / (n - 1);
      const Distortions d = linear_distortions(tri, x, y, delta);
      abs[j * n + i] = d.eta_abs;
      reg[j * n + i] = d.eta_reg;
      csv.stream() << x << ',' << y << ',' << d.eta_abs << ',' << d.eta_clamped << ',' << d.eta_reg << ','
                   << inverse(d.eta_clamped) << ',' << inverse(d.eta_reg) << '\n';
    }
  csv.commit();
  for (auto [i, j] : grid_minima(abs, n)) r.abs_minima.emplace_back(w.x0 + (w.x1 - w.x0) * i / (n - 1), w.y0 + (w.y1 - w.y0) * j / (n - 1));
  for (auto [i, j] : grid_minima(reg, n)) r.reg_minima.emplace_back(w.x0 + (w.x1 - w.x0) * i / (n - 1), w.y0 + (w.y1 - w.y0) * j / (n - 1));
  checks.expect(r.abs_minima.size() == 2, "fig4_6: |sigma| distortion should have two minima in the plane, found " +
                                              std::to_string(r.abs_minima.size()));
  checks.expect(r.reg_minima.size() == 1, "fig4_6: regularized distortion should have one minimum in the plane, found " +
                                              std::to_string(r.reg_minima.size()));
  if (r.reg_minima.size() == 1)
    checks.expect(r.reg_minima[0].first > 0.0, "fig4_6: regularized minimum outside the feasible half-plane x > 0");
  r.time_s = seconds_since(t0);
  return r;
}

// --------------------------------------------------------------------------
// Command line, summary, report.

struct Options {
  fs::path out = "results/measures";
  std::optional<fs::path> json;
  bool plot = false;
  fs::path plot_script = HOM_PLOT_SCRIPT;
  int grid = 121;
  int samples = 801;
};

std::string fixed(double v, int digits = 4) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(digits) << v;
  return os.str();
}

int run(const Options& o) {
  const auto t_start = Clock::now();
  fs::create_directories(o.out);
  Checks checks{"bench_measures"};
  Json cases = Json::array();

  // ---- the cubic triangle: equispaced (figure 3.5) and warp & blend (figure 3.6)
  const int p = 3;
  const IdealVertices<Simplex<2>> equilateral = regular_ideal_vertices<Simplex<2>>();
  const auto tri_eq = make_planar_element<Simplex<2>, Equispaced>(p, equilateral, 50);
  const auto tri_wb = make_planar_element<Simplex<2>, WarpBlend>(p, equilateral, 50);
  const auto free_tri = triangle_free_nodes();

  // The thesis's coordinates of x1..x10 (section 3.3.1) and hom's numbering.
  {
    const double thesis[10][2] = {{0, 0},           {1, 0},           {0.5, sqrt3 / 2}, {1.0 / 3, 0},
                                  {2.0 / 3, 0},     {5.0 / 6, sqrt3 / 6}, {2.0 / 3, sqrt3 / 3}, {1.0 / 3, sqrt3 / 3},
                                  {1.0 / 6, sqrt3 / 6}, {0.5, sqrt3 / 6}};
    const int hom_node[10] = {0, 1, 2, 3, 4, 5, 6, 8, 7, 9};
    double err = 0.0;
    for (int k = 0; k < 10; ++k)
      err = std::max(err, (tri_eq.nodes.col(hom_node[k]) - Eigen::Vector2d(thesis[k][0], thesis[k][1])).norm());
    checks.expect(err < 1e-14, "fig3_4: equispaced nodes differ from the thesis's x1..x10 by " + std::to_string(err));
  }

  OutputFile elements(o.out / "elements.csv");
  elements.stream() << "figure,node_set,free_node,location,kind,curve,index,x,y\n";

  // ---- figure 3.4, table 3.1
  Fig34Result f34;
  {
    const auto t0 = Clock::now();
    OutputFile curves(o.out / "fig3_4_curves.csv");
    curves.stream() << "node_set,free_node,position,shape,oddy\n";
    sweep_triangle(tri_eq, free_tri, o.samples, curves.stream(), elements.stream(), f34);
    sweep_triangle(tri_wb, free_tri, o.samples, curves.stream(), elements.stream(), f34);
    curves.commit();
    OutputFile configs(o.out / "fig3_4_configs.csv");
    configs.stream() << "node_set,free_node,location,x,y,shape,oddy\n";
    for (const auto& c : f34.configurations)
      configs.stream() << c.node_set << ',' << c.free_node << ',' << c.location << ',' << c.x << ',' << c.y << ','
                       << c.q.shape << ',' << c.q.oddy << '\n';
    configs.commit();
    f34.time_s = seconds_since(t0);
  }
  for (const auto& c : f34.configurations) {
    if (c.location == 2)
      checks.expect(std::abs(c.q.shape - 1.0) <= 1e-12 && std::abs(c.q.oddy - 1.0) <= 1e-12,
                    "table 3.1: location 2 of " + c.free_node + " (" + c.node_set + ") has q != 1");
    // Location 1 and 3 of the edge and face nodes: figures 3.4(b), (c) show
    // folded elements (the node is pushed across an opposite part of the
    // boundary or far off its edge), which must get q = 0.
    if (c.location != 2 && c.free_node != "vertex")
      checks.expect(c.q.shape == 0.0 && c.q.oddy == 0.0, "table 3.1: location " + std::to_string(c.location) +
                                                             " of " + c.free_node + " (" + c.node_set +
                                                             ") should be tangled (q = 0)");
  }
  // Not a claim of the thesis but a fact (shear argument at triangle_free_nodes()):
  // figure 3.4(d) never reaches q = 0.
  checks.expect(f34.vertex_sweep_min_q > 0.0, "fig3_4: the equispaced vertex sweep reaches q = 0");
  checks.expect(f34.curve_mismatch == 0, "fig3_4: shape and Oddy disagree on validity at " +
                                             std::to_string(f34.curve_mismatch) + " sweep points");
  checks.expect(f34.oddy_above_shape == 0, "fig3_4: Oddy quality above shape quality at " +
                                               std::to_string(f34.oddy_above_shape) + " sweep points");
  {
    Json c = Json::object();
    c.set("name", "fig3_4")
        .set("stage", "node sweep")
        .set("figure", "3.4, table 3.1")
        .set("family", "triangle")
        .set("p", p)
        .set("elements", 1)
        .set("nodes", static_cast<int>(tri_eq.nodes.cols()))
        .set("node_set", Json::array({"equispaced", "warp_blend"}))
        .set("measure", Json::array({"shape", "oddy"}))
        .set("ideal", "equilateral (the unperturbed element)")
        .set("quadrature", std::string(Quadrature::name))
        .set("sweep_samples", o.samples)
        .set("validity_mismatch", f34.curve_mismatch)
        .set("oddy_above_shape", f34.oddy_above_shape)
        .set("vertex_sweep_min_q_shape", f34.vertex_sweep_min_q)
        .set("note", "moving the equispaced vertex x3 along x shears the element (det D phi unchanged), so "
                     "locations 1 and 3 of x3 are valid with low quality; the edge and face nodes fold at "
                     "locations 1 and 3");
    Json configs = Json::array();
    for (const auto& k : f34.configurations) {
      Json j = Json::object();
      j.set("node_set", k.node_set)
          .set("free_node", k.free_node)
          .set("location", k.location)
          .set("position", point_json(k.x, k.y))
          .set("q_shape", k.q.shape)
          .set("q_oddy", k.q.oddy);
      configs.push(std::move(j));
    }
    c.set("configurations", std::move(configs));
    Json thesis = Json::object();
    thesis.set("location_2_quality", 1.0)
        .set("locations_table_3_1",
             Json::array({Json::array({"x3", point_json(-1, sqrt3 / 2), point_json(0.5, sqrt3 / 2),
                                       point_json(2, sqrt3 / 2)}),
                          Json::array({"x4", point_json(1.0 / 3, -1.5), point_json(1.0 / 3, 0),
                                       point_json(1.0 / 3, 1.5)}),
                          Json::array({"x10", point_json(0.5, -1), point_json(0.5, sqrt3 / 6),
                                       point_json(0.5, 1.5)})}))
        .set("claims", Json::array({"both measures give q = 1 at the ideal location",
                                    "both measures detect the same tangled positions (q = 0)",
                                    "the Oddy quality is stricter than the shape quality"}));
    c.set("thesis", std::move(thesis));
    c.set("time_s", f34.time_s);
    cases.push(std::move(c));
  }

  // ---- figures 3.5, 3.6
  const auto s35 = level_set_study("fig3_5", "3.5", tri_eq, free_tri, o.grid, o.out, elements.stream());
  const auto s36 = level_set_study("fig3_6", "3.6", tri_wb, free_tri, o.grid, o.out, elements.stream());
  check_level_set_study(s35, checks, true);
  // Equispaced vertex: validity depends on the vertical displacement only
  // (rank-one argument at triangle_free_nodes()).
  checks.expect(s35.sets[0].rows_mixed == 0, "fig3_5 vertex: validity depends on x in " +
                                                 std::to_string(s35.sets[0].rows_mixed) + " grid rows (expected a strip)");
  check_level_set_study(s36, checks, true);
  cases.push(level_set_case(s35, true));
  cases.push(level_set_case(s36, true));

  // ---- figure D.3: quadrilateral of degree 2 on [-1, 1]^2. At p = 2 the
  // Gauss-Lobatto nodes {-1, 0, 1} are the equispaced ones.
  IdealVertices<Cube<2>> square;
  for (int v = 0; v < 4; ++v) square.col(v) = Cube<2>::vertex(v);
  const auto quad = make_planar_element<Cube<2>, GaussLobatto>(2, square, 50);
  const auto sD3 = level_set_study("figD_3", "D.3", quad, quadrilateral_free_nodes(), o.grid, o.out, elements.stream());
  check_level_set_study(sD3, checks, true);
  cases.push(level_set_case(sD3, true));
  elements.commit();

  // ---- figures 4.5, 4.6
  const Fig45Result f45 = figure_4_5(10 * (o.samples / 2) + 1, o.out, checks);  // x = 0 is a sample
  const Fig46Result f46 = figure_4_6(2 * (o.grid / 2) + 41, f45.delta, o.out, checks);
  {
    Json c = Json::object();
    c.set("name", "fig4_5")
        .set("stage", "distortion curve")
        .set("figure", "4.5")
        .set("family", "triangle")
        .set("p", 1)
        .set("elements", 1)
        .set("nodes", 3)
        .set("measure", "shape")
        .set("ideal", "equilateral")
        .set("delta", f45.delta)
        .set("samples", f45.samples)
        .set("regularized_local_minima", static_cast<int>(f45.reg_minima.size()))
        .set("regularized_minimum_x", f45.reg_minimum_x)
        .set("regularized_minimum_eta", f45.reg_minimum_eta)
        .set("regularized_eta_at_0", f45.eta_reg_at_0);
    Json am = Json::array();
    for (double x : f45.abs_minima) am.push(x);
    c.set("abs_det_minima_x", std::move(am))
        .set("clamped_infinite_for_x_le_0", f45.clamped_infinite_left)
        .set("lemma_3_1_max_difference", f45.lemma31_max_difference);
    Json thesis = Json::object();
    thesis.set("valid_for", "0 < x < inf")
        .set("distortion_minima_x", Json::array({-sqrt3 / 2, sqrt3 / 2}))
        .set("distortion_minimum_eta", 1.0)
        .set("asymptote_x", 0.0)
        .set("regularized_single_minimum_near_x", sqrt3 / 2);
    c.set("thesis", std::move(thesis)).set("time_s", f45.time_s);
    cases.push(std::move(c));

    Json d = Json::object();
    d.set("name", "fig4_6")
        .set("stage", "level sets")
        .set("figure", "4.6")
        .set("family", "triangle")
        .set("p", 1)
        .set("elements", 1)
        .set("nodes", 3)
        .set("measure", "shape")
        .set("ideal", "equilateral")
        .set("delta", f45.delta)
        .set("grid", f46.n)
        .set("window", Json::array({f46.window.x0, f46.window.x1, f46.window.y0, f46.window.y1}));
    Json a = Json::array(), b = Json::array();
    for (auto [x, y] : f46.abs_minima) a.push(point_json(x, y));
    for (auto [x, y] : f46.reg_minima) b.push(point_json(x, y));
    d.set("abs_det_minima", std::move(a)).set("regularized_minima", std::move(b));
    Json thesis46 = Json::object();
    thesis46.set("claims", Json::array({"the regularized distortion removes the local minimum outside the feasible region",
                                        "the regularized distortion is continuous and differentiable"}))
        .set("distortion_minima", Json::array({point_json(-sqrt3 / 2, 0), point_json(sqrt3 / 2, 0)}));
    d.set("thesis", std::move(thesis46)).set("time_s", f46.time_s);
    cases.push(std::move(d));
  }

  // ---- summary
  std::cout << "bench_measures " << HOM_VERSION << ": thesis figures 3.4-3.6, 4.5, 4.6, D.3 (quadrature: "
            << Quadrature::name << ")\n\n";
  std::cout << "Table 3.1 / figure 3.4: element quality of the cubic triangle at the three locations\n";
  std::cout << "  node set     free    loc  position              q_shape   q_oddy\n";
  for (const auto& c : f34.configurations)
    std::cout << "  " << std::left << std::setw(12) << c.node_set << " " << std::setw(7) << c.free_node
              << std::right << std::setw(3) << c.location << "  (" << std::setw(8) << fixed(c.x) << ", "
              << std::setw(8) << fixed(c.y) << ")  " << std::setw(8) << fixed(c.q.shape) << " " << std::setw(8)
              << fixed(c.q.oddy) << '\n';
  std::cout << "  sweep points where the two measures disagree on validity: " << f34.curve_mismatch << '\n';
  std::cout << "  equispaced x3 sweep (x in [-2, 3]): min q_shape = " << fixed(f34.vertex_sweep_min_q)
            << " (a shear of the ideal: never tangled)\n";
  std::cout << "  (>= below: the region reaches the window border; the equispaced vertex region is an\n"
               "   unbounded horizontal strip, so its area in the window is a lower bound)\n";

  for (const auto* s : {&s35, &s36, &sD3}) {
    std::cout << "\nFigure " << s->figure << ": feasible region (q > 0) of a " << s->family << " of degree " << s->p
              << ", " << s->node_set << " nodes, " << s->sets.front().n << "^2 grid\n";
    std::cout << "  free node  window                       area(shape)  area(oddy)  mismatch  max q_shape at\n";
    for (const LevelSet& ls : s->sets)
      std::cout << "  " << std::left << std::setw(9) << ls.free_node << std::right << "  [" << std::setw(5)
                << fixed(ls.window.x0, 1) << "," << std::setw(5) << fixed(ls.window.x1, 1) << "]x[" << std::setw(5)
                << fixed(ls.window.y0, 1) << "," << std::setw(5) << fixed(ls.window.y1, 1) << "]  "
                << (ls.border_feasible ? ">=" : "  ") << std::setw(9) << fixed(ls.area_shape) << " "
                << (ls.border_feasible ? ">=" : "  ") << std::setw(9) << fixed(ls.area_oddy) << "  " << std::setw(8)
                << ls.mismatch << "  (" << fixed(ls.argmax_x, 3) << ", " << fixed(ls.argmax_y, 3) << ")\n";
  }

  std::cout << "\nFigure 4.5: linear triangle x0 = (0,0.5), x1 = (0,-0.5), x2 = (x,0), equilateral ideal, delta = "
            << f45.delta << '\n';
  std::cout << "  |sigma| distortion minima at x =";
  for (double x : f45.abs_minima) std::cout << ' ' << fixed(x, 4);
  std::cout << "  (thesis: +-sqrt(3)/2 = +-" << fixed(sqrt3 / 2, 4) << ")\n";
  std::cout << "  regularized distortion: " << f45.reg_minima.size() << " local minimum, at x = "
            << fixed(f45.reg_minimum_x, 6) << " (eta = " << fixed(f45.reg_minimum_eta, 6)
            << "); eta_delta(0) = " << fixed(f45.eta_reg_at_0, 4) << '\n';
  std::cout << "  clamped distortion infinite exactly for x <= 0: "
            << (f45.clamped_infinite_left && f45.clamped_finite_right ? "yes" : "no") << '\n';
  std::cout << "Figure 4.6: minima in [-3,3]^2 (" << f46.n << "^2 grid): |sigma|:";
  for (auto [x, y] : f46.abs_minima) std::cout << " (" << fixed(x, 2) << ", " << fixed(y, 2) << ")";
  std::cout << "; regularized:";
  for (auto [x, y] : f46.reg_minima) std::cout << " (" << fixed(x, 2) << ", " << fixed(y, 2) << ")";
  std::cout << '\n';

  const double total = seconds_since(t_start);
  std::cout << "\n" << checks.count() - checks.failures().size() << "/" << checks.count() << " checks passed; CSV in "
            << o.out.string() << " (" << fixed(total, 2) << " s)\n";

  if (o.json) {
    Json report = Json::object();
    report.set("tool", "bench_measures").set("version", HOM_VERSION).set("cases", std::move(cases));
    report.set("checks", hom::io::checks_json(checks.all())).set("time_s", total);
    if (o.json->has_parent_path()) fs::create_directories(o.json->parent_path());
    OutputFile js(*o.json);
    report.write(js.stream());
    js.stream() << '\n';
    js.commit();
  }
  if (o.plot) {
    std::cout << std::flush;
    hom::bench::run_plot_script(o.plot_script, o.out);
  }
  if (!checks.failures().empty()) {
    std::cerr << "bench_measures: " << checks.failures().size() << " of the thesis's claims not reproduced\n";
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  namespace po = boost::program_options;
  Options o;
  po::options_description desc(
      "bench_measures: reproduces the thesis's figures 3.4-3.6, 4.5, 4.6 and D.3 (quality measures)\nOptions");
  std::string out, json, script;
  desc.add_options()("help,h", "print this help")(
      "out", po::value<std::string>(&out)->default_value(o.out.string()), "directory for the CSV (and PNG) files")(
      "json", po::value<std::string>(&json), "write the JSON report (DESIGN.md schema) to this file")(
      "plot", po::bool_switch(&o.plot), "run bench/plot_measures.py on the CSV files (needs python3 + matplotlib)")(
      "plot-script", po::value<std::string>(&script)->default_value(o.plot_script.string()),
      "path of plot_measures.py")("grid", po::value<int>(&o.grid)->default_value(o.grid),
                                  "level-set grid points per axis")(
      "samples", po::value<int>(&o.samples)->default_value(o.samples), "samples of each figure 3.4 sweep");
  try {
    po::variables_map vm;
    po::store(po::parse_command_line(argc, argv, desc), vm);
    po::notify(vm);
    if (vm.count("help")) {
      std::cout << desc << '\n';
      return 0;
    }
    if (o.grid < 11 || o.samples < 11) throw std::invalid_argument("--grid and --samples must be at least 11");
    o.out = out;
    o.plot_script = script;
    if (!json.empty()) o.json = json;
    return run(o);
  } catch (const std::exception& e) {
    std::cerr << "bench_measures: error: " << e.what() << '\n';
    return 2;
  }
}
