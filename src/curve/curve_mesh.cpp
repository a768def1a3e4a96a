// Chapter 6's a posteriori pipeline (curve_mesh.hpp): curving the edges and
// faces of an elevated linear mesh onto the CAD model, chapter 5 on the
// faces, chapter 4 in the volume.

#include "curve_mesh.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "cad_mesher.hpp"
#include "hom/measure/oddy_measure.hpp"
#include "hom/measure/shape_measure.hpp"
#include "hom/mesh/elevate.hpp"
#include "hom/optimize/optimize.hpp"
#include "hom/quality/mesh_quality.hpp"
#include "hom/surface/certified_surface.hpp"
#include "hom/surface/optimize_surface.hpp"
#include "hom/surface/surface_mesh_quality.hpp"

namespace hom::cad {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

std::string point_text(const Eigen::Vector3d& x) {
  std::ostringstream s;
  s.precision(6);
  s << "(" << x[0] << ", " << x[1] << ", " << x[2] << ")";
  return s.str();
}

/// Where the nodes of a degree-p patch (a boundary face of a tetrahedron, or
/// an element of a surface or planar mesh) of family PF sit: for each local
/// edge its interior nodes from the edge's first vertex to its second with
/// their fraction s of the edge (the node set's Gauss-Lobatto points), the
/// face-interior nodes, and every node's reference point.
template <ElementFamily PF>
struct PatchTables {
  std::vector<std::vector<std::pair<int, double>>> edge_nodes;
  std::vector<int> interior;
  std::vector<typename PF::Point> ref;

  explicit PatchTables(int p) {
    ref = WarpBlend::template points<PF>(p);
    constexpr auto edges = PF::edges();
    edge_nodes.resize(edges.size());
    for (int i = PF::num_vertices; i < int(ref.size()); ++i) {
      const auto w = hom::detail::vertex_shape_values<PF>(ref[i]);
      std::vector<int> support;
      for (int v = 0; v < PF::num_vertices; ++v)
        if (std::abs(w[v]) > 1e-12) support.push_back(v);
      if (support.size() > 2) {
        interior.push_back(i);
        continue;
      }
      bool found = false;
      for (std::size_t k = 0; k < edges.size(); ++k) {
        const int a = edges[k][0], b = edges[k][1];
        if ((support[0] == std::min(a, b) && support[1] == std::max(a, b))) {
          edge_nodes[k].push_back({i, w[b]});
          found = true;
        }
      }
      if (!found) throw std::logic_error("hom::cad::curve_mesh: a patch node on no edge");
    }
    for (auto& list : edge_nodes)
      std::sort(list.begin(), list.end(), [](const auto& x, const auto& y) { return x.second < y.second; });
  }
};

/// A boundary face of the mesh (or an element of a surface / planar mesh)
/// on CAD face `face`: its global nodes in the PF layout.
struct Patch {
  int face = 0;
  std::vector<int> nodes;
  int element = 0;  ///< the element it is (surface and planar meshes) or bounds (volume)
};

/// A mesh edge of the patches: vertices a < b, interior nodes from a to b.
struct EdgeInfo {
  int a = 0, b = 0;
  std::vector<int> nodes;
  std::vector<double> s;
  std::set<int> faces;
  int count = 0;
};

/// 1D Lagrange interpolation through (x_j, y_j) at x.
Eigen::Vector2d lagrange_1d(const std::vector<double>& xs, const std::vector<Eigen::Vector2d>& ys, double x) {
  Eigen::Vector2d r = Eigen::Vector2d::Zero();
  for (std::size_t j = 0; j < xs.size(); ++j) {
    double l = 1.0;
    for (std::size_t m = 0; m < xs.size(); ++m)
      if (m != j) l *= (x - xs[m]) / (xs[j] - xs[m]);
    r += l * ys[j];
  }
  return r;
}

template <ElementFamily Family, int SpaceDim, class Measure>
class Pipeline {
 public:
  static constexpr int D = Family::dim;
  static constexpr bool volume = D == 3;
  static constexpr bool planar = SpaceDim == 2;
  static constexpr bool surface = D == 2 && SpaceDim == 3;
  using PF = std::conditional_t<volume, FaceFamily<Family>, Family>;
  using MeshT = Mesh<Family, WarpBlend, SpaceDim>;
  using FaceMesh = Mesh<PF, WarpBlend, 3>;

  Pipeline(const CadModel& cad, const CurveOptions& o, const Measure& measure)
      : cad_(cad), o_(o), measure_(measure), tables_(o.p) {
    vertex_curves_.resize(cad.num_vertices() + 1);
    for (int e = 1; e <= cad.num_edges(); ++e) {
      if (cad.degenerated(e)) continue;
      curves_.emplace(e, cad.curve(e));
      const auto v = cad.edge_vertices(e);
      vertex_curves_[v[0]].insert(e);
      vertex_curves_[v[1]].insert(e);
      const auto f = cad.edge_faces(e);
      edge_faces_[e] = std::set<int>(f.begin(), f.end());
    }
    for (int f = 1; f <= cad.num_faces(); ++f) surfaces_.emplace(f, cad.surface(f));
  }

  /// The unit normal of CAD face `tag` (curve in 2D) at its closest point
  /// to node `node` of `mesh`; empty where the parameterization is singular
  /// (a pole, an apex) or the entity is not in the model.
  std::optional<Eigen::Matrix<double, SpaceDim, 1>> entity_normal(const MeshT& mesh, int tag, int node) const {
    Eigen::Vector3d x = Eigen::Vector3d::Zero();
    x.template head<SpaceDim>() = mesh.node(node);
    if constexpr (SpaceDim == 3) {
      const auto it = surfaces_.find(tag);
      if (it == surfaces_.end()) return std::nullopt;
      const auto d = it->second.derivatives(it->second.project(x));
      const Eigen::Vector3d n = d.col(0).cross(d.col(1));
      if (n.norm() <= 1e-12 * d.col(0).norm() * d.col(1).norm()) return std::nullopt;
      return n.normalized();
    } else {
      const auto it = curves_.find(tag);
      if (it == curves_.end()) return std::nullopt;
      const Eigen::Vector3d t = it->second.derivative(it->second.project(x));
      if (t.head<2>().norm() == 0.0) return std::nullopt;
      return Eigen::Vector2d(-t[1], t[0]).normalized();
    }
  }

