// hom curve [MODEL.step|.stp|.iges|.igs|.brep] [--mesh LINEAR.msh] [--p P (2)] [-o OUT.msh (curved.msh)]
//           [--size H] [--size-min H] [--size-curvature N] [--size-ball X,Y,Z,R,H]... [--vertex-size TAGS=H]...
//           [--solids TAGS] [--surface] [--quads]
//           [--measure shape|oddy] [--solver newton|matrix-free|gauss-seidel|auto]
//           [--pcont auto|on|off] [--threads N] [--vtu OUT.vtu] [--json FILE] [-v]
//           [--certify [--certify-depth N] [--certify-rounds N]] [--refine-invalid N] [--mesh-time-limit S]
//           [--bl-first H [--bl-growth G] [--bl-layers N] [--bl-walls TAGS] [--bl-extrusion F]]
//
// Chapter 6's a posteriori generation of a curved high-order mesh from CAD
// (src/curve/curve_mesh.hpp): a linear mesh of the model (Gmsh with the
// OpenCASCADE kernel, or the user's MSH file classified on the model by
// projection), elevated to degree P straight-sided (the ideal), its CAD
// edges' nodes at Gauss-Lobatto positions in arc length, its CAD faces'
// nodes blended in parameter space and optimized on the surface (chapter 5),
// the volume's interior nodes optimized (chapter 4). Without a model: the
// built-in cube with a spherical cavity (thesis section 4.3.1).
//
// What is meshed: tetrahedra when the model has solids (unless --surface);
// a planar model (all faces in one plane) gives a planar mesh in z = 0
// (moved there if needed); other models a surface mesh. Sizes: --size
// (the largest), --size-min, --size-curvature, and size fields as in thesis
// section 4.3.3: --size-ball (size H within distance R of a point, in the
// model's coordinates) and --vertex-size (size H at model vertices). Gmsh's
// floor (--size-min) is global, so a ball finer than it would, with
// --size-curvature, refine every curved place of the model: the model is
// then meshed first without the balls, and that mesh's sizes are kept
// outside them (CadMeshOptions::earlier_sizes). --quads asks for
// quadrilaterals (surface and planar meshes). --solids keeps the mesh of
// some solids (and, with --surface, of their faces): one region of a model
// whose solids touch without sharing faces, such as a body and the far
// field around it.
//
// The result is checked before anything is written: every element valid at
// every quadrature point (against its straight-sided ideal; surface elements
// oriented by their CAD face) and det D phi > 0 at every node (>= 0 on
// surfaces, whose normal vanishes at a pole), and every boundary node on its
// CAD entity at its parameters. An invalid result writes nothing. --certify
// adds certification (issue 8): the sign of det D phi_P bounded everywhere in
// each element (Bernstein coefficients), folds between quadrature points
// repaired by moving interior nodes (optimize/certified.hpp). The CAD faces
// (every face of a surface mesh, the boundary faces of a volume mesh) are
// certified element by element, against their nodes' interpolated surface
// normals, and their folds repaired by sliding face nodes on the
// surface (surface/certified_surface.hpp). An uncertified result is invalid.
//
// --bl-first adds a curved boundary layer of stretched tetrahedra on the wall
// faces (thesis section 6.3.3, cad_boundary_layer.hpp): the linear mesh gets
// the layer topology, is smoothed against the stretched ideal, elevated with
// its wall nodes on the CAD faces and optimized. --bl-walls names the wall's
// CAD faces (default: the faces of the solids' cavities, else every face off
// the model's bounding box: the body in a far-field domain). Volume meshes
// only; with --certify the layer mesh is certified and its folds between
// quadrature points repaired, the wall held. A smoothed linear mesh that is
// still tangled stops the pipeline there (exit 3).
//
// --refine-invalid N: when the result is invalid (or not certified), the
// model is meshed again, finer in a ball around each failing element (half
// its size, cad_mesher.hpp's LocalSize), and curved again, up to N times.
// Where the model itself is too coarse for its mesh (a fuselage's tail tip
// thinner than the elements there), this is what makes the result valid.
// Balls finer than --size-min with --size-curvature keep the first mesh's
// sizes elsewhere, as --size-ball does (refine_invalid.hpp's refine_around).
// With --certify, a try whose CAD faces are left uncertified skips its
// volume stage while tries remain (CurveOptions::skip_volume_if_faces_uncertified):
// the volume would not be certified either, and the next try refines there.
//
// Exit status: 0 valid mesh written; 3 the result is invalid (nothing
// written); 1 unreadable model or mesh, meshing failure, I/O error; 2 bad
// options.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include <boost/program_options.hpp>

