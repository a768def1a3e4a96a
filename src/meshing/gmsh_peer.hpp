#pragma once
/// @file gmsh_peer.hpp
/// Gmsh's high-order mesh optimizer as a peer of hom's (issue 5): the same
/// perturbed mesh goes through Gmsh's optimizer (Mesh.HighOrderOptimize of
/// Gmsh's library) and comes back as a hom Mesh, so that a harness can judge
/// both results with hom's own quality measure, side by side.
///
///   hom::meshing::GmshPeerOptions o;
///   o.time_limit_s = 600;
///   const auto r = hom::meshing::gmsh_high_order_optimize(perturbed, o);
///   if (r.finished) ... hom::mesh_quality(r.mesh, ...) ...
///   else std::puts(r.status.c_str());      // "timeout", "crashed (signal 11, ...)", "failed: ..."
///
/// Gmsh's optimizer can run for an hour (3182 s at p = 5 on the cube with a
/// cavity of table 4.1) or crash, so it runs in a child process, the helper
/// executable `gmsh_peer_run` built beside this library, under a wall-clock
/// limit; the caller's process never loads a Gmsh model and keeps no state
/// from the run. The exchange goes through files in a scratch directory:
///   in.msh    the input, MSH 4.1 binary as hom writes it (io/msh.hpp: nodes
///             at Gmsh's equispaced positions, elements in Gmsh's node order);
///   out.msh   the result, same tags, only the node coordinates differ;
///   info.txt  "version V" as soon as Gmsh is up, then "optimize_s T",
///             "note TEXT" (Gmsh's last error, if any) and "done";
///   log.txt   Gmsh's messages (unless `verbose`, which shows them).
///
/// Fixed nodes. hom's optimizer moves the NodeKind::free nodes only. Gmsh
/// 4.8's optimizer frees every node not on a model point: nodes on curves
/// and surfaces slide along them (along local tangent lines and planes for
/// the discrete entities a mesh file gives), and 4.8 has no option to fix them
/// (Mesh.HighOrderFixBoundaryNodes came later). So the child builds the
/// model through Gmsh's API with one discrete volume per element entity,
/// holding the free nodes, and one discrete point holding every other node:
/// Gmsh then keeps exactly hom's fixed set. The result is checked: same
/// number of nodes, every fixed node where it was (up to the round-off of
/// converting to equispaced nodes and back, `max_fixed_displacement`).
///
/// Modes (Mesh.HighOrderOptimize): 1 optimization (gmsh::model::mesh::
/// optimize("HighOrder")), 2 elastic analogy then optimization, 3 elastic
/// analogy only ("HighOrderElastic"), 4 fast curving ("HighOrderFastCurving").
/// Gmsh's options Mesh.HighOrderThresholdMin/Max, NumLayers, PassMax and
/// IterMax are set from GmshPeerOptions (their defaults are Gmsh's). Gmsh's
/// optimizer works on the scaled Jacobian: it optimizes patches around the
/// elements whose scaled Jacobian lies outside [threshold_min, threshold_max]
/// and leaves the others alone.

#include <string>

#include "hom/element/simplex.hpp"
#include "hom/mesh/mesh.hpp"

namespace hom::meshing {

struct GmshPeerOptions {
  int mode = 1;                ///< Mesh.HighOrderOptimize: 1, 2, 3 or 4 (see the file comment)
  double time_limit_s = 600;   ///< wall clock of the child process, model set-up included
  int threads = 1;             ///< General.NumThreads of the child (0: Gmsh's default)
  double threshold_min = 0.1;  ///< Mesh.HighOrderThresholdMin
  double threshold_max = 2.0;  ///< Mesh.HighOrderThresholdMax
  int num_layers = 6;          ///< Mesh.HighOrderNumLayers
  int pass_max = 25;           ///< Mesh.HighOrderPassMax
  int iter_max = 100;          ///< Mesh.HighOrderIterMax
  bool verbose = false;        ///< Gmsh's messages on this terminal instead of log.txt
  /// The helper executable; empty: $HOM_GMSH_PEER_RUN, else the one built
  /// with this library.
  std::string helper;
  /// Scratch directory (created if missing, kept); empty: a fresh directory
  /// under the system's temporary directory, removed afterwards unless
  /// keep_files.
  std::string work_dir;
  bool keep_files = false;
};

struct PeerResult {
  std::string tool = "gmsh";
  std::string version;      ///< Gmsh's General.Version, as the child reported it (empty if it never started)
  int mode = 1;
  bool finished = false;    ///< a result mesh came back and passed the checks
  /// "ok", "timeout", "crashed (signal N, NAME)", or "failed: why".
  std::string status;
  /// The optimizer call(s) when finished (the time to compare with hom's);
  /// otherwise the wall time until the child ended or was killed.
  double time_s = 0.0;
  double wall_s = 0.0;      ///< child start to end: model set-up, optimization, files
  double cpu_s = 0.0;       ///< the child's processor time, user + system (less than wall_s on a loaded machine)
  double peak_rss_mb = 0.0; ///< the child's peak resident memory (Gmsh's, beside hom's own)
  std::string note;         ///< Gmsh's last error message, if it reported one; after a timeout or crash, its last log line
  double max_fixed_displacement = 0.0;  ///< largest move of a non-free node (round-off)
  /// The result when finished: the input mesh (classification, entities,
  /// ideal, boundary facets) with Gmsh's node positions.
  Mesh<Simplex<3>> mesh;
};

/// Runs Gmsh's high-order optimizer on `perturbed` in a child process (see
/// the file comment). The mesh's node classification says what may move:
/// NodeKind::free nodes move, every other node stays. Never throws for what
/// happens in the child (the status says); throws std::invalid_argument for
/// bad options.
PeerResult gmsh_high_order_optimize(const Mesh<Simplex<3>>& perturbed, const GmshPeerOptions& options = {});

/// The same with the options of the harnesses' command lines.
inline PeerResult gmsh_high_order_optimize(const Mesh<Simplex<3>>& perturbed, int mode, double time_limit_s,
                                           int threads) {
  GmshPeerOptions o;
  o.mode = mode;
  o.time_limit_s = time_limit_s;
  o.threads = threads;
  return gmsh_high_order_optimize(perturbed, o);
}

}  // namespace hom::meshing