  /// The linear mesh with its flat corners split (mesh/flat_corners.hpp):
  /// a simplex whose edges at a corner all lie on one CAD face (curve in 2D),
  /// or on faces tangent to each other there (a fillet's seam), would have
  /// det = 0 there once curved, which no optimization of the interior can
  /// mend. Surface meshes and quadrilaterals are left as they are (the mesher
  /// splits their ears, src/cad/ears.hpp).
  MeshT without_flat_corners(const MeshT& linear, FlatCornerSplit& s) {
    MeshT out = linear;
    if constexpr (Family::is_simplex && !surface) {
      if (!o_.split_flat_corners) return out;
      s = split_flat_corners(out, EntityNormal<SpaceDim>([&](int tag, int node) {
                               return entity_normal(out, tag, node);  // the mesh of the current pass
                             }));
      if (s.corners > 0)
        say("linear mesh: " + std::to_string(s.corners) + " flat corners (every edge there on one CAD " +
            (volume ? "face" : "curve") + ", or on nearly coplanar or tangent ones): " +
            std::to_string(s.edges_split) + " interior edges split, " + std::to_string(s.faces_split) +
            " interior faces split, " + std::to_string(s.centroid_splits) +
            " elements split at their centroid; " + std::to_string(out.num_elements()) + " elements");
    }
    return out;
  }

  CurveResult<MeshT> run(const MeshT& linear) {
    const auto start = Clock::now();
    CurveResult<MeshT> out;
    // 1. Ideal mesh: the linear mesh elevated, straight-sided (6.2.1).
    auto t0 = Clock::now();
    mesh_ = elevate(without_flat_corners(linear, out.flat_corners), o_.p);
    straight_ = mesh_.nodes();
    const double t_elevate = since(t0);
    out.stages.push_back(linear_stage(t_elevate));
    say("elevated to p = " + std::to_string(o_.p) + " straight-sided: " + std::to_string(mesh_.num_elements()) +
        " elements, " + std::to_string(mesh_.num_nodes()) + " nodes (" + fmt_s(t_elevate) + ")");

    // 2.-3. The boundary onto the CAD: edges, then faces (6.1 steps 2-3).
    t0 = Clock::now();
    collect_patches();
    collect_edges();
    const int on_curves = place_edges();
    int face_nodes = 0;
    if constexpr (!planar) face_nodes = place_faces();
    const double t_boundary = since(t0);
    say("boundary on the CAD: " + std::to_string(on_curves) + " mesh edges on CAD curves (nodes at Gauss-Lobatto "
        "positions in arc length), " + std::to_string(face_nodes) + " face nodes blended in (u, v) (" +
        fmt_s(t_boundary) + ")");
    optimize_placed(out, t_boundary);
    out.time_s = since(start);
    return out;
  }

  /// Steps 3-4 alone on a mesh that is already curved onto the model (its
  /// boundary nodes classified on the CAD entities, for instance a file
  /// written by `hom curve`): the ideal is each element's straight-sided
  /// counterpart (its vertices), the CAD-edge nodes stay, the face nodes
  /// slide on their surfaces and the interior nodes move.
  CurveResult<MeshT> run_curved(const MeshT& curved) {
    const auto start = Clock::now();
    CurveResult<MeshT> out;
    mesh_ = curved;
    mesh_.reset_ideal();
    straight_ = mesh_.nodes();  // only the vertex columns are read (straight3)
    snap_to_cad();
    collect_patches();
    optimize_placed(out, 0.0);
    out.time_s = since(start);
    return out;
  }

 private:
  /// Puts every node classified on a CAD vertex, edge or face with its
  /// parameters at V, C(t) or S(u, v). A curved mesh read from a file is on
  /// the CAD only up to the interpolation error of its stored nodes (MSH
  /// keeps the element map at equispaced points, hom's nodes are
  /// interpolated from them); the optimizers then keep the nodes on their
  /// entities exactly.
  void snap_to_cad() {
    for (int i = 0; i < mesh_.num_nodes(); ++i) {
      const NodeClass& c = mesh_.node_class(i);
      if (!c.entity || (c.kind == NodeKind::free && c.entity->dim == SpaceDim)) continue;
      if (planar && c.entity->dim == D) continue;  // the planar domain itself
      const int tag = c.entity->tag;
      Eigen::Vector3d x;
      if (c.entity->dim == 0 && tag >= 1 && tag <= cad_.num_vertices())
        x = cad_.vertex(tag);
      else if (c.entity->dim == 1 && c.num_params == 1 && curves_.count(tag))
        x = curves_.at(tag).evaluate(c.params[0]);
      else if (c.entity->dim == 2 && c.num_params == 2 && surfaces_.count(tag))
        x = surfaces_.at(tag).evaluate({c.params[0], c.params[1]});
      else
        continue;
      mesh_.nodes().col(i) = x.template head<SpaceDim>();
    }
  }

  /// Chapter 5 on the CAD faces, chapter 4 in the domain, the result's
  /// per-element quality and its CAD conformity.
  void optimize_placed(CurveResult<MeshT>& out, double t_boundary) {
    if constexpr (!planar) {
      // 3. Chapter 5 on every CAD face.
      const auto t0 = Clock::now();
      build_face_meshes();
      StageReport initial = surface_stage("initial");
      initial.time_s = t_boundary;
      out.stages.push_back(initial);
      say("surface, initial curved: " + row(initial) + " (" + fmt_s(since(t0)) + " to evaluate)");
      StageReport optimized = optimize_faces();
      out.stages.push_back(optimized);
      say("surface, optimized (chapter 5, " + std::to_string(face_meshes_.size()) + " CAD faces" +
          (optimized.p_continuation ? ", p-continuation on the tangled ones" : "") + "): " + row(optimized) + ", " +
          std::to_string(optimized.iterations) + " Newton iterations (" + fmt_s(optimized.time_s) + ")");
    }
    if constexpr (!surface) {
      // 4. Chapter 4 in the volume / planar domain.
      MeshQuality q0 = mesh_quality(mesh_, measure_, IdealKind::straight_sided, rule());
      StageReport initial = make_stage(part(), "initial", q0);
      initial.nodes = mesh_.num_nodes();
      initial.time_s = planar ? t_boundary : 0.0;
      out.stages.push_back(initial);
      say(std::string(part()) + ", initial curved: " + row(initial));
      out.volume_skipped_for = elements_on_uncertified_faces();
      if (out.volume_skipped_for.empty()) {
        out.stages.push_back(optimize_domain(initial.quality.inverted));
      } else {
        final_ = std::move(q0);
        say("volume stage skipped: " + std::to_string(out.volume_skipped_for.size()) +
            " elements have a boundary triangle not certified valid on its CAD face (the result is invalid)");
      }
    }
    out.element_quality = final_.qualities();
    out.element_scaled_jacobian = final_.scaled_jacobians();
    out.element_valid.resize(final_.elements.size());
    for (std::size_t e = 0; e < final_.elements.size(); ++e) out.element_valid[e] = final_.elements[e].valid;
    out.inverted = out.stages.back().quality.inverted;
    out.conformity = check_on_cad<Family, SpaceDim>(mesh_, cad_, o_.tolerance * cad_.size());
    out.valid = out.inverted == 0 && out.conformity.ok && out.volume_skipped_for.empty();
    if (o_.certify && out.volume_skipped_for.empty()) {
      if constexpr (surface) certification_ = face_certification_;
      if (!certification_) certification_ = certification_outcome(std::vector<ElementCertificate<PF>>{}, RepairStop::certified);
      const auto& c = *certification_;
      say_certificate(part(), c);
      out.valid = out.valid && c.certified();
      out.certification = std::move(certification_);
    }
    out.mesh = std::move(mesh_);
  }

