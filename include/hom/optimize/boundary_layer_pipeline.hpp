#pragma once
/// @file boundary_layer_pipeline.hpp
/// Curved high-order boundary-layer meshes of simplices from an inviscid
/// linear mesh and an analytic wall (thesis section 6.3.3.1, steps 1-3,
/// table 6.4):
///
///   (a) "inviscid"  the linear isotropic input, measured against itself;
///   (b) "inserted"  the boundary-layer topology (mesh/boundary_layer.hpp),
///                   the new wall midpoints placed on the wall geometry
///                   (each on its facets' own wall entity, on the
///                   intersection where two meet:
///                   detail::project_onto_wall_entities), measured against
///                   the per-element stretched ideal;
///   (c) "smoothed"  (b) smoothed and untangled against that ideal at p = 1
///                   (chapter 4), the wall and outer boundary nodes fixed
///                   (every node not classified free is held; the layer's
///                   nodes on the wall border first go to their full
///                   heights, then, in 3D, slide on their faces: the
///                   faces are optimized on their surfaces first against
///                   the faces of the stretched ideal; see
///                   BoundaryLayerPipelineOptions::optimize_side_faces);
///   (d) "curved"    (c) elevated to degree p, its wall nodes put on the
///                   geometry (geometry/curve_boundary.hpp) and, unless
///                   carry_layer is off, the layer's free nodes (and its
///                   nodes on the wall border, kept on their neighbouring
///                   entity) moved along with the wall (fading to nothing
///                   at the layer's top),
///                   measured against
///                   the straight-sided (c): "the ideal mesh is represented by
///                   the viscous linear mesh";
///   (e) "optimized" in 3D, the nodes on the non-wall faces that the
///                   geometry has (the box faces a wing section meets)
///                   first optimized on their surfaces (chapter 5, the
///                   faces' edges held), then (d) smoothed and untangled
///                   against the same ideal;
///                   with high_order_optimize.certify, every element is then
///                   certified (Bernstein bounds) and the uncertified ones
///                   repaired (optimize/certified.hpp), the wall held.
///
/// When (c) leaves inverted elements the pipeline stops there (unless
/// stop_if_smoothed_invalid is off): (d) and (e) measure against the
/// smoothed linear mesh, whose inverted elements make an ideal with
/// negative determinants, so they cannot end valid and only cost time (a
/// tangled layer under a cavity ring took longer at (e) than all the rest).
///
///     hom::BoundaryLayerPipelineOptions o;
///     o.layer = {.first_height = 1e-3, .growth = 2, .layers = 4};
///     o.p = 4;
///     hom::GeometryModel<3> wall;
///     wall.add_surface(sphere_tag, hom::Sphere(c, 0.5));
///     auto r = hom::boundary_layer_pipeline(linear, {sphere_tag}, wall, o);
///     // r.stages: table 6.4's rows; r.mesh: the final curved mesh
///
/// Why the wall midpoints are projected at (b) and not only at (d): the
/// first level is usually thinner than the chord's sagitta, so a layer built
/// on the flat facets and curved only at (d) would put the wall above the
/// first interface nodes; placing them at (b) lets (c) build the layers on
/// the curved wall's vertices. The linear wall still cuts the chords, so (d)
/// moves the high-order wall nodes by at most the sagitta of a sub-facet.
/// A layer thinner than that sagitta cannot be valid with straight-sided
/// top faces: keep the total height above it (or refine the wall).
///
/// This sits in optimize/ because it drives the optimizer; it needs only
/// the header-only core (Eigen).

#include <algorithm>
#include <chrono>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "hom/element/simplex.hpp"
#include "hom/geometry/curve_boundary.hpp"
#include "hom/geometry/geometry_model.hpp"
#include "hom/measure/shape_measure.hpp"
#include "hom/mesh/boundary_layer.hpp"
#include "hom/mesh/elevate.hpp"
#include "hom/mesh/mesh.hpp"
#include "hom/optimize/optimize.hpp"
#include "hom/quadrature/quadrature_policy.hpp"
#include "hom/quality/mesh_quality.hpp"
#include "hom/quality/statistics.hpp"
#include "hom/surface/optimize_boundary_face.hpp"