#include "cad_boundary_layer.hpp"
#include "cad_command.hpp"
#include "certify_options.hpp"
#include "cad_mesher.hpp"
#include "cad_model.hpp"
#include "command.hpp"
#include "curve_mesh.hpp"
#include "curve_models.hpp"
#include "hom/optimize/solve.hpp"
#include "layer_options.hpp"
#include "mesh_ears.hpp"
#include "mesh_io.hpp"
#include "options.hpp"
#include "refine_invalid.hpp"

namespace po = boost::program_options;

namespace {

struct CurveCli {
  std::string model, mesh, out, vtu, json;
  int p = 0;
  bool p_given = false;  ///< --p on the command line (a curved --mesh keeps its own degree)
  double size = 0.0;
  double size_min = 0.0;
  double merge_small_edges = 0.0;
  double mesh_time_limit = 600.0;  ///< seconds Gmsh may take to mesh the model (0: no limit)
  int size_curvature = 0;
  std::string solids;  ///< --solids: model solid tags, comma-separated (empty: all)
  std::vector<std::string> size_balls;    ///< --size-ball X,Y,Z,R,H (repeatable)
  std::vector<std::string> vertex_sizes;  ///< --vertex-size TAGS=H (repeatable)
  bool surface = false;
  bool quads = false;
  std::string measure = "shape";
  std::string solver = "auto";
  std::string pcont = "auto";
  int threads = 0;
  double tolerance = 1e-6;
  int iterations_after_valid = -1;
  int refine_invalid = 0;  ///< tries after the first, each meshing the model finer around the failing elements
  bool verbose = false;
  hom::tools::CertifyCli certify;
  double bl_first = 0.0;  ///< > 0: insert a boundary layer
  double bl_growth = 2.0, bl_extrusion = 0.1, bl_total = 0.0;
  int bl_layers = 7;
  std::string bl_walls;
  bool bl_options_given = false;  ///< a --bl-* option other than --bl-first on the command line
};

/// Options of the default pipeline that the boundary-layer pipeline does not
/// take (its measure is the shape measure, its optimizer the default one).
void check_boundary_layer_options(const CurveCli& o) {
  using hom::tools::UsageError;
  try {
    hom::BoundaryLayerOptions{
        .first_height = o.bl_first, .growth = o.bl_growth, .layers = o.bl_layers, .extrusion_fraction = o.bl_extrusion}
        .validate();
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("curve: ") + e.what());
  }
  auto refuse = [](const std::string& what) {
    throw UsageError("curve: " + what + " does not apply with --bl-first (the boundary-layer pipeline)");
  };
  if (o.surface) refuse("--surface");
  if (o.quads) refuse("--quads");
  if (o.measure != "shape") refuse("--measure " + o.measure);
  if (o.solver != "auto") refuse("--solver " + o.solver);
  if (o.pcont != "auto") refuse("--pcont " + o.pcont);
  if (o.iterations_after_valid >= 0) refuse("--iterations-after-valid");
}