  /// With CurveOptions::skip_volume_if_faces_uncertified, the elements of a
  /// volume mesh whose boundary triangles the CAD faces' stage left
  /// uncertified (ascending, each once); empty when the volume stage runs.
  std::vector<int> elements_on_uncertified_faces() const {
    if (!volume || !o_.skip_volume_if_faces_uncertified || !face_certification_ ||
        face_certification_->certified())
      return {};
    std::vector<int> elements = face_certification_->uncertified;  // element numbers (merge_face_certificate)
    elements.erase(std::unique(elements.begin(), elements.end()), elements.end());  // sorted by add()
    return elements;
  }

  CertifyOptions certify_options() const {
    CertifyOptions co;
    co.max_depth = o_.certify_depth;
    co.threads = o_.threads;
    return co;
  }

  static const char* part() { return volume ? "volume" : planar ? "planar" : "surface"; }
  const QuadratureRule<D>& rule() const { return quadrature_for<Family, DefaultExactness>(o_.p); }
  const QuadratureRule<2>& face_rule() const { return quadrature_for<PF, DefaultExactness>(o_.p); }

  void say(const std::string& s) const {
    if (o_.progress) o_.progress(s);
  }
  static std::string fmt_s(double t) {
    char b[32];
    std::snprintf(b, sizeof b, "%.2f s", t);
    return b;
  }
  static std::string row(const StageReport& r) {
    char b[160];
    std::snprintf(b, sizeof b, "min q %.3f, mean q %.3f, %d inverted, min scaled Jacobian %.3f", r.quality.min,
                  r.quality.mean, r.quality.inverted, r.scaled_jacobian.min);
    return b;
  }

  StageReport make_stage(const std::string& p, const std::string& stage, const MeshQuality& q) const {
    StageReport r;
    r.part = p;
    r.stage = stage;
    r.elements = int(q.elements.size());
    r.quality = q.quality_statistics();
    r.scaled_jacobian = q.scaled_jacobian_statistics();
    return r;
  }

  StageReport linear_stage(double time) {
    MeshQuality q;
    if constexpr (surface)
      q = surface_mesh_quality(mesh_, measure_, IdealKind::straight_sided, rule());
    else
      q = mesh_quality(mesh_, measure_, IdealKind::straight_sided, rule());
    StageReport r = make_stage(part(), "linear", q);
    r.nodes = mesh_.num_nodes();
    r.time_s = time;
    return r;
  }

  // --- positions ------------------------------------------------------------
  Eigen::Vector3d straight3(int i) const {
    Eigen::Vector3d x = Eigen::Vector3d::Zero();
    x.template head<SpaceDim>() = straight_.col(i);
    return x;
  }
  Eigen::Vector3d pos3(int i) const {
    Eigen::Vector3d x = Eigen::Vector3d::Zero();
    x.template head<SpaceDim>() = mesh_.node(i);
    return x;
  }
  void set_pos(int i, const Eigen::Vector3d& x) { mesh_.node(i) = x.template head<SpaceDim>(); }

  // --- patches and edges -------------------------------------------------------
  void collect_patches() {
    std::set<std::vector<int>> seen;
    auto add = [&](int face, std::vector<int> nodes, int element, const std::string& what) {
      if (face < 1 || face > cad_.num_faces())
        throw MeshingError(cad_.name() + ": " + what + " is on face " + std::to_string(face) + ", the model has " +
                           std::to_string(cad_.num_faces()) + " faces");
      std::vector<int> key(nodes.begin(), nodes.begin() + PF::num_vertices);
      std::sort(key.begin(), key.end());
      if (!seen.insert(key).second) return;
      patches_.push_back({face, std::move(nodes), element});
    };
    if constexpr (volume) {
      for (const auto& f : mesh_.boundary_facets())
        add(f.entity_tag, mesh_.facet_node_ids(f), f.element, "boundary face of element " + std::to_string(f.element));
    } else {
      for (int e = 0; e < mesh_.num_elements(); ++e) {
        const auto col = mesh_.element(e);
        add(mesh_.element_entities()[e], std::vector<int>(col.data(), col.data() + col.size()), e,
            "element " + std::to_string(e));
      }
    }
  }

  void collect_edges() {
    constexpr auto edges = PF::edges();
    for (const auto& pt : patches_)
      for (std::size_t k = 0; k < edges.size(); ++k) {
        int a = pt.nodes[edges[k][0]], b = pt.nodes[edges[k][1]];
        auto [it, inserted] = edges_.try_emplace({std::min(a, b), std::max(a, b)});
        EdgeInfo& info = it->second;
        if (inserted) {
          info.a = std::min(a, b);
          info.b = std::max(a, b);
          for (const auto& [local, s] : tables_.edge_nodes[k]) {
            info.nodes.push_back(pt.nodes[local]);
            info.s.push_back(s);
          }
          if (a > b) {
            std::reverse(info.nodes.begin(), info.nodes.end());
            std::reverse(info.s.begin(), info.s.end());
            for (double& s : info.s) s = 1.0 - s;
          }
        }
        info.faces.insert(pt.face);
        ++info.count;
      }
  }

  /// CAD curves through node i: its own, or those of its vertex.
  std::set<int> curves_of(int i) const {
    const NodeClass& c = mesh_.node_class(i);
    if (!c.entity) return {};
    if (c.entity->dim == 1) return {c.entity->tag};
    if (c.entity->dim == 0 && c.entity->tag < int(vertex_curves_.size())) return vertex_curves_[c.entity->tag];
    return {};
  }

  std::string edge_name(const EdgeInfo& e) const {
    return "mesh edge from node " + std::to_string(e.a) + " at " + point_text(straight3(e.a)) + " to node " +
           std::to_string(e.b) + " at " + point_text(straight3(e.b));
  }

