#pragma once
/// @file cad_mesher.hpp
/// Linear meshes of a CadModel whose boundary nodes are classified on the
/// model's vertices, edges and faces (chapter 6, section 6.1 step 1: the
/// linear mesh the a posteriori pipeline curves), made with Gmsh's library
/// (OpenCASCADE kernel), or supplied by the user and classified by
/// projection. Compiled in src/cad; this header needs only hom's headers.
///
///   auto cad = hom::cad::read_cad("part.step");
///   hom::cad::CadMeshOptions o;
///   o.size = 2.0;
///   auto mesh = hom::cad::mesh_cad<hom::Simplex<3>>(cad, o);   // tetrahedra
///   auto skin = hom::cad::mesh_cad<hom::Simplex<2>, hom::WarpBlend, 3>(cad, o);  // surface triangles
///
/// Entity tags of the result are the CadModel's (cad_model.hpp): a node on
/// face f has entity {2, f} and (u, v) with cad.surface(f).evaluate(u, v)
/// equal to its position; on edge e, {1, e} and t; on vertex v, {0, v}
/// (fixed). Element entities are solid tags (faces for a surface mesh),
/// boundary facets carry face tags (edge tags for a 2D mesh).
///
/// Gmsh gets the healed shape itself (importShapesNativePointer: Debian's
/// Gmsh and hom_cad use the same OpenCASCADE). Its entity tags need not be
/// the model's, so entities are matched: Gmsh points to model vertices by
/// position; Gmsh curves and surfaces to the model edge / face on which
/// their mesh nodes lie at the same parameters (Gmsh uses the OpenCASCADE
/// parameterization) and, for faces, inside the trimming; Gmsh volumes to
/// the solid with the same faces. Then every boundary node is checked:
/// |S(u, v) - x| (|C(t) - x|, |V - x|) must not exceed `tolerance` times
/// the model's size. An entity or node that cannot be classified is an error
/// (MeshingError) that names it.

#include <algorithm>
#include <functional>
#include <iterator>
#include <limits>
#include <map>
#include <optional>
#include <vector>
#include <stdexcept>
#include <string>

#include "cad_model.hpp"
#include "hom/element/cube.hpp"
#include "hom/element/simplex.hpp"
#include "hom/io/msh.hpp"
#include "hom/mesh/mesh.hpp"
#include "hom/mesh/topology.hpp"