namespace hom {

/// OptimizeOptions that regularize the whole mesh while any element is
/// invalid (the pipeline's default, see BoundaryLayerPipelineOptions).
inline OptimizeOptions whole_mesh_regularized() {
  OptimizeOptions o;
  o.regularization_scope = RegularizationScope::whole_mesh;
  return o;
}

struct BoundaryLayerPipelineOptions {
  BoundaryLayerOptions layer;
  int p = 2;                             ///< degree of stages (d) and (e) (>= 1)
  /// Stages (c) and (e), the latter's certify stage included. Both
  /// regularize the whole mesh while any element is invalid
  /// (RegularizationScope::whole_mesh): with the element-wise scope, the
  /// valid neighbours of the elements that curving inverted keep sigma_0's
  /// barrier, which cuts the Newton steps to 2^-17 (SD7003 wing at p = 4,
  /// 198 inverted at (e): still 198 after 8 iterations, against valid after
  /// 56 with the whole-mesh scope; bench_boundary_layer
  /// --regularization-scope).
  OptimizeOptions linear_optimize = whole_mesh_regularized();
  OptimizeOptions high_order_optimize = whole_mesh_regularized();  ///< see above
  /// At (d), move the layer's free nodes with the wall (detail::carry_wall_curving):
  /// without it the curving of the wall is absorbed by the first level alone,
  /// which inverts it wherever the sub-facet's sagitta is a sizeable fraction
  /// of the first height (for p = 2, about a quarter). false reproduces the
  /// thesis's stage (d), which moves the wall nodes only.
  bool carry_layer = true;
  /// Stop after (c) when the smoothed linear mesh still has inverted
  /// elements (file comment); off runs (d) and (e) whatever (c) left.
  bool stop_if_smoothed_invalid = true;
  /// 3D, before the volume at (c) and at (e): optimize the nodes on every
  /// non-wall boundary face that `geometry` has a surface for on that
  /// surface (chapter 5, surface/optimize_boundary_face.hpp), the face's
  /// edges held; at (c) against the faces of the stretched ideal, at (e)
  /// against the smoothed linear mesh, then certified and their folds
  /// repaired on the surface. The volume optimizer holds these nodes, so a
  /// triangle folded in its face leaves its tetrahedron inverted whatever
  /// the free nodes do: at (c), the SD7003 wing's layer triangles at the
  /// 4-degree trailing edge on both box faces (the border nodes' full
  /// heights along the averaged normal fold them); at (e), triangles curved
  /// along the wall's border.
  bool optimize_side_faces = true;
  /// Called after each stage with its name, e.g. to print progress.
  std::function<void(const std::string&)> progress;
};

/// One row of table 6.4.
struct BoundaryLayerStage {
  std::string name;   ///< "inviscid", "inserted", "smoothed", "curved", "optimized"
  std::string ideal;  ///< what the quality is measured against: "own", "layer", "smoothed-linear"
  int p = 1;
  int elements = 0;
  int nodes = 0;
  Statistics quality;          ///< shape quality q_E (Min, Max, Mean, Std.Dev., #inv)
  Statistics scaled_jacobian;
  double time_s = 0.0;         ///< time of the step that produced the stage
  int iterations = 0;          ///< optimizer iterations (stages c and e)
  bool converged = false;      ///< optimizer converged (stages c and e)
  std::string stop_reason;     ///< why the optimizer stopped (stages c and e)
};

template <int Dim>
struct BoundaryLayerPipelineResult {
  using MeshT = Mesh<Simplex<Dim>>;
  BoundaryLayer<Dim> layer;   ///< stage (b): inserted mesh, stretched ideal, levels, aspect ratio
  MeshT smoothed;             ///< stage (c), linear
  MeshT mesh;                 ///< stage (e), degree p: the result (the (c) mesh when stopped_after_smoothing)
  std::vector<BoundaryLayerStage> stages;  ///< (a) to (e), or (a) to (c) when stopped_after_smoothing
  bool valid = false;         ///< no inverted element in the result, det > 0 at every node too
  /// (c) left inverted elements and the pipeline stopped there
  /// (BoundaryLayerPipelineOptions::stop_if_smoothed_invalid).
  bool stopped_after_smoothing = false;
  /// Stage (e)'s certify-and-repair outcome, when high_order_optimize.certify
  /// (the stage's statistics are of the repaired mesh).
  std::optional<CertificationOutcome> certification;
  double time_s = 0.0;        ///< stages (b) to (e)
  /// Surface-optimizer iterations on the non-wall faces at the start of (e)
  /// (3D: BoundaryLayerPipelineOptions::optimize_side_faces).
  int boundary_face_iterations = 0;