  /// Curves each edge onto its CAD curve or face; returns the number of
  /// edges on curves.
  int place_edges() {
    int on_curves = 0;
    for (auto& [key, e] : edges_) {
      if (e.nodes.empty()) continue;
      const Eigen::Vector3d mid = 0.5 * (straight3(e.a) + straight3(e.b));
      const double length = (straight3(e.b) - straight3(e.a)).norm();
      std::set<int> candidates;
      {
        const auto ca = curves_of(e.a), cb = curves_of(e.b);
        for (int c : ca)
          if (cb.count(c) && std::includes(edge_faces_[c].begin(), edge_faces_[c].end(), e.faces.begin(), e.faces.end()))
            candidates.insert(c);
      }
      bool feature = e.faces.size() >= 2 || e.count == 1;
      if (!feature) {
        // Two patches of one face: on a curve only if it is the face's seam.
        std::set<int> seams;
        for (int c : candidates)
          if (edge_faces_[c].size() == 1 && distance_to_curve(c, mid) <= 0.25 * length) seams.insert(c);
        candidates = seams;
        feature = !candidates.empty();
      }
      if (feature) {
        if (candidates.empty()) {
          std::ostringstream faces;  // (not string +=: GCC 12 -O3 warns falsely, -Wrestrict)
          for (int f : e.faces) faces << ' ' << f;
          throw MeshingError(cad_.name() + ": " + edge_name(e) + " bounds model face(s)" + faces.str() +
                             " but no model edge of those faces joins its ends");
        }
        int best = *candidates.begin();
        double best_d = std::numeric_limits<double>::infinity();
        for (int c : candidates) {
          const double d = distance_to_curve(c, mid);
          if (d < best_d) {
            best_d = d;
            best = c;
          }
        }
        place_on_curve(e, best, mid);
        ++on_curves;
      } else if constexpr (!planar) {
        place_in_face(e, *e.faces.begin());
      }
    }
    return on_curves;
  }

  double distance_to_curve(int c, const Eigen::Vector3d& x) const {
    const auto& g = curves_.at(c);
    return (g.evaluate(g.project(x)) - x).norm();
  }

  /// The parameter of node i on curve c, the representative nearest tm.
  double curve_parameter(int i, int c, double tm) const {
    const auto& g = curves_.at(c);
    const auto range = g.range();
    const NodeClass& cl = mesh_.node_class(i);
    std::vector<double> options;
    if (cl.entity && *cl.entity == EntityId{1, c} && cl.num_params == 1) {
      options.push_back(cl.params[0]);
    } else {
      const Eigen::Vector3d x = pos3(i);
      const double scale = std::max(g.length(), 1e-300);
      options.push_back(g.project(x));
      // A closed, non-periodic curve passes through its vertex at both ends.
      for (double t : {range.lo, range.hi})
        if ((g.evaluate(t) - x).norm() <= 1e-6 * scale) options.push_back(t);
    }
    double best = options.front(), best_d = std::numeric_limits<double>::infinity();
    for (double t : options) {
      const double u = range.unwrap(t, tm);
      if (std::abs(u - tm) < best_d) {
        best_d = std::abs(u - tm);
        best = u;
      }
    }
    return best;
  }

  /// Section 6.1 step 2: the edge's nodes at its Gauss-Lobatto fractions of
  /// the arc length between its ends.
  void place_on_curve(const EdgeInfo& e, int c, const Eigen::Vector3d& mid) {
    const auto& g = curves_.at(c);
    const double tm = g.project(mid);
    const double ta = curve_parameter(e.a, c, tm), tb = curve_parameter(e.b, c, tm);
    const double length = g.arc_length(ta, tb);
    if (!(std::abs(length) > 0.0))
      throw MeshingError(cad_.name() + ": " + edge_name(e) + " has zero length on model edge " + std::to_string(c));
    for (std::size_t j = 0; j < e.nodes.size(); ++j) {
      const double t = g.parameter_at_length(ta, e.s[j] * length);
      set_pos(e.nodes[j], g.evaluate(t));
      NodeClass& cl = mesh_.node_class(e.nodes[j]);
      cl.kind = NodeKind::on_entity;
      cl.entity = EntityId{1, c};
      cl.num_params = 1;
      cl.params = {g.range().normalize(t), 0.0};
    }
  }

  bool degenerate(const OccSurface& s, const Eigen::Vector2d& uv, int k) const {
    const auto d = s.derivatives(uv);
    return d.col(k).norm() < 1e-8 * std::max(d.col(1 - k).norm(), 1e-300);
  }

  /// (u, v) of node i on face f (not unwrapped).
  Eigen::Vector2d uv_on_face(int i, int f) const {
    const NodeClass& c = mesh_.node_class(i);
    const auto& s = surfaces_.at(f);
    if (c.entity && c.entity->dim == 2 && c.entity->tag == f && c.num_params == 2) return {c.params[0], c.params[1]};
    if (c.entity && c.entity->dim == 1 && c.num_params == 1 && edge_faces_.count(c.entity->tag) &&
        edge_faces_.at(c.entity->tag).count(f))
      return cad_.edge_uv_on_face(c.entity->tag, f, c.params[0]);
    return s.project(pos3(i));
  }

  void unwrap_near(const OccSurface& s, Eigen::Vector2d& uv, const Eigen::Vector2d& ref) const {
    for (int k = 0; k < 2; ++k) uv[k] = s.range(k).unwrap(uv[k], ref[k]);
  }

  void set_face_node(int i, int f, const Eigen::Vector2d& uv) {
    const auto& s = surfaces_.at(f);
    set_pos(i, s.evaluate(uv));
    NodeClass& cl = mesh_.node_class(i);
    cl.kind = NodeKind::on_entity;
    cl.entity = EntityId{2, f};
    cl.num_params = 2;
    cl.params = {s.range(0).normalize(uv[0]), s.range(1).normalize(uv[1])};
  }

  /// An edge inside face f: straight in (u, v), mapped by the surface.
  void place_in_face(const EdgeInfo& e, int f) {
    const auto& s = surfaces_.at(f);
    Eigen::Vector2d ua = uv_on_face(e.a, f), ub = uv_on_face(e.b, f);
    unwrap_near(s, ub, ua);
    for (int k = 0; k < 2; ++k) {  // a pole: its free parameter from the other end
      if (degenerate(s, ua, k)) ua[k] = ub[k];
      if (degenerate(s, ub, k)) ub[k] = ua[k];
    }
    for (std::size_t j = 0; j < e.nodes.size(); ++j) set_face_node(e.nodes[j], f, (1 - e.s[j]) * ua + e.s[j] * ub);
  }