void check_options(const CurveCli& o) {
  using hom::tools::UsageError;
  using hom::tools::ends_with;
  if (o.p < 2) throw UsageError("curve: need a degree --p >= 2");
  if (o.p > 15) throw UsageError("curve: --p must be at most 15");
  if (o.out.empty()) throw UsageError("curve: need an output file: -o OUT.msh");
  if (!ends_with(o.out, ".msh")) throw UsageError("curve: -o file name must end in .msh, got '" + o.out + "'");
  if (!o.vtu.empty() && !ends_with(o.vtu, ".vtu")) throw UsageError("curve: --vtu file name must end in .vtu");
  if (!o.mesh.empty() && !ends_with(o.mesh, ".msh")) throw UsageError("curve: --mesh must be a .msh file, got '" + o.mesh + "'");
  if (o.vtu == o.out || (!o.json.empty() && (o.json == o.out || o.json == o.vtu)))
    throw UsageError("curve: -o, --vtu and --json must name different files");
  if (o.measure != "shape" && o.measure != "oddy")
    throw UsageError("curve: --measure must be shape or oddy, got '" + o.measure + "'");
  if (o.solver != "auto") {
    try {
      hom::parse_solver_kind(o.solver);
    } catch (const std::invalid_argument&) {
      throw UsageError("curve: --solver must be newton, matrix-free, gauss-seidel or auto, got '" + o.solver + "'");
    }
  }
  if (o.pcont != "auto" && o.pcont != "on" && o.pcont != "off")
    throw UsageError("curve: --pcont must be auto, on or off, got '" + o.pcont + "'");
  if (o.size < 0) throw UsageError("curve: --size must be positive");
  if (o.size_min < 0) throw UsageError("curve: --size-min must be >= 0");
  if (!(o.mesh_time_limit >= 0) || !std::isfinite(o.mesh_time_limit))
    throw UsageError("curve: --mesh-time-limit must be a number of seconds >= 0");
  if (o.size_min > 0 && o.size > 0 && o.size_min > o.size)
    throw UsageError("curve: --size-min must not exceed --size");
  if (o.size_curvature < 0) throw UsageError("curve: --size-curvature must be >= 0");
  if (o.threads < 0) throw UsageError("curve: --threads must be >= 0 (0: OpenMP's default)");
  if (!(o.tolerance > 0)) throw UsageError("curve: --tolerance must be positive");
  if (!(o.merge_small_edges >= 0)) throw UsageError("curve: --merge-small-edges must be >= 0 (0: off)");
  if (o.merge_small_edges > 0 && o.model.empty())
    throw UsageError("curve: --merge-small-edges needs a MODEL file (the built-in model has no small edges)");
  o.certify.check("curve");
  if (o.mesh.empty() == false && (o.size > 0 || o.size_min > 0 || o.size_curvature > 0 || !o.solids.empty() ||
                                  !o.size_balls.empty() || !o.vertex_sizes.empty()))
    throw UsageError("curve: --size, --size-min, --size-curvature, --size-ball, --vertex-size and --solids apply to "
                     "the built-in mesher, not to --mesh");
  if (o.refine_invalid < 0) throw UsageError("curve: --refine-invalid must be >= 0 (0: off)");
  if (o.refine_invalid > 0 && !o.mesh.empty())
    throw UsageError("curve: --refine-invalid meshes the model again; it does not apply to a --mesh");
  if (o.refine_invalid > 0 && o.bl_first != 0.0)
    throw UsageError("curve: --refine-invalid does not apply with --bl-first (the boundary-layer pipeline)");
  if (o.bl_first != 0.0) check_boundary_layer_options(o);
  else if (o.bl_options_given) throw UsageError("curve: the --bl-* options need --bl-first H (the first layer's height)");
}

/// The solids of --solids, checked against the model.
std::vector<int> solid_tags(const hom::cad::CadModel& cad, const std::string& list) {
  auto tags = hom::tools::parse_tag_list("curve", "--solids", list);
  for (int s : tags)
    if (s < 1 || s > cad.num_solids())
      throw hom::tools::UsageError("curve: --solids " + std::to_string(s) + ": " + cad.name() +
                                   (cad.num_solids() == 0 ? std::string(" has no solids")
                                                          : " has solids 1.." + std::to_string(cad.num_solids())));
  return tags;
}

