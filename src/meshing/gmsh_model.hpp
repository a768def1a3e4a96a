#pragma once
/// @file gmsh_model.hpp
/// Reading meshes and geometry out of Gmsh's library (compiled in
/// libhom_meshing; this header does not include gmsh.h, so code using it
/// needs only to link against hom_meshing).
///
///   hom::meshing::GmshSession session;          // gmsh::initialize / finalize
///   ... build and mesh a model with the Gmsh API ...
///   auto mesh = hom::meshing::linear_mesh_from_gmsh_model<hom::Simplex<3>>();
///   auto geometry = hom::meshing::analytic_geometry_from_gmsh_model();
///
/// The mesh goes through the same path as a file (io::to_mesh, msh.hpp), so
/// it gets the same checks, node classification (free / fixed / on_entity
/// with Gmsh's parametric coordinates), boundary facets classified on their
/// surfaces (curves in 2D), model entities with their bounding entities, and
/// physical groups.

#include <memory>
#include <string>

#include "hom/element/family.hpp"
#include "hom/geometry/geometry_model.hpp"
#include "hom/io/msh.hpp"
#include "hom/mesh/mesh.hpp"
#include "hom/nodes/warp_blend.hpp"

namespace hom::meshing {

struct GmshSessionOptions {
  bool verbose = false;  ///< Gmsh's own messages on the terminal (General.Terminal)
  int threads = 1;       ///< General.NumThreads; 1 keeps meshing deterministic
  std::string subject;   ///< what is meshed (a file name), for the message below
  /// > 0: a session open longer than this many seconds (wall time) ends the
  /// process with a message and status 1 (see GmshSession); 0: no limit.
  double time_limit_s = 0.0;
};

/// Initializes Gmsh (without reading the user's configuration files) for the
/// lifetime of the object; nested sessions share one initialization. Not
/// thread-safe: Gmsh's API is a global state.
///
/// Gmsh 4.8.4 meshes curves and surfaces inside OpenMP parallel loops (even
/// on one thread), and an error there ("Impossible to mesh periodic surface
/// 1", thrown as a std::string) cannot leave the loop: the runtime calls
/// std::terminate. While a session is open, std::terminate prints
/// "hom: <subject>: Gmsh failed: <its message>" on stderr and exits with
/// status 1 instead of aborting; nothing after it runs, so no output file
/// is begun.
///
/// Gmsh 4.8.4 also loops forever on some surfaces (an OpenCASCADE cone's
/// apex: refineMeshBDS / smooth_point_centroid never return), and a running
/// Gmsh call cannot be interrupted. With a time limit, a watchdog thread
/// prints "hom: <subject>: Gmsh did not finish meshing within N s" on stderr
/// and exits with status 1 when the session outlives it.
class GmshSession {
 public:
  explicit GmshSession(const GmshSessionOptions& options = {});
  ~GmshSession();
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;

 private:
  struct Watchdog;
  std::string previous_subject_;
  std::unique_ptr<Watchdog> watchdog_;
};

/// The current Gmsh model's mesh as MSH data: every entity (with its physical
/// groups and signed boundary), every node (with its entity and parametric
/// coordinates), every element of every dimension. Throws std::runtime_error
/// with Gmsh's last error if the API fails.
io::MshData gmsh_model_data(const std::string& name = "gmsh model");

/// The current Gmsh model's mesh as a hom Mesh of family Family (the model
/// must be meshed, with elements of Family's shape only in the top
/// dimension; lower-dimensional elements classify nodes and facets).
template <ElementFamily Family, NodeSet Nodes = WarpBlend>
Mesh<Family, Nodes> linear_mesh_from_gmsh_model(const std::string& name = "gmsh model") {
  return io::to_mesh<Family, Nodes>(gmsh_model_data(name));
}

/// Analytic geometry recognized from the current Gmsh model's entities: every
/// curve Gmsh reports as "Line" or "Circle" and every surface it reports as
/// "Plane" or "Sphere" gets the matching hom model (geometry/*.hpp), fitted
/// to points of its parameterization and kept only if samples of the entity
/// lie on it within `tolerance` times the entity's size. Other entities are
/// left out (their nodes keep their positions when curving).
GeometryModel<3> analytic_geometry_from_gmsh_model(double tolerance = 1e-9);

}  // namespace hom::meshing