  /// Section 6.1 step 3: each patch's interior nodes in (u, v), the elevated
  /// straight face plus the blended displacements of its curved edges.
  int place_faces() {
    int placed = 0;
    constexpr int nv = PF::num_vertices;
    constexpr auto edges = PF::edges();
    for (const auto& pt : patches_) {
      if (tables_.interior.empty()) break;
      const int f = pt.face;
      const auto& s = surfaces_.at(f);
      const int n = int(pt.nodes.size());
      std::vector<Eigen::Vector2d> U(n);
      int ref = -1;
      for (int i = 0; i < n; ++i) {
        if (i >= nv && std::find(tables_.interior.begin(), tables_.interior.end(), i) != tables_.interior.end()) continue;
        U[i] = uv_on_face(pt.nodes[i], f);
        const auto& c = mesh_.node_class(pt.nodes[i]);
        if (ref < 0 && c.entity && c.entity->dim == 2) ref = i;
      }
      if (ref < 0) ref = 0;
      for (int i = 0; i < n; ++i)
        if (i != ref) unwrap_near(s, U[i], U[ref]);
      // Poles among the vertices: the free parameter from the others.
      for (int k = 0; k < 2; ++k)
        for (int v = 0; v < nv; ++v)
          if (degenerate(s, U[v], k)) {
            double sum = 0.0;
            int cnt = 0;
            for (int w = 0; w < nv; ++w)
              if (w != v && !degenerate(s, U[w], k)) {
                sum += U[w][k];
                ++cnt;
              }
            if (cnt > 0) U[v][k] = sum / cnt;
          }
      // Vertex weights of every node: barycentric coordinates of its
      // straight-sided position (triangles; the node set of a tetrahedron's
      // faces need not be the triangle's), reference bilinear weights (quads).
      auto weights = [&](int i) {
        std::array<double, nv> w{};
        if constexpr (PF::is_simplex) {
          Eigen::Matrix<double, 3, 2> A;
          A.col(0) = straight3(pt.nodes[1]) - straight3(pt.nodes[0]);
          A.col(1) = straight3(pt.nodes[2]) - straight3(pt.nodes[0]);
          const Eigen::Vector2d l = A.colPivHouseholderQr().solve(straight3(pt.nodes[i]) - straight3(pt.nodes[0]));
          w = {1.0 - l[0] - l[1], l[0], l[1]};
        } else {
          w = hom::detail::vertex_shape_values<PF>(tables_.ref[i]);
        }
        return w;
      };
      auto straight_uv = [&](const std::array<double, nv>& w) {
        Eigen::Vector2d u = Eigen::Vector2d::Zero();
        for (int v = 0; v < nv; ++v) u += w[v] * U[v];
        return u;
      };
      // Edge displacements, as polynomials of the position along the edge.
      struct EdgeWarp {
        std::vector<double> x;
        std::vector<Eigen::Vector2d> y;
      };
      std::vector<EdgeWarp> warps(edges.size());
      for (std::size_t k = 0; k < edges.size(); ++k) {
        auto& w = warps[k];
        if constexpr (!PF::is_simplex) {
          w.x.push_back(0.0);
          w.y.push_back(Eigen::Vector2d::Zero());
        }
        for (const auto& [local, sk] : tables_.edge_nodes[k]) {
          const Eigen::Vector2d d = U[local] - straight_uv(weights(local));
          if constexpr (PF::is_simplex) {
            // Warburton: d(r) / (1 - r^2), r = 2 s - 1, a polynomial of degree p - 2.
            w.x.push_back(2 * sk - 1);
            w.y.push_back(d / (4 * sk * (1 - sk)));
          } else {
            w.x.push_back(sk);
            w.y.push_back(d);
          }
        }
        if constexpr (!PF::is_simplex) {
          w.x.push_back(1.0);
          w.y.push_back(Eigen::Vector2d::Zero());
        }
      }
      for (int i : tables_.interior) {
        const auto w = weights(i);
        Eigen::Vector2d uv = straight_uv(w);
        for (std::size_t k = 0; k < edges.size(); ++k) {
          const int a = edges[k][0], b = edges[k][1];
          if constexpr (PF::is_simplex) {
            uv += 4 * w[a] * w[b] * lagrange_1d(warps[k].x, warps[k].y, w[b] - w[a]);
          } else {
            // Transfinite: the edge's displacement at the point's position
            // along it, weighted by the distance from the opposite edge.
            const auto ca = PF::vertex_corner(a), cb = PF::vertex_corner(b);
            const int run = ca[0] != cb[0] ? 0 : 1, side = 1 - run;
            const auto& xi = tables_.ref[i];
            const double sk = ca[run] ? (1 - xi[run]) / 2 : (1 + xi[run]) / 2;
            const double blend = ca[side] ? (1 + xi[side]) / 2 : (1 - xi[side]) / 2;
            uv += blend * lagrange_1d(warps[k].x, warps[k].y, sk);
          }
        }
        set_face_node(pt.nodes[i], f, uv);
        ++placed;
      }
    }
    return placed;
  }

  // --- chapter 5 on the faces -------------------------------------------------
  struct FacePatchMesh {
    int face = 0;
    FaceMesh mesh;
    std::vector<int> global;
    /// Of each face element, the mesh element it is (surface mesh) or bounds (volume mesh).
    std::vector<int> patch;
    Eigen::Matrix2Xd uv;
  };