  /// What the last stage's quality is measured against: the smoothed linear
  /// mesh (straight-sided) after (e), the stretched layer ideal after (c).
  IdealMesh<Simplex<Dim>> final_ideal() const {
    return stopped_after_smoothing ? layer.ideal : smoothed.straight_sided_ideal();
  }
};

namespace detail {

template <int Dim>
using Coordinates = typename Mesh<Simplex<Dim>>::Coordinates;

/// Closest point of x on any of the wall entities' geometries (curves in 2D,
/// surfaces in 3D) that `model` has.
template <int Dim>
Eigen::Matrix<double, Dim, 1> project_to_nearest_wall(const GeometryModel<Dim>& model, const std::vector<int>& walls,
                                                      const Eigen::Matrix<double, Dim, 1>& x) {
  Eigen::Matrix<double, Dim, 1> best = x;
  double best_d = std::numeric_limits<double>::infinity();
  for (int t : walls) {
    Eigen::Matrix<double, Dim, 1> y;
    if constexpr (Dim == 2) {
      const auto* g = model.curve(t);
      if (!g) continue;
      y = g->evaluate(g->project(x));
    } else {
      const auto* g = model.surface(t);
      if (!g) continue;
      y = g->evaluate(g->project(x));
    }
    if ((y - x).norm() < best_d) {
      best_d = (y - x).norm();
      best = y;
    }
  }
  return best;
}

/// The point of the wall entities `entities` (their geometry in `model`)
/// that x belongs at: on one entity its closest point; on several (x on an
/// edge where they meet) alternating projections onto each, which converge
/// to their intersection where they meet at an angle (and stay within the
/// projections' distance of it where they meet tangentially). Entities
/// without geometry in `model` are skipped; with none left, x.
template <int Dim>
Eigen::Matrix<double, Dim, 1> project_onto_wall_entities(const GeometryModel<Dim>& model, const std::vector<int>& entities,
                                                         const Eigen::Matrix<double, Dim, 1>& x) {
  Eigen::Matrix<double, Dim, 1> y = project_to_nearest_wall<Dim>(model, entities, x);
  if (entities.size() < 2) return y;
  for (int sweep = 0; sweep < 100; ++sweep) {
    const Eigen::Matrix<double, Dim, 1> start = y;
    for (int t : entities) y = project_to_nearest_wall<Dim>(model, {t}, y);
    if ((y - start).norm() <= 1e-13 * (1.0 + y.norm())) break;
  }
  return y;
}

/// Moves every free node of a layer element with the curving of the wall
/// below it, fading out across the layer: a node x over wall facet f has its
/// foot y on the flat sub-facet (of f's 1-to-4 / 1-to-2 split, positions of
/// `linear`) under it and its height t above it; it moves by
/// max(0, 1 - t / H) (P(y) - y), P the projection onto f's wall entity. At the wall
/// (t = 0) this is curve_boundary's own move; at the top of the layer, none.
///
/// With `model`, the layer's nodes on the wall border (on_entity of a
/// neighbouring, non-wall boundary entity: the box faces a wing section
/// meets) move the same way and are then projected back onto their entity's
/// geometry. The optimizer holds them at (e), so without this the first
/// level there keeps straight interface-1 edges under a wall edge bulged by
/// its sagitta (more than h0 = 2e-4 on the NACA 0012 section's sub-facets)
/// and stays inverted: 62 level-0 elements along both box faces after (e)
/// in the quick wing case. Nodes on the wall (or a wall curve), fixed nodes
/// and entities without geometry in `model` stay.
template <int Dim>
void carry_wall_curving(Mesh<Simplex<Dim>>& mesh, const BoundaryLayer<Dim>& layer, const Mesh<Simplex<Dim>>& linear,
                        const WallProjection<Dim>& project, const GeometryModel<Dim>* model = nullptr) {
  using Point = Eigen::Matrix<double, Dim, 1>;
  // Sub-facets in site order (layer_templates.hpp), oriented like the facet.
  constexpr int num_sub = Dim == 3 ? 4 : 2;
  static constexpr int sub[4][3] = {{0, 3, 5}, {3, 1, 4}, {5, 4, 2}, {3, 4, 5}};
  static constexpr int sub2[2][2] = {{0, 2}, {2, 1}};
  const double H = layer.total_height;
  std::vector<char> done(mesh.num_nodes(), 0);
  const Coordinates<Dim> start = mesh.nodes();
  for (int e = 0; e < mesh.num_elements(); ++e) {
    if (!layer.wall_facet[e]) continue;
    const int facet = *layer.wall_facet[e];
    const auto& w = layer.facet_wall_nodes[facet];
    const std::vector<int> entity{layer.facet_tags[facet]};
    for (int i : mesh.element(e)) {
      if (done[i]) continue;
      // A border node stays on its neighbouring boundary entity's geometry.
      const NodeClass& cls = mesh.node_class(i);
      const AnySurface* side_surface = nullptr;
      const AnyCurve<Dim>* side_curve = nullptr;
      if (cls.kind == NodeKind::on_entity && model && cls.entity && cls.entity->dim == Dim - 1 &&
          std::find(layer.facet_tags.begin(), layer.facet_tags.end(), cls.entity->tag) == layer.facet_tags.end()) {
        if constexpr (Dim == 3)
          side_surface = model->surface(cls.entity->tag);
        else
          side_curve = model->curve(cls.entity->tag);
      }
      if (cls.kind != NodeKind::free && !side_surface && !side_curve) continue;
      done[i] = 1;
      const Point x = start.col(i);
      // The sub-facet whose barycentric coordinates of x's foot are the most
      // inside (the one containing the foot, if any).
      double best = -std::numeric_limits<double>::infinity();
      Point foot = x, normal = Point::Zero();
      for (int k = 0; k < num_sub; ++k) {
        std::array<Point, Dim> v;
        for (int j = 0; j < Dim; ++j) v[j] = linear.node(w[Dim == 3 ? sub[k][j] : sub2[k][j]]);
        const auto [n, measure] = facet_normal<Dim>(v);
        if (!(measure > 0.0)) continue;
        const Point y = x - n.dot(x - v[0]) * n;  // foot on the sub-facet's plane
        // Barycentric coordinates of y (least squares in the facet's span).
        Eigen::Matrix<double, Dim, Dim - 1> T;
        for (int j = 1; j < Dim; ++j) T.col(j - 1) = v[j] - v[0];
        const Eigen::Matrix<double, Dim - 1, 1> l = T.colPivHouseholderQr().solve(y - v[0]);
        const double inside = std::min(1.0 - l.sum(), l.minCoeff());
        if (inside > best) {
          best = inside;
          // Clamp the foot into the sub-facet so P is evaluated on the wall's patch.
          Eigen::Matrix<double, Dim - 1, 1> c = l.cwiseMax(0.0);
          if (c.sum() > 1.0) c /= c.sum();
          foot = v[0] + T * c;
          normal = n;
        }
      }
      const double t = std::abs(normal.dot(x - foot));
      const double weight = std::max(0.0, 1.0 - t / H);
      if (!(weight > 0.0)) continue;
      Point y = x + weight * (project(foot, entity) - foot);
      NodeClass& moved = mesh.node_class(i);  // its parameters follow it
      if (side_surface) {
        if constexpr (Dim == 3) {
          const Eigen::Vector2d uv = side_surface->project(y);
          y = side_surface->evaluate(uv);
          moved.num_params = 2;
          moved.params = {uv[0], uv[1]};
        }
      } else if (side_curve) {
        const double u = side_curve->project(y);
        y = side_curve->evaluate(u);
        moved.num_params = 1;
        moved.params = {u, 0.0};
      }
      mesh.node(i) = y;
    }
  }
}

template <int Dim>
BoundaryLayerStage measure_stage(const Mesh<Simplex<Dim>>& mesh, const IdealMesh<Simplex<Dim>>& ideal, std::string name,
                                 std::string ideal_name) {
  const auto q = mesh_quality(mesh, ShapeMeasure{}, ideal, quadrature_for<Simplex<Dim>, DefaultExactness>(mesh.degree()));
  BoundaryLayerStage s;
  s.name = std::move(name);
  s.ideal = std::move(ideal_name);
  s.p = mesh.degree();
  s.elements = mesh.num_elements();
  s.nodes = mesh.num_nodes();
  s.quality = q.quality_statistics();
  s.scaled_jacobian = q.scaled_jacobian_statistics();
  return s;
}

inline void record_optimization(BoundaryLayerStage& s, const OptimizeResult& r) {
  s.time_s = r.time_s;
  s.iterations = r.result.iterations + (r.continuation ? r.continuation->iterations : 0);
  s.converged = r.result.converged;
  s.stop_reason = std::string(to_string(r.result.reason));
}

/// BoundaryLayerPipelineOptions::optimize_side_faces: optimizes the nodes on
/// every non-wall face of `mesh` that `geometry` has a surface for, on that
/// surface, against `ideal` (per element) or, without it, the mesh's
/// straight-sided ideal; `certify` adds the certify-and-repair stage on each
/// face. Returns the surface optimizer's iterations over all faces, repair
/// rounds included. (A template, although only Dim = 3 is used, so that the
/// surface optimizer is instantiated where the pipeline is, not in every
/// file that includes this header.)
template <int Dim>
int optimize_side_faces(Mesh<Simplex<Dim>>& mesh, const std::vector<int>& walls, const GeometryModel<Dim>& geometry,
                        const OptimizeOptions& stage, bool certify, const IdealMesh<Simplex<Dim>>* ideal = nullptr) {
  static_assert(Dim == 3, "hom::detail::optimize_side_faces: the faces of a tetrahedral mesh");
  std::vector<int> faces;
  for (const auto& f : mesh.boundary_facets())
    if (std::find(walls.begin(), walls.end(), f.entity_tag) == walls.end() && geometry.surface(f.entity_tag) &&
        std::find(faces.begin(), faces.end(), f.entity_tag) == faces.end())
      faces.push_back(f.entity_tag);
  OptimizeOptions o;
  o.solver = SolverKind::newton;
  o.threads = stage.threads;
  o.max_iterations = stage.max_iterations;
  o.verbose = stage.verbose;
  o.certify = certify;
  o.certify_depth = stage.certify_depth;
  o.certify_rounds = stage.certify_rounds;
  int iterations = 0;
  for (int f : faces)
    if (const auto r = optimize_boundary_face(mesh, f, *geometry.surface(f), o, ShapeMeasure{}, ideal)) {
      iterations += r->optimization.result.iterations;
      if (r->certification)
        for (const SolverResult& round : r->certification->repairs) iterations += round.iterations;
    }
  return iterations;
}

}  // namespace detail

/// Runs stages (a)-(e) (file comment). `geometry` holds the wall's analytic
/// geometry under the wall entity tags (other entities' geometry, if any, is
/// used at (d) to curve their nodes too). Throws std::invalid_argument for bad
/// options (insert_boundary_layer's and p < 1).
template <int Dim>
BoundaryLayerPipelineResult<Dim> boundary_layer_pipeline(const Mesh<Simplex<Dim>>& inviscid, const std::vector<int>& wall_tags,
                                                         const GeometryModel<Dim>& geometry,
                                                         const BoundaryLayerPipelineOptions& options) {
  using Clock = std::chrono::steady_clock;
  auto seconds_since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
  if (options.p < 1) throw std::invalid_argument("hom::boundary_layer_pipeline: p must be >= 1, got " + std::to_string(options.p));
  auto progress = [&](const BoundaryLayerStage& s) {
    if (options.progress) options.progress(s.name);
  };
  BoundaryLayerPipelineResult<Dim> out;
  const auto start = Clock::now();

  // (a)
  out.stages.push_back(detail::measure_stage(inviscid, inviscid.straight_sided_ideal(), "inviscid", "own"));
  progress(out.stages.back());

  // (b)
  auto t = Clock::now();
  const WallProjection<Dim> project = [&](const Eigen::Matrix<double, Dim, 1>& x, const std::vector<int>& entities) {
    return detail::project_onto_wall_entities<Dim>(geometry, entities, x);
  };
  out.layer = insert_boundary_layer(inviscid, wall_tags, options.layer, project);
  const double insert_s = seconds_since(t);
  out.stages.push_back(detail::measure_stage(out.layer.mesh, out.layer.ideal, "inserted", "layer"));
  out.stages.back().time_s = insert_s;
  progress(out.stages.back());

  // (c): the held border nodes first go to their heights (boundary_layer.hpp),
  // then, in 3D, slide on their faces against the faces of the stretched
  // ideal (the volume holds them).
  out.smoothed = out.layer.mesh;
  for (int n : out.layer.border_nodes) out.smoothed.node(n) = out.layer.full_height_positions.col(n);
  t = Clock::now();
  if constexpr (Dim == 3)
    if (options.optimize_side_faces)
      out.boundary_face_iterations += detail::optimize_side_faces(out.smoothed, wall_tags, geometry,
                                                                  options.linear_optimize, false, &out.layer.ideal);
  const double linear_faces_s = seconds_since(t);
  const auto rc = optimize(out.smoothed, out.layer.ideal, options.linear_optimize);
  out.stages.push_back(detail::measure_stage(out.smoothed, out.layer.ideal, "smoothed", "layer"));
  detail::record_optimization(out.stages.back(), rc);
  out.stages.back().time_s += linear_faces_s;
  progress(out.stages.back());
  if (options.stop_if_smoothed_invalid && out.stages.back().quality.inverted > 0) {
    out.mesh = out.smoothed;
    out.stopped_after_smoothing = true;
    out.time_s = seconds_since(start);
    return out;  // valid stays false
  }

  // (d)
  t = Clock::now();
  out.smoothed.reset_ideal();
  const IdealMesh<Simplex<Dim>> linear_ideal = out.smoothed.straight_sided_ideal();
  out.mesh = elevate(out.smoothed, options.p);
  curve_boundary(out.mesh, geometry);
  if (options.carry_layer) detail::carry_wall_curving<Dim>(out.mesh, out.layer, out.smoothed, project, &geometry);
  const double curve_s = seconds_since(t);
  out.stages.push_back(detail::measure_stage(out.mesh, linear_ideal, "curved", "smoothed-linear"));
  out.stages.back().time_s = curve_s;
  progress(out.stages.back());

  // (e): first the faces the layer meets besides the wall, on their surfaces
  // (chapter 5; their nodes are held in the volume), then the volume.
  t = Clock::now();
  if constexpr (Dim == 3)
    if (options.optimize_side_faces)
      // Always certified: a triangle folded at a node cannot be mended by
      // the volume stage, which holds these nodes, and the faces are small.
      out.boundary_face_iterations +=
          detail::optimize_side_faces(out.mesh, wall_tags, geometry, options.high_order_optimize, true);
  const double faces_s = seconds_since(t);
  const auto re = optimize(out.mesh, linear_ideal, options.high_order_optimize);
  out.stages.push_back(detail::measure_stage(out.mesh, linear_ideal, "optimized", "smoothed-linear"));
  detail::record_optimization(out.stages.back(), re);
  out.stages.back().time_s += faces_s;
  out.certification = re.certification;
  progress(out.stages.back());

  // Valid as hom curve's acceptance test: det D phi_P > 0 at every
  // quadrature point (no inverted element) and at every node (a fold at an
  // element corner that no quadrature point sees; the stage's min scaled
  // Jacobian is over both).
  out.valid = out.stages.back().quality.inverted == 0 && out.stages.back().scaled_jacobian.min > 0.0;
  out.time_s = seconds_since(start);
  return out;
}

}  // namespace hom
