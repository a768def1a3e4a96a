#pragma once
/// @file curve_mesh.hpp
/// Chapter 6's a posteriori generation of a curved high-order mesh from a
/// CAD model (sections 6.1 and 6.2), hierarchically:
///
///   1. the linear mesh, classified on the model (cad_mesher.hpp: mesh_cad,
///      or a user mesh and classify), elevated to degree p straight-sided:
///      the ideal mesh M_I (section 6.2.1);
///   2. edges on a CAD curve: the high-order nodes at the Gauss-Lobatto
///      positions of the node set *in arc length* between the edge's ends
///      (section 6.1 step 2, OccCurve::parameter_at_length); other edges
///      stay straight (in the face's parameter space when they lie inside a
///      CAD face, mapped by the surface);
///   3. faces on a CAD face: the nodes placed in the face's parametric space
///      by blending the curved edges into the elevated straight face
///      (Warburton's warp & blend, section 6.1 step 3: an edge's
///      displacement d(r), r = lambda_b - lambda_a, enters the triangle as
///      4 lambda_a lambda_b d(r) / (1 - r^2); quadrilaterals blend their edges
///      transfinitely), with the edges' parameters from their pcurves
///      (CadModel::edge_uv_on_face), periodic parameters unwrapped next to the
///      face's own (ParameterRange::unwrap) and the free parameter of a pole
///      (a degenerate side: S_u = 0) taken from the element's other vertices;
///      mapped by the surface, then optimized on the surface, face by face,
///      with chapter 5's method (optimize_surface: parametric coordinates
///      as unknowns, ideal = the straight-sided element, the face's edges
///      fixed), a tangled face after p-continuation on the surface (its
///      linear sub-mesh untangled first, surface_continuation.hpp;
///      CurveOptions::pcont). For a surface mesh this is the result;
///   4. a volume or planar mesh: the interior nodes optimized with chapter
///      4's method (hom::optimize) against the straight-sided ideal M_I with
///      every boundary node fixed (section 6.2.3), with p-continuation
///      (appendix C) when the initial mesh is tangled (CurveOptions::pcont).
///
/// Mesh kinds (explicitly instantiated in curve_mesh.cpp; all on the WarpBlend
/// node set, which is Gauss-Lobatto on every edge and on quadrilaterals):
/// tetrahedra (Simplex<3>, 3), surface triangles and quadrilaterals
/// (Simplex<2> / Cube<2>, 3), planar triangles and quadrilaterals (Simplex<2>
/// / Cube<2>, 2; the model must lie in z = 0, see place_in_xy_plane).
///
/// Statistics per stage (StageReport), thesis style (tables 5.5, 6.1, 6.2):
/// "linear" (the straight-sided elevated mesh against itself: 1 everywhere
/// unless the linear mesh is inverted), "initial" (curved boundary, before
/// optimization) and "optimized", for the surface part (the boundary faces,
/// each element against its straight-sided counterpart, oriented by the CAD
/// surface's outward normal) and for the volume / planar part.
///
///   auto cad = hom::cad::cube_with_cavity_model();
///   auto linear = hom::cad::mesh_cad<hom::Simplex<3>>(cad, {.size = 1.0});
///   hom::cad::CurveOptions o;
///   o.p = 4;
///   auto r = hom::cad::curve_mesh(cad, linear, o);   // r.mesh, r.stages, r.valid

#include <algorithm>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "cad_model.hpp"
#include "hom/element/cube.hpp"
#include "hom/element/simplex.hpp"
#include "hom/io/msh_data.hpp"
#include "hom/mesh/flat_corners.hpp"
#include "hom/mesh/mesh.hpp"
#include "hom/nodes/warp_blend.hpp"
#include "hom/optimize/certified.hpp"
#include "hom/quality/statistics.hpp"