  void build_face_meshes() {
    std::map<int, std::vector<int>> by_face;
    for (std::size_t k = 0; k < patches_.size(); ++k) by_face[patches_[k].face].push_back(int(k));
    std::vector<int> local(mesh_.num_nodes(), -1);
    const auto perm = io::detail::reflection_permutation<PF>(o_.p);
    for (const auto& [f, ids] : by_face) {
      const auto& s = surfaces_.at(f);
      FacePatchMesh fm;
      fm.face = f;
      for (int k : ids) fm.patch.push_back(patches_[k].element);
      const int np = PF::num_nodes(o_.p);
      typename FaceMesh::Connectivity conn(np, ids.size());
      for (std::size_t e = 0; e < ids.size(); ++e)
        for (int i = 0; i < np; ++i) {
          const int g = patches_[ids[e]].nodes[i];
          if (local[g] < 0) {
            local[g] = int(fm.global.size());
            fm.global.push_back(g);
          }
          conn(i, e) = local[g];
        }
      const int n = int(fm.global.size());
      Eigen::Matrix3Xd X(3, n), I(3, n);
      fm.uv.resize(2, n);
      for (int k = 0; k < n; ++k) {
        X.col(k) = pos3(fm.global[k]);
        I.col(k) = straight3(fm.global[k]);
        fm.uv.col(k) = uv_on_face(fm.global[k], f);
      }
      // Orientation: the elements must turn like S_u x S_v (the surface
      // quality's and optimizer's normal); a face whose patches turn the
      // other way is optimized on mirrored elements.
      int votes = 0;
      for (std::size_t e = 0; e < ids.size(); ++e) {
        const auto& nodes = patches_[ids[e]].nodes;
        Eigen::Vector3d nf;
        if constexpr (PF::is_simplex)
          nf = (straight3(nodes[1]) - straight3(nodes[0])).cross(straight3(nodes[2]) - straight3(nodes[0]));
        else
          nf = (straight3(nodes[2]) - straight3(nodes[0])).cross(straight3(nodes[3]) - straight3(nodes[1]));
        for (int g : nodes) {
          const auto& c = mesh_.node_class(g);
          if (!(c.entity && c.entity->dim == 2 && c.num_params == 2)) continue;
          const auto d = s.derivatives({c.params[0], c.params[1]});
          const double dot = d.col(0).cross(d.col(1)).dot(nf);
          votes += dot > 0 ? 1 : dot < 0 ? -1 : 0;
          break;
        }
      }
      if (votes == 0) {  // no face node: the centroid of the first patch
        const auto& nodes = patches_[ids.front()].nodes;
        Eigen::Vector3d c = Eigen::Vector3d::Zero();
        for (int v = 0; v < PF::num_vertices; ++v) c += straight3(nodes[v]) / PF::num_vertices;
        const auto d = s.derivatives(s.project(c));
        Eigen::Vector3d nf = (straight3(nodes[1]) - straight3(nodes[0])).cross(straight3(nodes[2]) - straight3(nodes[0]));
        votes = d.col(0).cross(d.col(1)).dot(nf) >= 0 ? 1 : -1;
      }
      if (votes < 0) {
        const auto old = conn;
        for (Eigen::Index e = 0; e < conn.cols(); ++e)
          for (int i = 0; i < np; ++i) conn(i, e) = old(perm[i], e);
      }
      fm.mesh = FaceMesh(o_.p, std::move(X), std::move(conn));
      fm.mesh.set_ideal_coordinates(std::move(I));
      for (int k = 0; k < n; ++k) fm.mesh.node_class(k) = mesh_.node_class(fm.global[k]);
      fm.mesh.element_entities().assign(ids.size(), f);
      for (int g : fm.global) local[g] = -1;
      face_meshes_.push_back(std::move(fm));
    }
  }

  /// The boundary faces' quality, face by face (each against its CAD
  /// surface's normal); for a surface mesh it is kept per element (final_).
  StageReport surface_stage(const std::string& stage) {
    MeshQuality all;
    if constexpr (surface) all.elements.resize(mesh_.num_elements());
    for (const auto& fm : face_meshes_) {
      const MeshQuality q = surface_mesh_quality(fm.mesh, surfaces_.at(fm.face), fm.uv, measure_,
                                                 IdealKind::straight_sided, face_rule());
      if constexpr (surface) {
        for (std::size_t e = 0; e < q.elements.size(); ++e) all.elements[fm.patch[e]] = q.elements[e];
      } else {
        all.elements.insert(all.elements.end(), q.elements.begin(), q.elements.end());
      }
    }
    StageReport r = make_stage("surface", stage, all);
    r.nodes = surface_nodes();
    if constexpr (surface) final_ = std::move(all);
    return r;
  }

  int surface_nodes() const {
    std::set<int> all;
    for (const auto& fm : face_meshes_) all.insert(fm.global.begin(), fm.global.end());
    return int(all.size());
  }

  /// The face stage's options (chapter 5 on one CAD face).
  OptimizeOptions face_options() const {
    OptimizeOptions opt;
    opt.solver = SolverKind::newton;
    opt.ideal = IdealKind::straight_sided;
    opt.threads = o_.threads;
    opt.max_iterations = o_.surface_max_iterations;
    opt.verbose = o_.verbose;
    return opt;
  }

  StageReport optimize_faces() {
    const auto t0 = Clock::now();
    int iterations = 0, not_converged = 0;
    bool continued = false;
    std::string reason = "none";
    std::optional<CertificationOutcome> certification;
    for (auto& fm : face_meshes_) {
      const auto free = surface_free_node_mask(fm.mesh);
      const bool movable = std::any_of(free.begin(), free.end(), [](bool b) { return b; });
      OptimizeOptions opt = face_options();
      const auto& s = surfaces_.at(fm.face);
      const Eigen::Matrix2Xd uv_start = fm.uv;
      if (o_.optimize_surface && movable) {
        // Bounded parameters: a node that the blending put a hair outside
        // the face's parameter box would make the objective +inf.
        for (int k = 0; k < fm.mesh.num_nodes(); ++k)
          if (free[k])
            for (int a = 0; a < 2; ++a) fm.uv(a, k) = s.range(a).normalize(fm.uv(a, k));
        // p-continuation on the surface (appendix C, surface_continuation.hpp),
        // with the domain stage's policy: automatic = when the face is tangled.
        opt.p_continuation = o_.pcont == CurveOptions::Continuation::on ||
                             (o_.pcont == CurveOptions::Continuation::automatic && face_tangled(fm));
        const auto r = hom::optimize_surface<Measure, DefaultExactness>(fm.mesh, s, fm.uv, opt, measure_);
        iterations += r.result.iterations + (r.continuation ? r.continuation->iterations : 0);
        continued = continued || r.continuation.has_value();
        not_converged += !r.result.converged;
        reason = std::string(to_string(r.result.reason));
      }
      if (o_.certify) {
        // Certification and repair of the face (surface/certified_surface.hpp):
        // a fold between the quadrature points, at a corner node say, is
        // mended here, where the face nodes can still slide on the CAD.
        CertifyRepairOptions ro;
        ro.certify = certify_options();
        const bool repair = o_.optimize_surface && movable;
        ro.max_rounds = repair ? o_.certify_rounds : 0;
        CertificationOutcome c = certify_and_repair_surface<Measure, DefaultExactness>(
            fm.mesh, s, fm.uv, surface_ideals(fm.mesh, opt.ideal), opt.solver_options(), ro, o_.threads,
            opt.regularization_alpha, measure_, repair ? &uv_start : nullptr);
        if (!repair && !c.certified()) c.reason = RepairStop::not_repaired;
        if (!c.certified()) say_face_not_certified(fm, c);
        merge_face_certificate(certification, c, fm.patch);
      }
      if (o_.optimize_surface && movable)
        for (int k = 0; k < fm.mesh.num_nodes(); ++k)
          if (free[k]) set_face_node(fm.global[k], fm.face, fm.uv.col(k));
    }
    const double t = since(t0);
    StageReport r = surface_stage("optimized");
    r.time_s = t;
    r.iterations = iterations;
    r.solver = o_.optimize_surface ? "newton" : "none";
    r.stop_reason = reason;
    r.faces_not_converged = not_converged;
    r.p_continuation = continued;
    if (certification) {
      if constexpr (!surface) say_certificate("CAD faces", *certification);  // a surface mesh's is the final one
      face_certification_ = std::move(certification);
    }
    return r;
  }