/// --size-ball X,Y,Z,R,H: elements of size H within distance R of (X, Y, Z),
/// the size field of thesis section 4.3.3 (0.1 in a sphere, 2 elsewhere).
hom::cad::LocalSize size_ball(const std::string& text) {
  const auto v = hom::tools::parse_number_list("curve", "--size-ball", text);
  const bool finite = std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
  if (v.size() != 5 || !finite || !(v[3] > 0) || !(v[4] > 0))
    throw hom::tools::UsageError("curve: --size-ball " + text +
                                 ": expected X,Y,Z,R,H, five numbers with radius R > 0 and size H > 0");
  return {.center = Eigen::Vector3d(v[0], v[1], v[2]), .radius = v[3], .size = v[4]};
}

/// --vertex-size TAGS=H: size H at these model vertices (the tags are checked
/// against the model with the other size fields); a later option wins for a
/// vertex named twice.
void add_vertex_sizes(const std::string& text, double size_min, std::map<int, double>& sizes) {
  using hom::tools::UsageError;
  const auto eq = text.find('=');
  if (eq == std::string::npos)
    throw UsageError("curve: --vertex-size " + text +
                     ": expected TAGS=H, model vertex tags and a size, e.g. 3,7=0.05");
  const auto tags = hom::tools::parse_tag_list("curve", "--vertex-size", text.substr(0, eq));
  const auto h = hom::tools::parse_number_list("curve", "--vertex-size", text.substr(eq + 1));
  if (h.size() != 1 || !std::isfinite(h[0]) || !(h[0] > 0))
    throw UsageError("curve: --vertex-size " + text + ": the size after '=' must be one number > 0");
  // Gmsh clamps every size to Mesh.MeshSizeMin: a smaller one would be ignored without a word.
  if (h[0] < size_min)
    throw UsageError("curve: --vertex-size " + text + ": the size is below --size-min, which Gmsh would keep");
  for (int v : tags) sizes[v] = h[0];
}

/// The boundary layer's settings; the walls checked against the model later.
hom::tools::CadBoundaryLayerOptions boundary_layer_options(const CurveCli& o) {
  hom::tools::CadBoundaryLayerOptions b;
  b.layer = {.first_height = o.bl_first, .growth = o.bl_growth, .layers = o.bl_layers, .extrusion_fraction = o.bl_extrusion};
  if (!o.bl_walls.empty()) b.walls = hom::tools::parse_tag_list("curve", "--bl-walls", o.bl_walls);
  return b;
}

/// The shared pipeline's settings from the command line.
hom::tools::CadCommandOptions cad_command_options(const CurveCli& o) {
  auto c = hom::tools::shared_cad_command_options("curve", o);
  c.curve.p = o.p;
  c.curve.pcont = o.pcont == "on"    ? hom::cad::CurveOptions::Continuation::on
                  : o.pcont == "off" ? hom::cad::CurveOptions::Continuation::off
                                     : hom::cad::CurveOptions::Continuation::automatic;
  c.curve.iterations_after_valid = o.iterations_after_valid;
  return c;
}

/// The linear mesh of a planar (S = 2) or surface (S = 3) model.
template <class Family, int S>
auto faces_of(const hom::cad::CadModel& model, const hom::cad::CadMeshOptions& m) {
  return hom::cad::mesh_cad<Family, hom::WarpBlend, S>(model, m);
}

/// Says what the next try of --refine-invalid changes: `floor` is the size
/// floor of the try that failed (0: none), `kept_sizes` whether the next
/// keeps the first mesh's sizes outside the balls (refine_around).
void print_refinement(const std::vector<hom::cad::LocalSize>& balls, double floor, bool kept_sizes, int attempt,
                      int attempts) {
  double smallest = balls.front().size, largest = smallest;
  for (const auto& b : balls) {
    smallest = std::min(smallest, b.size);
    largest = std::max(largest, b.size);
  }
  std::printf("\ntry %d of %d: the model meshed again, finer around the %d failing elements (size %.3g to %.3g there)",
              attempt, attempts, int(balls.size()), smallest, largest);
  if (floor > smallest) std::printf("; the size floor (--size-min) lowered from %.3g to %.3g", floor, smallest);
  if (floor > smallest && kept_sizes) std::printf(" in the balls, elsewhere the first mesh's sizes");
  std::printf("\n");
  std::fflush(stdout);
}