namespace hom::cad {

/// Meshing or classification failed (Gmsh failed, a node off the model).
class MeshingError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A ball where the mesh is made finer: element size `size` within `radius`
/// of `center`, growing linearly to the global size over another `radius`
/// (Gmsh's Ball field). hom curve --refine-invalid puts one around each
/// element that stayed invalid and meshes the model again.
struct LocalSize {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double radius = 0.0;
  double size = 0.0;
};

/// The element sizes of an earlier mesh of the model, at its vertices (see
/// size_map), to mesh it again with them in place of Gmsh's curvature sizing,
/// so that balls finer than size_min need not lower Gmsh's global floor for
/// the whole model (--refine-invalid's retries, and hom curve's --size-ball
/// below --size-min).
struct SizeMap {
  std::vector<Eigen::Vector3d> points;
  std::vector<double> sizes;  ///< at `points`, > 0
  bool empty() const { return points.empty(); }
};

struct CadMeshOptions {
  int dim = 3;                   ///< 3: tetrahedra of the solids; 2: triangles / quads of the faces
  bool quads = false;            ///< 2D: recombine into quadrilaterals (Mesh.RecombineAll)
  /// 2D triangles: split the ears (ears.hpp; quadrilateral ears are always
  /// split). mesh_cad sets it for surface meshes; a planar mesh's are split
  /// by the curving pipeline (hom/mesh/flat_corners.hpp). A volume mesh's
  /// boundary ears are always split, each with the tetrahedron on it.
  bool split_triangle_ears = false;
  /// Leave every ear as Gmsh made it (to compare with split_mesh_ears, which
  /// splits the ears of a mesh that comes without Gmsh's curve lines).
  bool keep_ears = false;
  double size = 0.0;             ///< Mesh.MeshSizeMax; 0: default_mesh_size(model)
  double size_min = 0.0;         ///< Mesh.MeshSizeMin
  int size_from_curvature = 0;   ///< Mesh.MeshSizeFromCurvature: elements per 2 pi radians; 0: off
  std::map<int, double> vertex_sizes;  ///< mesh size at model vertices (tag -> size)
  /// Balls meshed finer (the smallest size of the balls that hold a point
  /// wins). Gmsh's floor Mesh.MeshSizeMin is global: a ball's size below
  /// size_min lowers that floor to it everywhere.
  std::vector<LocalSize> local_sizes;
  /// Not empty: the size outside the balls is the earlier mesh's, a weighted
  /// mean of its sizes at the vertices near the point (a Gmsh size callback,
  /// continuous), never below size_min, and size_from_curvature is ignored
  /// (the earlier mesh has it), so the floor size_floor() matters only where
  /// the balls ask for less.
  SizeMap earlier_sizes;
  /// Mesh.Algorithm; 0: 6 (Frontal-Delaunay; 4.8.4's 8 crashes on surfaces
  /// with a pole), with the faces where it leaves slivers (angles below 3
  /// degrees) wider than twice the size meshed again with MeshAdapt (1)
  int algorithm_2d = 0;
  int algorithm_3d = 1;          ///< Mesh.Algorithm3D (1: Delaunay)
  int seed = 1;                  ///< Mesh.RandomSeed
  int threads = 1;               ///< General.NumThreads (1: deterministic)
  bool verbose = false;          ///< Gmsh's messages on the terminal
  /// > 0: meshing that takes longer (wall seconds) ends the process with a
  /// message and status 1 (GmshSessionOptions::time_limit_s); 0: no limit
  double time_limit_s = 0.0;
  double tolerance = 1e-8;       ///< classification tolerance, relative to the model's size
  /// Solids to keep (model tags), empty: all. The others are meshed too
  /// (Gmsh meshes the model whole) but left out of the result with their
  /// faces, edges and vertices that no kept solid has: a model whose solids
  /// touch without sharing faces (a body and the far field around it, each
  /// with its own copy of the interface) gives the mesh of one region. For a
  /// surface mesh (dim 2), the faces of these solids.
  std::vector<int> solids;
  /// Called with a line on what the mesher did beyond the options (faces
  /// meshed again with another algorithm); empty: silent.
  std::function<void(const std::string&)> progress;
};

/// The element size used when CadMeshOptions::size is 0: the model's
/// bounding-box diagonal / 20.
double default_mesh_size(const CadModel& cad);

/// The sizes of `mesh` (degree 1; any degree uses its vertices) at its
/// vertices: the mean length of the straight edges at each (a planar mesh's
/// points get z = 0). Meshed again from it, wing_fuselage.step's first mesh
/// (966 nodes) had 1029 nodes; from the harmonic mean, which weighs the short
/// edges across its thin wing, 1658 (gmsh 4.8 from Python, 2026-12-06).
/// Edges of length 0 (a surface's pole, where a patch's side collapses) are
/// left out, and so is a vertex with no other edge.
template <class MeshT>
SizeMap size_map(const MeshT& mesh) {
  const Topology<typename MeshT::family> topology(mesh);
  std::vector<double> sum(mesh.num_nodes(), 0.0);
  std::vector<int> count(mesh.num_nodes(), 0);
  for (const auto& [a, b] : topology.edges()) {
    const double length = (mesh.node(a) - mesh.node(b)).norm();
    if (!(length > 0)) continue;
    sum[a] += length, sum[b] += length;
    ++count[a], ++count[b];
  }
  SizeMap map;
  for (int v : topology.vertices()) {
    if (count[v] == 0) continue;
    Eigen::Vector3d x = Eigen::Vector3d::Zero();
    x.template head<MeshT::space_dim>() = mesh.node(v);
    map.points.push_back(x);
    map.sizes.push_back(sum[v] / count[v]);
  }
  return map;
}

/// Gmsh's global floor on the element size (Mesh.MeshSizeMin): size_min,
/// lowered to the smallest local size; 0 when size_min is 0 (no floor).
double size_floor(const CadMeshOptions& o);

/// True when the balls ask for less than size_min while curvature sizing is
/// on: Gmsh would then refine every curved place of the model to the balls'
/// size, so the caller meshes with earlier_sizes outside the balls instead.
inline bool balls_lower_curvature_floor(const CadMeshOptions& o) {
  return o.size_from_curvature > 0 && size_floor(o) < o.size_min;
}

/// Throws std::invalid_argument naming the first bad entry of the size
/// fields: a local size without a finite center, radius > 0 and size > 0,
/// a vertex size at a tag outside 1..num_vertices or not finite and > 0, or
/// earlier sizes with a point not finite or a size not finite and > 0.
/// cad_mesh_data checks them first; a caller may check them before meshing.
void check_size_fields(const CadModel& cad, const CadMeshOptions& o);

/// Meshes the model with Gmsh and returns the mesh as MSH data with the
/// model's entity tags (see above); nodes keep their parametric coordinates.
/// Throws MeshingError; std::invalid_argument for bad options.
io::MshData cad_mesh_data(const CadModel& cad, const CadMeshOptions& options = {});

/// The mesh of Family (Simplex<3>; Simplex<2> / Cube<2> with SpaceDim 3 for
/// a surface mesh, SpaceDim 2 for a planar model in z = 0), degree 1.
template <ElementFamily Family, NodeSet Nodes = WarpBlend, int SpaceDim = Family::dim>
Mesh<Family, Nodes, SpaceDim> mesh_cad(const CadModel& cad, CadMeshOptions options = {}) {
  options.dim = Family::dim;
  options.quads = !Family::is_simplex;
  options.split_triangle_ears = Family::is_simplex && Family::dim == 2 && SpaceDim == 3;
  if constexpr (Family::dim == 3) static_assert(Family::is_simplex, "hom::cad::mesh_cad: volume meshes are tetrahedral");
  return io::to_mesh<Family, Nodes, SpaceDim>(cad_mesh_data(cad, options));
}

/// Where a point lies on the model: the lowest-dimensional entity (vertex,
/// then edge, then face) within `tolerance` (absolute), with its parameters.
struct CadPointClass {
  EntityId entity;
  int num_params = 0;
  std::array<double, 2> params{};
  double distance = 0.0;
};

/// Classifies each column of `points` (3 x N); std::nullopt for a point
/// farther than `tolerance` from every face.
std::vector<std::optional<CadPointClass>> classify_points(const CadModel& cad, const Eigen::Matrix3Xd& points,
                                                          double tolerance);

/// Classifies a user-supplied linear mesh (its boundary nodes: those of the
/// topological boundary of a volume mesh, every node of a surface mesh) on
/// the model by projection: nodes within `tolerance` (absolute) of a vertex
/// become fixed on it, of an edge or face on_entity with their parameters;
/// boundary facets get the face (edge) they lie on; the mesh's entities
/// become the model's. Throws MeshingError naming the first boundary node
/// that is farther than `tolerance` from the model.
template <ElementFamily Family, NodeSet Nodes, int SpaceDim>
  requires(SpaceDim == 3)
void classify(Mesh<Family, Nodes, SpaceDim>& mesh, const CadModel& cad, double tolerance) {
  const int n = mesh.num_nodes();
  std::vector<bool> boundary(n, Family::dim == 2);
  std::vector<BoundaryFacet<Family>> facets;
  if constexpr (Family::dim == 3) {
    const Topology<Family> topo(mesh);
    for (const FacetRef& f : topo.boundary_facets()) {
      BoundaryFacet<Family> bf;
      bf.element = f.element;
      bf.local_facet = f.local;
      const auto lv = facet_vertices<Family>(f.local);
      for (int k = 0; k < facet_num_vertices<Family>; ++k) bf.vertices[k] = mesh.vertex(f.element, lv[k]);
      for (int id : mesh.facet_node_ids(bf)) boundary[id] = true;
      facets.push_back(bf);
    }
  }
  std::vector<int> ids;
  for (int i = 0; i < n; ++i)
    if (boundary[i]) ids.push_back(i);
  Eigen::Matrix3Xd x(3, ids.size());
  for (std::size_t k = 0; k < ids.size(); ++k) x.col(k) = mesh.node(ids[k]);
  const auto cls = classify_points(cad, x, tolerance);
  for (std::size_t k = 0; k < ids.size(); ++k) {
    if (!cls[k]) {
      const auto p = mesh.node(ids[k]);
      throw MeshingError(cad.name() + ": mesh node " + std::to_string(ids[k]) + " at (" + std::to_string(p[0]) + ", " +
                         std::to_string(p[1]) + ", " + std::to_string(p[2]) + ") is farther than " +
                         std::to_string(tolerance) + " from every face of the model");
    }
    NodeClass& c = mesh.node_class(ids[k]);
    c.entity = cls[k]->entity;
    c.kind = cls[k]->entity.dim == 0 ? NodeKind::fixed : NodeKind::on_entity;
    c.num_params = cls[k]->num_params;
    c.params = cls[k]->params;
  }
  // A facet lies on the face shared by all its vertices' entities (the
  // faces of a vertex or edge, or the face itself).
  auto faces_of = [&](EntityId e) {
    std::vector<int> f;
    if (e.dim == 2) f.push_back(e.tag);
    if (e.dim == 1) f = cad.edge_faces(e.tag);
    if (e.dim == 0)
      for (int ed = 1; ed <= cad.num_edges(); ++ed) {
        const auto v = cad.edge_vertices(ed);
        if (v[0] == e.tag || v[1] == e.tag)
          for (int t : cad.edge_faces(ed)) f.push_back(t);
      }
    std::sort(f.begin(), f.end());
    f.erase(std::unique(f.begin(), f.end()), f.end());
    return f;
  };
  auto common_face = [&](const auto& vertex_ids, const std::string& what) {
    std::vector<int> common;
    bool first = true;
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (int v : vertex_ids) {
      centroid += mesh.node(v);
      const auto f = faces_of(*mesh.node_class(v).entity);
      if (first) {
        common = f;
        first = false;
      } else {
        std::vector<int> both;
        std::set_intersection(common.begin(), common.end(), f.begin(), f.end(), std::back_inserter(both));
        common = both;
      }
    }
    if (common.empty()) throw MeshingError(cad.name() + ": " + what + " has vertices on no common face of the model");
    if (common.size() == 1) return common.front();
    centroid /= double(vertex_ids.size());
    int best = common.front();  // the face nearest to the centroid
    double best_d = std::numeric_limits<double>::infinity();
    for (int f : common) {
      const auto s = cad.surface(f);
      const double d = (s.evaluate(s.project(centroid)) - centroid).norm();
      if (d < best_d) {
        best_d = d;
        best = f;
      }
    }
    return best;
  };
  if constexpr (Family::dim == 3) {
    for (auto& bf : facets)
      bf.entity_tag = common_face(bf.vertices, "boundary facet of element " + std::to_string(bf.element));
    mesh.boundary_facets() = std::move(facets);
  } else {
    for (int e = 0; e < mesh.num_elements(); ++e) {
      std::array<int, Family::num_vertices> v{};
      for (int k = 0; k < Family::num_vertices; ++k) v[k] = mesh.vertex(e, k);
      mesh.element_entities()[e] = common_face(v, "element " + std::to_string(e));
    }
  }
  mesh.entities() = cad.entities();
}

}  // namespace hom::cad