  /// Adds one face's certification to the faces' so far; `patch` maps the
  /// face mesh's elements to the mesh's patches (elements of a surface mesh).
  static void merge_face_certificate(std::optional<CertificationOutcome>& all, const CertificationOutcome& face,
                                     const std::vector<int>& patch) {
    if (!all) {
      all.emplace();
      all->on_surface = true;
    }
    all->add(face, patch);
  }

  /// One line per CAD face left uncertified: which face, which elements
  /// (the mesh's), and why its repair stopped.
  void say_face_not_certified(const FacePatchMesh& fm, const CertificationOutcome& c) const {
    std::string elements;
    for (std::size_t k = 0; k < c.uncertified.size() && k < 5; ++k)
      elements += (k ? " " : "") + std::to_string(fm.patch[c.uncertified[k]]);
    if (c.uncertified.size() > 5) elements += " ...";
    say("  CAD face " + std::to_string(fm.face) + ": " + std::to_string(c.invalid) + " invalid, " +
        std::to_string(c.undecided) + " undecided of " + std::to_string(fm.mesh.num_elements()) + " (" +
        (surface ? "elements " : "boundary faces of elements ") + elements + "); repair stopped: " +
        std::string(to_string(c.reason)) + (c.restored ? ", face kept as optimized" : ""));
  }

  void say_certificate(const std::string& what, const CertificationOutcome& c) const {
    std::string line = what + " certified: " + std::to_string(c.valid) + " valid, " + std::to_string(c.invalid) +
                       " invalid, " + std::to_string(c.undecided) + " undecided";
    if (c.rounds > 0)
      line += " (before repair " + std::to_string(c.initial_invalid) + " invalid, " +
              std::to_string(c.initial_undecided) + " undecided; " + std::to_string(c.rounds) + " repair rounds" +
              (c.restored ? ", undone" : "") + ")";
    say(line + " (" + fmt_s(c.time_s) + ")");
  }

  /// Whether some element of the face mesh is invalid (against its
  /// straight-sided counterpart, on its CAD surface).
  bool face_tangled(const FacePatchMesh& fm) const {
    const MeshQuality q = surface_mesh_quality(fm.mesh, surfaces_.at(fm.face), fm.uv, measure_, IdealKind::straight_sided,
                                               face_rule());
    return std::any_of(q.elements.begin(), q.elements.end(), [](const ElementQuality& e) { return !e.valid; });
  }

  // --- chapter 4 in the domain -------------------------------------------------
  StageReport optimize_domain(int initial_inverted) {
    int free_nodes = 0;
    for (const auto& c : mesh_.node_classes()) free_nodes += c.kind == NodeKind::free;
    const long dofs = long(free_nodes) * D;
    OptimizeOptions opt;
    opt.ideal = IdealKind::straight_sided;
    opt.solver = o_.solver == "auto" ? auto_solver_kind(dofs) : parse_solver_kind(o_.solver);
    opt.p_continuation = o_.pcont == CurveOptions::Continuation::on ||
                         (o_.pcont == CurveOptions::Continuation::automatic && initial_inverted > 0);
    opt.threads = o_.threads;
    opt.max_iterations = o_.max_iterations;
    opt.iterations_after_valid = o_.iterations_after_valid;
    opt.continuation_iterations_after_valid = o_.iterations_after_valid;
    opt.verbose = o_.verbose;
    opt.certify = o_.certify;
    opt.certify_depth = o_.certify_depth;
    opt.certify_rounds = o_.certify_rounds;
    const auto t0 = Clock::now();
    int iterations = 0;
    std::string reason = "none";
    if (free_nodes > 0) {
      const auto r = hom::optimize<Measure, DefaultExactness>(mesh_, opt, measure_);
      iterations = r.result.iterations + (r.continuation ? r.continuation->iterations : 0);
      reason = std::string(to_string(r.result.reason));
      certification_ = r.certification;
    } else if (o_.certify) {
      const auto tc = Clock::now();
      certification_ = certification_outcome(certify_mesh(mesh_, certify_options()).elements, RepairStop::no_free_nodes);
      certification_->time_s = since(tc);
    }
    const double t = since(t0);
    final_ = mesh_quality(mesh_, measure_, IdealKind::straight_sided, rule());
    StageReport r = make_stage(part(), "optimized", final_);
    r.nodes = mesh_.num_nodes();
    r.time_s = t;
    r.iterations = iterations;
    r.solver = std::string(to_string(opt.solver));
    r.stop_reason = reason;
    r.p_continuation = opt.p_continuation;
    say(std::string(part()) + ", optimized (chapter 4, " + r.solver + (r.p_continuation ? ", p-continuation" : "") +
        ", " + std::to_string(free_nodes) + " free nodes): " + row(r) + ", " + std::to_string(iterations) +
        " iterations (" + fmt_s(t) + ")");
    return r;
  }

  const CadModel& cad_;
  const CurveOptions& o_;
  const Measure& measure_;
  PatchTables<PF> tables_;
  std::map<int, OccCurve> curves_;
  std::map<int, OccSurface> surfaces_;
  std::vector<std::set<int>> vertex_curves_;
  std::map<int, std::set<int>> edge_faces_;
  MeshT mesh_;
  typename MeshT::Coordinates straight_;
  std::vector<Patch> patches_;
  std::map<std::pair<int, int>, EdgeInfo> edges_;
  std::vector<FacePatchMesh> face_meshes_;
  MeshQuality final_;
  std::optional<CertificationOutcome> certification_;  ///< CurveOptions::certify
  std::optional<CertificationOutcome> face_certification_;  ///< the CAD faces', with CurveOptions::certify
};

}  // namespace