/// A linear --mesh's ears (src/cad/mesh_ears.hpp), split like those of hom's
/// own meshes: once curved, their corner on the CAD curve has det D phi = 0.
template <class MeshT>
void split_ears_of_user_mesh(MeshT& mesh, const hom::cad::CadModel& cad, double tolerance) {
  const int ears = hom::cad::split_mesh_ears(mesh, cad);
  if (ears == 0) return;
  hom::tools::classify_user_mesh(mesh, cad, tolerance);  // the new nodes, on the ears' faces
  std::printf("linear mesh: %d ears split (a boundary %s whose two edges at a corner lie on one CAD curve: "
              "flat there once curved, whatever the free nodes do); %d elements, %d nodes\n",
              ears, MeshT::family::is_simplex ? "triangle" : "quadrilateral", mesh.num_elements(), mesh.num_nodes());
}

int run(int argc, char** argv) {
  CurveCli o;
  po::options_description opts(
      "hom curve [MODEL.step|.iges|.brep] [--mesh LINEAR.msh] [--p P] [-o OUT.msh] [options]\n"
      "hom curve MODEL --mesh CURVED.msh -o OUT.msh [options]   (optimize a curved mesh on the model)\n\n"
      "Generate a curved high-order mesh from CAD (thesis chapter 6): a linear mesh of the model\n"
      "(Gmsh, or --mesh), elevated to degree P, boundary nodes put on the CAD (edges at\n"
      "Gauss-Lobatto positions in arc length, faces blended in parameter space and optimized on\n"
      "the surface, chapter 5), the volume optimized (chapter 4). Without MODEL: the built-in cube\n"
      "with a spherical cavity. Solids give tetrahedra, planar models a planar mesh in z = 0,\n"
      "other models a surface mesh. The result is checked (all elements valid, boundary nodes on\n"
      "the CAD) before it is written; an invalid result writes nothing. A curved --mesh (degree\n"
      "> 1, e.g. written by hom curve) is only optimized: face nodes slide on their CAD surfaces\n"
      "(chapter 5), interior nodes move (chapter 4), CAD-edge nodes stay.\n"
      "Exit status: 0 valid mesh written, 3 invalid result (nothing written), 1 unreadable\n"
      "input or meshing failure, 2 bad options.\n\noptions");
  opts.add_options()("help,h", "show this help")                                                     //
      ("p", po::value(&o.p)->default_value(2), "polynomial degree (>= 2)")                                             //
      ("output,o", po::value(&o.out)->default_value("curved.msh"), "curved mesh (.msh, MSH 4.1)")                                 //
      ("mesh", po::value(&o.mesh),
       "linear mesh to curve instead of meshing the model, or curved mesh to optimize on it (.msh)")       //
      ("size", po::value(&o.size)->default_value(0.0), "element size (0: model size / 20)")          //
      ("size-min", po::value(&o.size_min)->default_value(0.0),
       "smallest element size, a floor for --size-curvature (0: none)")  //
      ("size-curvature", po::value(&o.size_curvature)->default_value(0),
       "elements per 2 pi radians of curvature (0: off)")                                            //
      ("merge-small-edges", po::value(&o.merge_small_edges)->default_value(0.0),
       "heal the model: drop CAD edges shorter than this, joining their neighbours (0: off)")  //
      ("mesh-time-limit", po::value(&o.mesh_time_limit)->default_value(600.0),
       "seconds Gmsh may take to mesh the model, then exit 1 with a message (Gmsh 4.8 loops forever on some "
       "surfaces, a cone's apex for one; 0: no limit)")  //
      ("size-ball", po::value(&o.size_balls)->composing(),
       "X,Y,Z,R,H: elements of size H within distance R of the point (X, Y, Z), growing to --size outside "
       "(repeatable)")  //
      ("vertex-size", po::value(&o.vertex_sizes)->composing(),
       "TAGS=H: elements of size H at these model vertices (comma-separated tags; repeatable)")  //
      ("solids", po::value(&o.solids),
       "mesh only these solids (model tags, comma-separated; default all): one region of a model whose "
       "solids touch without sharing faces")  //
      ("surface", po::bool_switch(&o.surface), "surface mesh of a model with solids")               //
      ("quads", po::bool_switch(&o.quads), "quadrilaterals (surface and planar meshes)")            //
      ("measure", po::value(&o.measure)->default_value("shape"), "distortion measure: shape | oddy")  //
      ("solver", po::value(&o.solver)->default_value("auto"),
       "volume / planar solver: newton | matrix-free | gauss-seidel | auto")                          //
      ("pcont", po::value(&o.pcont)->default_value("auto"),
       "p-continuation of the volume stage: auto (when the initial mesh is tangled) | on | off")    //
      ("threads", po::value(&o.threads)->default_value(0), "threads (0: OpenMP's default)")         //
      ("refine-invalid", po::value(&o.refine_invalid)->default_value(0),
       "if the result is invalid or uncertified, mesh the model again finer around the failing elements and curve "
       "again, up to N times (0: off)")  //
      ("iterations-after-valid", po::value(&o.iterations_after_valid)->default_value(-1),
       "volume stage: stop once valid this many iterations (-1: optimize to convergence)")         //
      ("tolerance", po::value(&o.tolerance)->default_value(1e-6),
       "--mesh: classification tolerance, relative to the model's size")                             //
      ("bl-first", po::value(&o.bl_first)->default_value(0.0),
       "insert a boundary layer: height of its first layer (0: none)")  //
      ("bl-growth", po::value(&o.bl_growth)->default_value(2.0), "boundary layer: ratio of consecutive heights (>= 1)")  //
      ("bl-layers", po::value(&o.bl_layers)->default_value(7), "boundary layer: number of layers")  //
      ("bl-total", po::value(&o.bl_total),
       "boundary layer, instead of --bl-layers: the total height; the fewest layers that reach it")  //
      ("bl-walls", po::value(&o.bl_walls),
       "boundary layer: the wall's CAD face tags, comma-separated (default: the cavities' faces, else the faces "
       "off the bounding box)")  //
      ("bl-extrusion", po::value(&o.bl_extrusion)->default_value(0.1),
       "boundary layer: the inserted topology is extruded by this fraction of the total height")  //
      ("vtu", po::value(&o.vtu),
       "write the curved mesh colored by quality (ParaView); an invalid result too, its failing cells marked")  //
      ("json", po::value(&o.json), "write the statistics of every stage as JSON")                    //
      ("verbose,v", po::bool_switch(&o.verbose), "one progress line per optimizer iteration (stderr)");
  o.certify.declare(opts,
                    "certify the sign of det everywhere in each element (Bernstein bounds), repair folds between "
                    "quadrature points by moving interior nodes; an uncertified result is not written");
  po::variables_map vm;
  if (!hom::tools::parse_options("curve", argc, argv, opts, {{"model", po::value(&o.model)}}, vm)) return 0;
  o.p_given = vm.count("p") && !vm["p"].defaulted();
  for (const char* b : {"bl-growth", "bl-layers", "bl-total", "bl-walls", "bl-extrusion"})
    o.bl_options_given = o.bl_options_given || (vm.count(b) && !vm[b].defaulted());
  if (o.bl_first > 0.0)
    o.bl_layers = hom::tools::layers_from_options("curve", vm, o.bl_first, o.bl_growth, o.bl_total, o.bl_layers);
  check_options(o);

  // (read_cad's CadError names the file)
  hom::cad::CadModel cad = o.model.empty() ? hom::cad::cube_with_cavity_model()
                                           : hom::cad::read_cad(o.model, {.merge_small_edges = o.merge_small_edges});
  std::printf("%s\n", cad.summary().c_str());
  for (const auto& h : cad.healing()) std::printf("  healed: %s\n", h.c_str());
  hom::cad::CadMeshOptions mo;
  mo.size = o.size;
  mo.size_min = o.size_min;
  mo.size_from_curvature = o.size_curvature;
  mo.threads = 1;
  mo.time_limit_s = o.mesh_time_limit;
  mo.progress = [](const std::string& line) { std::printf("%s\n", line.c_str()); };
  if (!o.solids.empty()) mo.solids = solid_tags(cad, o.solids);
  for (const auto& b : o.size_balls) mo.local_sizes.push_back(size_ball(b));
  if (o.model.empty() && o.size == 0.0) {
    // The built-in model: graded towards the cavity as in test_cad (about
    // 1400 tetrahedra; table 4.1's mesh is of this kind).
    mo.size = 1.62;
    for (int v = 1; v <= cad.num_vertices(); ++v)
      mo.vertex_sizes[v] = (cad.vertex(v) - Eigen::Vector3d::Constant(2.5)).norm() < 1.0 ? 0.2 : 1.62;
  }
  for (const auto& v : o.vertex_sizes) add_vertex_sizes(v, o.size_min, mo.vertex_sizes);
  try {
    hom::cad::check_size_fields(cad, mo);  // the balls are checked as read: only a tag can be wrong here
  } catch (const std::invalid_argument& e) {
    throw hom::tools::UsageError(std::string("curve: --vertex-size: ") + e.what());
  }
  if (mo.size == 0.0 && o.size_min > hom::cad::default_mesh_size(cad))
    throw hom::tools::UsageError("curve: --size-min " + std::to_string(o.size_min) +
                                 " exceeds the default size (model size / 20 = " +
                                 std::to_string(hom::cad::default_mesh_size(cad)) + ")");

  const hom::tools::CadCommandOptions co = cad_command_options(o);
  auto t0 = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  if (!o.mesh.empty()) {
    const auto data = hom::io::read_msh_data(o.mesh);
    return hom::tools::with_mesh<hom::WarpBlend>(data, [&](auto& mesh) -> int {
      using M = std::decay_t<decltype(mesh)>;
      using F = typename M::family;
      if constexpr (!F::is_simplex && F::dim == 3) {
        throw hom::tools::UsageError("curve: " + o.mesh + " is a hexahedral mesh; hom curve handles tetrahedra, and "
                                     "triangles or quadrilaterals on surfaces or in the plane");
      } else {
        if (mesh.degree() > 1 && o.p_given && o.p != mesh.degree())
          throw hom::tools::UsageError("curve: " + o.mesh + " is already curved (degree " +
                                       std::to_string(mesh.degree()) + "); --p " + std::to_string(o.p) +
                                       " cannot change it (leave --p out to optimize it on the model)");
        if (o.bl_first > 0.0 && (M::dim != 3 || mesh.degree() > 1))
          throw hom::tools::UsageError("curve: --bl-first needs a linear tetrahedral --mesh; " + o.mesh + " holds " +
                                       std::string(F::name) + " of degree " + std::to_string(mesh.degree()));
        hom::tools::classify_user_mesh(mesh, cad, o.tolerance * cad.size());
        split_ears_of_user_mesh(mesh, cad, o.tolerance * cad.size());
        if constexpr (M::dim == 3)
          if (o.bl_first > 0.0) return hom::tools::boundary_layer_and_write(cad, mesh, boundary_layer_options(o), co);
        return hom::tools::curve_and_write(cad, mesh, co, elapsed());
      }
    });
  }
  // The options `m` for meshing `model` with mesh_model(model, options):
  // with --size-ball finer than --size-min and --size-curvature, the model is
  // meshed first without the balls and its sizes kept outside them, so that
  // the balls do not lower Gmsh's floor everywhere (refine_around).
  auto with_balls = [&](const hom::cad::CadModel& model, auto mesh_model) {
    hom::cad::CadMeshOptions m = mo;
    if (!hom::cad::balls_lower_curvature_floor(m)) return m;
    std::vector<hom::cad::LocalSize> balls;
    balls.swap(m.local_sizes);
    hom::cad::refine_around(m, balls, mesh_model(model, m));
    std::printf("--size-ball finer than --size-min: the model meshed first without the balls, its sizes kept "
                "outside them\n");
    return m;
  };
  // Meshes `model` and curves the mesh; with --refine-invalid an invalid
  // result is tried again, the model meshed finer around its failing
  // elements (the balls of earlier tries kept). A try whose meshing fails
  // ends the tries with the last curved one's result (its report and VTU
  // are written; no mesh).
  auto mesh_and_curve = [&](const hom::cad::CadModel& model, auto mesh_model) -> int {
    hom::cad::CadMeshOptions m = with_balls(model, mesh_model);
    auto linear = mesh_model(model, m);
    int status = 0;
    auto curve = [&](const auto& mesh, bool last) {
      hom::tools::CadCommandOptions this_try = co;
      this_try.curve.skip_volume_if_faces_uncertified = !last;
      std::vector<hom::cad::LocalSize> balls;
      status = hom::tools::curve_and_write(model, mesh, this_try, elapsed(), last ? nullptr : &balls);
      return balls;
    };
    auto remesh = [&](const hom::cad::Refinement& r) -> std::optional<decltype(linear)> {
      print_refinement(r.balls, r.floor_before, r.kept_sizes, r.next_try, o.refine_invalid + 1);
      t0 = std::chrono::steady_clock::now();
      try {
        return mesh_model(model, r.options);
      } catch (const hom::cad::MeshingError& e) {
        std::fprintf(stderr, "hom: curve: try %d: %s; the result stands at try %d's (invalid, no mesh written)\n",
                     r.next_try, e.what(), r.next_try - 1);
        return std::nullopt;
      }
    };
    hom::cad::curve_refining_invalid(m, linear, o.refine_invalid, curve, remesh);
    return status;
  };
  if (cad.num_solids() > 0 && !o.surface) {
    if (o.quads) throw hom::tools::UsageError("curve: volume meshes are tetrahedral; --quads needs --surface");
    auto tetrahedra = [](const hom::cad::CadModel& model, const hom::cad::CadMeshOptions& m) {
      return hom::cad::mesh_cad<hom::Simplex<3>>(model, m);
    };
    if (o.bl_first > 0.0)
      return hom::tools::boundary_layer_and_write(cad, tetrahedra(cad, with_balls(cad, tetrahedra)),
                                                  boundary_layer_options(o), co);
    return mesh_and_curve(cad, tetrahedra);
  }
  if (o.bl_first > 0.0)
    throw hom::tools::UsageError("curve: --bl-first needs a model with solids (a tetrahedral mesh); " + cad.name() +
                                 " has none (for a planar mesh use hom boundary-layer)");
  if (auto placed = hom::cad::place_in_xy_plane(cad)) {
    if (placed->moved) {
      std::printf("planar model: moved rigidly into the plane z = 0\n");
      for (auto& b : mo.local_sizes) b.center = placed->rotation * b.center + placed->translation;  // --size-ball
    }
    if (o.quads) return mesh_and_curve(placed->model, faces_of<hom::Cube<2>, 2>);
    return mesh_and_curve(placed->model, faces_of<hom::Simplex<2>, 2>);
  }
  if (o.quads) return mesh_and_curve(cad, faces_of<hom::Cube<2>, 3>);
  return mesh_and_curve(cad, faces_of<hom::Simplex<2>, 3>);
}

const hom::tools::RegisterCommand reg{{"curve", "Generate a curved high-order mesh from CAD (chapter 6)", run}};

}  // namespace