namespace hom::cad {

struct CurveOptions {
  int p = 2;                       ///< target degree (>= 2)
  std::string measure = "shape";   ///< distortion measure: "shape" or "oddy"
  /// Solver of the volume / planar stage: "newton", "matrix-free",
  /// "gauss-seidel" or "auto" (newton up to 20000 free coordinates, else
  /// matrix-free, as `hom optimize`). Surfaces always use Newton (chapter 5).
  std::string solver = "auto";
  enum class Continuation { automatic, on, off };
  /// p-continuation (appendix C) of the volume / planar stage and, per CAD
  /// face, of the surface stage: automatic = on when the initial curved mesh
  /// (the face) has inverted elements.
  Continuation pcont = Continuation::automatic;
  bool optimize_surface = true;     ///< chapter 5 stage on the boundary faces
  /// Split the linear simplices with a flat corner (every edge there on one
  /// CAD face, or curve in 2D) before curving (mesh/flat_corners.hpp).
  bool split_flat_corners = true;
  int surface_max_iterations = 50;  ///< per CAD face
  int max_iterations = 200;         ///< volume / planar stage, per continuation stage
  /// Volume / planar stage (and its p-continuation stage): stop once every
  /// element has been valid this many iterations; < 0: optimize to
  /// convergence, as the thesis does (OptimizeOptions::iterations_after_valid).
  int iterations_after_valid = -1;
  int threads = 0;                  ///< 0: OpenMP's default
  bool verbose = false;             ///< optimizers' per-iteration lines (stderr)
  /// Called with one line per step (what ran, how long), e.g. to print progress.
  std::function<void(const std::string&)> progress;
  /// Boundary nodes must lie on their CAD entity within tolerance * model size.
  double tolerance = 1e-9;
  /// Certification as the final acceptance test (issue 8). A volume or
  /// planar mesh: hom::optimize's certify stage (optimize/certified.hpp)
  /// after the domain stage, its repair rounds moving interior nodes only (the
  /// boundary stays on the CAD). A surface mesh: each element is certified
  /// against its nodes' interpolated surface normals and repaired by sliding
  /// face nodes on the CAD (surface/certified_surface.hpp). An uncertified
  /// result is not valid
  /// (CurveResult::valid).
  bool certify = false;
  int certify_depth = CertifyOptions{}.max_depth;      ///< subdivision levels before "undecided"
  int certify_rounds = CertifyRepairOptions{}.max_rounds;  ///< repair rounds at most (0: certify only)
  /// With certify, a volume mesh: when the CAD faces' stage leaves some
  /// boundary triangle not certified valid, skip the volume stage and return
  /// the result invalid (CurveResult::volume_skipped_for). Such a tetrahedron
  /// has its face folded against the CAD surface's normal, and in every run
  /// measured (wing_fuselage.step, p = 4 and 5) the volume stage's
  /// uncertified elements were exactly those on such triangles, after up to
  /// 30 min of optimization. Set by --refine-invalid while tries remain: the
  /// next try meshes the model finer there at once.
  bool skip_volume_if_faces_uncertified = false;
};

/// One row of the statistics table.
struct StageReport {
  std::string part;   ///< "surface", "volume" or "planar"
  std::string stage;  ///< "linear", "initial" or "optimized"
  int elements = 0;
  int nodes = 0;
  Statistics quality;          ///< element quality q_E (Min, Max, Mean, Std.Dev., #inv)
  Statistics scaled_jacobian;  ///< scaled Jacobian (table 5.6)
  double time_s = 0.0;         ///< time of the step that produced this stage
  int iterations = 0;          ///< optimizer iterations (optimized stages)
  std::string solver;          ///< optimizer (optimized stages)
  std::string stop_reason;     ///< why the optimizer stopped (the last face's for surfaces)
  int faces_not_converged = 0; ///< surface stage: CAD faces whose solver did not converge
  bool p_continuation = false;
};

/// Whether every classified node lies on its CAD entity at its parameters.
struct CadConformity {
  bool ok = true;
  int checked = 0;              ///< nodes on a vertex, edge or face
  double max_distance = 0.0;    ///< largest |C(t) - x|, |S(u, v) - x|, |V - x|
  std::string problem;          ///< the first failure, naming the node and entity
};

template <class MeshT>
struct CurveResult {
  MeshT mesh;                        ///< the curved mesh (degree p, WarpBlend nodes)
  std::vector<StageReport> stages;   ///< in pipeline order
  CadConformity conformity;          ///< of the result
  int inverted = 0;                  ///< inverted elements of the result (its last stage)
  /// Per element of the result: quality q_E, scaled Jacobian, validity (the
  /// last stage's evaluation; for a surface mesh, oriented by its CAD face).
  std::vector<double> element_quality, element_scaled_jacobian;
  std::vector<bool> element_valid;
  /// The certificate (CurveOptions::certify), element numbers those of `mesh`.
  std::optional<CertificationOutcome> certification;
  /// What the flat-corner split did to the linear mesh (CurveOptions::split_flat_corners).
  FlatCornerSplit flat_corners;
  /// CurveOptions::skip_volume_if_faces_uncertified took effect: the volume
  /// stage did not run (the mesh and its statistics are the initial curved
  /// volume's, no certification), and these elements, ascending, have a
  /// boundary triangle not certified valid on its CAD face. Empty otherwise.
  std::vector<int> volume_skipped_for;
  /// inverted == 0 and conformity.ok, and with CurveOptions::certify every
  /// element certified valid; false when the volume stage was skipped.
  bool valid = false;
  double time_s = 0.0;               ///< whole pipeline (without the linear meshing)
};

template <ElementFamily Family, int SpaceDim>
using CurvedMesh = Mesh<Family, WarpBlend, SpaceDim>;

/// Runs the pipeline on a classified linear mesh of `cad` (degree 1). Throws
/// MeshingError (cad_mesher.hpp) with a message naming the mesh node / edge
/// and the CAD entity when the linear mesh does not fit the model (an edge
/// on a face boundary that no CAD edge joins, a face tag the model lacks),
/// std::invalid_argument for bad options.
template <ElementFamily Family, int SpaceDim>
CurveResult<CurvedMesh<Family, SpaceDim>> curve_mesh(const CadModel& cad, const CurvedMesh<Family, SpaceDim>& linear,
                                                     const CurveOptions& options);

/// Steps 3-4 alone, on a mesh of `cad` that is already curved (degree >= 2;
/// options.p is taken from it), for instance a file written by `hom curve` or
/// a mesh classified on the model with classify(): the nodes on CAD edges and
/// vertices stay, the nodes on CAD faces are optimized on their surfaces in
/// (u, v) (chapter 5, face by face; a node without parameters gets its
/// closest point's), then the interior of a volume or planar mesh (chapter 4),
/// each element against its straight-sided counterpart. Stages "initial" and
/// "optimized" (no "linear" stage). Throws as curve_mesh.
template <ElementFamily Family, int SpaceDim>
CurveResult<CurvedMesh<Family, SpaceDim>> optimize_on_cad(const CadModel& cad, const CurvedMesh<Family, SpaceDim>& curved,
                                                          CurveOptions options);

/// Checks that every node classified on a model vertex, edge or face lies
/// there at its parameters (nodes on an edge or face without parameters
/// fail), within `tolerance` (absolute). Planar meshes are compared in z = 0.
template <ElementFamily Family, int SpaceDim>
CadConformity check_on_cad(const CurvedMesh<Family, SpaceDim>& mesh, const CadModel& cad, double tolerance);

/// Physical groups for a solver: one per model entity of the mesh's
/// dimension that holds elements ("solid N" / "face N") and one per entity of
/// the boundary facets ("face N" / "edge N"), tagged with the entity's tag.
template <class MeshT>
void add_physical_groups(MeshT& mesh) {
  constexpr int D = MeshT::dim;
  std::vector<std::pair<int, int>> used;  // (dim, tag)
  for (int t : mesh.element_entities()) used.emplace_back(D, t);
  for (const auto& f : mesh.boundary_facets()) used.emplace_back(D - 1, f.entity_tag);
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  const char* names[] = {"vertex", "edge", "face", "solid"};
  const bool surface = MeshT::space_dim != D;
  mesh.physical_groups().clear();
  for (const auto& [dim, tag] : used) {
    // A planar mesh's 2D entity is a CAD face; a surface mesh's too.
    const char* word = (dim == 2 && (surface || D == 2)) ? "face" : names[dim];
    mesh.physical_groups().push_back({dim, tag, std::string(word) + " " + std::to_string(tag)});
    bool found = false;
    for (auto& en : mesh.entities())
      if (en.id == EntityId{dim, tag}) {
        en.physical_tags = {tag};
        found = true;
      }
    if (!found) mesh.entities().push_back(Entity{EntityId{dim, tag}, {tag}, {}});
  }
}

/// Gives the MSH nodes on a model edge or face that lack parametric
/// coordinates (a high-order node written at Gmsh's equispaced position is
/// the element map's value there, within the interpolation error of the CAD,
/// and MSH data carries parameters only for nodes whose position is the
/// mesh's own) the parameters of their closest point on the entity. Returns
/// the largest distance between such a node and its closest point (the
/// interpolation gap). A planar mesh's nodes are taken in z = 0.
double add_cad_parameters(io::MshData& data, const CadModel& cad);

}  // namespace hom::cad