namespace {

/// Runs `step` on the pipeline of the options' measure.
template <ElementFamily Family, int SpaceDim, class Step>
CurveResult<CurvedMesh<Family, SpaceDim>> with_pipeline(const CadModel& cad, const CurveOptions& options, Step step) {
  if (options.solver != "auto") parse_solver_kind(options.solver);  // throws on a bad name
  if (options.measure == "oddy") {
    const OddyMeasure m{};
    Pipeline<Family, SpaceDim, OddyMeasure> pipeline(cad, options, m);
    return step(pipeline);
  }
  if (options.measure != "shape")
    throw std::invalid_argument("hom::cad: the measure must be shape or oddy, got '" + options.measure + "'");
  const ShapeMeasure m{};
  Pipeline<Family, SpaceDim, ShapeMeasure> pipeline(cad, options, m);
  return step(pipeline);
}

}  // namespace

template <ElementFamily Family, int SpaceDim>
CurveResult<CurvedMesh<Family, SpaceDim>> curve_mesh(const CadModel& cad, const CurvedMesh<Family, SpaceDim>& linear,
                                                     const CurveOptions& options) {
  if (options.p < 2) throw std::invalid_argument("hom::cad::curve_mesh: the degree must be >= 2, got " + std::to_string(options.p));
  if (linear.degree() != 1)
    throw std::invalid_argument("hom::cad::curve_mesh: the input must be a linear mesh, got degree " +
                                std::to_string(linear.degree()));
  return with_pipeline<Family, SpaceDim>(cad, options, [&](auto& pipeline) { return pipeline.run(linear); });
}

template <ElementFamily Family, int SpaceDim>
CurveResult<CurvedMesh<Family, SpaceDim>> optimize_on_cad(const CadModel& cad, const CurvedMesh<Family, SpaceDim>& curved,
                                                          CurveOptions options) {
  if (curved.degree() < 2)
    throw std::invalid_argument("hom::cad::optimize_on_cad: the mesh must be curved (degree >= 2), got degree " +
                                std::to_string(curved.degree()));
  options.p = curved.degree();
  return with_pipeline<Family, SpaceDim>(cad, options, [&](auto& pipeline) { return pipeline.run_curved(curved); });
}

template <ElementFamily Family, int SpaceDim>
CadConformity check_on_cad(const CurvedMesh<Family, SpaceDim>& mesh, const CadModel& cad, double tolerance) {
  CadConformity r;
  std::map<int, OccCurve> curves;
  std::map<int, OccSurface> surfaces;
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    const NodeClass& c = mesh.node_class(i);
    if (!c.entity || c.entity->dim > 2 || (c.kind == NodeKind::free && c.entity->dim == SpaceDim)) continue;
    if (c.entity->dim == Family::dim && SpaceDim == Family::dim) continue;  // the planar domain itself
    Eigen::Vector3d x = Eigen::Vector3d::Zero();
    x.template head<SpaceDim>() = mesh.node(i);
    const int tag = c.entity->tag;
    double d = std::numeric_limits<double>::infinity();
    std::string what;
    if (c.entity->dim == 0) {
      what = "model vertex " + std::to_string(tag);
      if (tag >= 1 && tag <= cad.num_vertices()) d = (cad.vertex(tag) - x).norm();
    } else if (c.entity->dim == 1) {
      what = "model edge " + std::to_string(tag);
      if (tag >= 1 && tag <= cad.num_edges() && !cad.degenerated(tag) && c.num_params == 1) {
        auto it = curves.try_emplace(tag, cad.curve(tag)).first;
        d = (it->second.evaluate(c.params[0]) - x).norm();
      }
    } else {
      what = "model face " + std::to_string(tag);
      if (tag >= 1 && tag <= cad.num_faces() && c.num_params == 2) {
        auto it = surfaces.try_emplace(tag, cad.surface(tag)).first;
        d = (it->second.evaluate({c.params[0], c.params[1]}) - x).norm();
      }
    }
    ++r.checked;
    if (std::isfinite(d)) r.max_distance = std::max(r.max_distance, d);
    if (!(d <= tolerance) && r.ok) {
      r.ok = false;
      r.problem = "node " + std::to_string(i) + " at " + point_text(x) + " is " +
                  (std::isfinite(d) ? std::to_string(d) + " off " : "without parameters on ") + what;
    }
  }
  return r;
}

double add_cad_parameters(io::MshData& data, const CadModel& cad) {
  std::map<int, OccCurve> curves;
  std::map<int, OccSurface> surfaces;
  double gap = 0.0;
  for (auto& n : data.nodes) {
    if (!n.entity || n.num_params == n.entity->dim || n.entity->dim < 1 || n.entity->dim > 2) continue;
    const Eigen::Vector3d x(n.x[0], n.x[1], n.x[2]);
    const int tag = n.entity->tag;
    if (n.entity->dim == 1) {
      if (tag < 1 || tag > cad.num_edges() || cad.degenerated(tag)) continue;
      const auto& g = curves.try_emplace(tag, cad.curve(tag)).first->second;
      const double t = g.project(x);
      gap = std::max(gap, (g.evaluate(t) - x).norm());
      n.num_params = 1;
      n.params = {t, 0.0, 0.0};
    } else {
      if (tag < 1 || tag > cad.num_faces()) continue;
      const auto& s = surfaces.try_emplace(tag, cad.surface(tag)).first->second;
      const Eigen::Vector2d uv = s.project(x);
      gap = std::max(gap, (s.evaluate(uv) - x).norm());
      n.num_params = 2;
      n.params = {uv[0], uv[1], 0.0};
    }
  }
  return gap;
}

// The mesh kinds of the pipeline (curve_mesh.hpp).
#define HOM_CURVE_INSTANTIATE(F, S)                                                                        \
  template CurveResult<CurvedMesh<F, S>> curve_mesh<F, S>(const CadModel&, const CurvedMesh<F, S>&,        \
                                                          const CurveOptions&);                            \
  template CurveResult<CurvedMesh<F, S>> optimize_on_cad<F, S>(const CadModel&, const CurvedMesh<F, S>&,   \
                                                               CurveOptions);                              \
  template CadConformity check_on_cad<F, S>(const CurvedMesh<F, S>&, const CadModel&, double);
HOM_CURVE_INSTANTIATE(Simplex<3>, 3)
HOM_CURVE_INSTANTIATE(Simplex<2>, 3)
HOM_CURVE_INSTANTIATE(Cube<2>, 3)
HOM_CURVE_INSTANTIATE(Simplex<2>, 2)
HOM_CURVE_INSTANTIATE(Cube<2>, 2)
#undef HOM_CURVE_INSTANTIATE

}  // namespace hom::cad
