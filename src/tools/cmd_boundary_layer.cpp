// hom boundary-layer IN.msh --walls TAGS --bl-first H [--bl-growth G] [--bl-layers N] [--p P] -o OUT.msh
//                   [--wall-geometry sphere:cx,cy,cz,r | circle:cx,cy,r | plane | none]
//                   [--extrusion F] [--threads N] [--max-iterations N] [--json FILE] [--vtu FILE] [-v]
//                   [--certify [--certify-depth N] [--certify-rounds N]]
//
// Inserts a curved high-order boundary layer into a linear simplex mesh
// (thesis section 6.3.3, include/hom/optimize/boundary_layer_pipeline.hpp):
// the wall facets are split, layers of stretched simplices are inserted
// (12-tetrahedron stacked and 7-tetrahedron transition templates), the
// linear mesh is smoothed against the per-element stretched ideal, elevated
// to degree P with the wall on its analytic geometry, and optimized against
// the smoothed linear mesh. Prints the statistics of every stage (table 6.4).
//
// --walls: comma-separated tags of the wall (surfaces in 3D, curves in 2D):
// a physical group tag of that dimension if the file has one, else an
// entity tag. --wall-geometry: the wall's exact shape (plane and none leave
// the wall as the facets make it).
//
// --certify ends the last stage with hom optimize --certify's stage: every
// element certified (Bernstein bounds of det D phi_P), folds between
// quadrature points repaired with the wall held (optimize/certified.hpp).
//
// When the smoothed linear mesh (stage c) is still tangled, the degree-P
// stages are not run (they cannot end valid): the output is that linear
// mesh and the exit status 3.
//
// Exit status: 0 the result is valid (and, with --certify, certified), 3
// some elements are inverted or not certified valid (outputs
// are written anyway), 1 unreadable input or I/O error, 2 bad options or a
// mesh that is not a linear simplex mesh. Outputs are written only at the end,
// each atomically.

#include <cstdio>
#include <set>
#include <string>
#include <type_traits>
#include <vector>

#include <boost/program_options.hpp>

#include "boundary_layer_report.hpp"
#include "certify_options.hpp"
#include "command.hpp"
#include "hom/geometry/circle.hpp"
#include "hom/geometry/sphere.hpp"
#include "hom/io/certification_report.hpp"
#include "hom/io/report.hpp"
#include "hom/optimize/boundary_layer_pipeline.hpp"
#include "hom/quality/mesh_quality.hpp"
#include "layer_options.hpp"
#include "mesh_io.hpp"
#include "options.hpp"

namespace po = boost::program_options;

namespace {

using hom::tools::UsageError;

struct BoundaryLayerCli {
  std::string in, out, walls, geometry = "none", json, vtu;
  double first = 0.0, growth = 2.0, extrusion = 0.1, total = 0.0;
  int layers = 7, p = 2, threads = 0, max_iterations = 200;
  bool verbose = false;
  hom::tools::CertifyCli certify;
};

/// Entity tags of the walls: physical groups of dimension Dim - 1 first.
template <class MeshT>
std::vector<int> wall_entities(const MeshT& mesh, const std::vector<int>& tags) {
  constexpr int D = MeshT::dim;
  std::set<int> out;
  for (int t : tags) {
    bool physical = false;
    for (const auto& g : mesh.physical_groups()) physical = physical || (g.dim == D - 1 && g.tag == t);
    if (physical) {
      for (const auto& en : mesh.entities())
        if (en.id.dim == D - 1)
          for (int pt : en.physical_tags)
            if (pt == t) out.insert(en.id.tag);
      continue;
    }
    bool entity = false;
    for (const auto& f : mesh.boundary_facets()) entity = entity || f.entity_tag == t;
    if (!entity)
      throw UsageError("boundary-layer: --walls " + std::to_string(t) + ": no physical group of dimension " +
                       std::to_string(D - 1) + " and no boundary entity has this tag");
    out.insert(t);
  }
  return {out.begin(), out.end()};
}

template <int Dim>
hom::GeometryModel<Dim> wall_geometry(const std::string& spec, const std::vector<int>& walls) {
  hom::GeometryModel<Dim> g;
  if (spec == "none" || spec == "plane") return g;
  const auto colon = spec.find(':');
  const std::string kind = spec.substr(0, colon);
  const auto v = colon == std::string::npos
                     ? std::vector<double>{}
                     : hom::tools::parse_number_list("boundary-layer", "--wall-geometry", spec.substr(colon + 1));
  if constexpr (Dim == 3) {
    if (kind != "sphere" || v.size() != 4)
      throw UsageError("boundary-layer: --wall-geometry for a tetrahedral mesh: sphere:cx,cy,cz,r, plane or none; got '" +
                       spec + "'");
    if (!(v[3] > 0.0)) throw UsageError("boundary-layer: --wall-geometry: the radius must be positive");
    for (int t : walls) g.add_surface(t, hom::Sphere(Eigen::Vector3d(v[0], v[1], v[2]), v[3]));
  } else {
    if (kind != "circle" || v.size() != 3)
      throw UsageError("boundary-layer: --wall-geometry for a triangular mesh: circle:cx,cy,r, plane or none; got '" +
                       spec + "'");
    if (!(v[2] > 0.0)) throw UsageError("boundary-layer: --wall-geometry: the radius must be positive");
    for (int t : walls) g.add_curve(t, hom::Circle<2>(Eigen::Vector2d(v[0], v[1]), v[2]));
  }
  return g;
}

template <class MeshT>
int insert(const MeshT& mesh, const BoundaryLayerCli& o) {
  constexpr int D = MeshT::dim;
  if (mesh.degree() != 1)
    throw UsageError("boundary-layer: " + o.in + " has degree " + std::to_string(mesh.degree()) +
                     "; the boundary layer is inserted into a linear mesh");
  const auto walls = wall_entities(mesh, hom::tools::parse_tag_list("boundary-layer", "--walls", o.walls));
  const auto geometry = wall_geometry<D>(o.geometry, walls);
  hom::BoundaryLayerPipelineOptions opt;
  opt.layer = {.first_height = o.first, .growth = o.growth, .layers = o.layers, .extrusion_fraction = o.extrusion};
  opt.p = o.p;
  for (auto* s : {&opt.linear_optimize, &opt.high_order_optimize}) {
    s->threads = o.threads;
    s->max_iterations = o.max_iterations;
    s->verbose = o.verbose;
  }
  o.certify.apply_to(opt.high_order_optimize);
  if (o.verbose) opt.progress = [](const std::string& stage) { std::fprintf(stderr, "stage %s done\n", stage.c_str()); };

  std::printf("%s: %s mesh, %d elements, %d nodes; walls:", o.in.c_str(), D == 3 ? "tetrahedral" : "triangular",
              mesh.num_elements(), mesh.num_nodes());
  for (int w : walls) std::printf(" %d", w);
  std::printf("\nlayers %d, first height %g, growth %g (total %g), extrusion %g, p = %d, wall geometry %s\n\n", o.layers,
              o.first, o.growth, opt.layer.total_height(), o.extrusion, o.p, o.geometry.c_str());
  std::fflush(stdout);
  const auto r = hom::boundary_layer_pipeline<D>(mesh, walls, geometry, opt);
  hom::tools::print_boundary_layer_stages(r.stages);
  std::printf("\nlargest aspect ratio of the ideal layer elements: %.4g\n", r.layer.max_aspect_ratio);
  if (r.stopped_after_smoothing)
    std::printf("INVALID: %s\n", hom::tools::smoothed_tangled_message(r).c_str());
  else
    std::printf("%s\n", r.valid ? "valid at every quadrature point" : "INVALID: some elements have det <= 0 at a quadrature point");
  if (r.certification) hom::io::print_certification(*r.certification, o.certify.depth);
  const bool certified = !o.certify.on || (r.certification && r.certification->certified());
  if (r.valid && !certified)
    std::printf("NOT CERTIFIED: %d of %d elements are not certified valid after the repair rounds\n",
                int(r.certification->uncertified.size()), r.mesh.num_elements());

  // An invalid result is written too (exit 3), as by `hom optimize`, to be
  // looked at: when stopped at (c), the tangled linear mesh.
  hom::io::write_msh(o.out, r.mesh, {});
  std::printf("wrote %s%s\n", o.out.c_str(), r.stopped_after_smoothing ? " (the tangled linear mesh of stage c, p = 1)" : "");
  if (!o.vtu.empty()) {
    hom::tools::write_boundary_layer_vtu(o.vtu, r);
    std::printf("wrote %s\n", o.vtu.c_str());
  }
  if (!o.json.empty()) {
    auto cases = hom::tools::boundary_layer_cases(o.in, r, opt.layer);
    if (r.certification) hom::io::add_certification(cases.back(), *r.certification, o.certify.depth);
    hom::io::write_report(o.json, "hom boundary-layer", HOM_VERSION, std::move(cases));
    std::printf("wrote %s\n", o.json.c_str());
  }
  return r.valid && certified ? 0 : 3;
}

void check_options(const BoundaryLayerCli& o) {
  if (o.in.empty()) throw UsageError("boundary-layer: need an input mesh (see 'hom boundary-layer --help')");
  if (o.out.empty()) throw UsageError("boundary-layer: need an output file: -o OUT.msh");
  if (!hom::tools::ends_with(o.in, ".msh")) throw UsageError("boundary-layer: can only read .msh files, not '" + o.in + "'");
  if (!hom::tools::ends_with(o.out, ".msh"))
    throw UsageError("boundary-layer: -o file name must end in .msh, got '" + o.out + "'");
  if (o.walls.empty()) throw UsageError("boundary-layer: need the wall: --walls TAGS");
  try {
    hom::BoundaryLayerOptions{.first_height = o.first, .growth = o.growth, .layers = o.layers, .extrusion_fraction = o.extrusion}
        .validate();
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("boundary-layer: ") + e.what());
  }
  if (o.p < 1 || o.p > 10) throw UsageError("boundary-layer: --p must be in 1..10, got " + std::to_string(o.p));
  if (o.threads < 0) throw UsageError("boundary-layer: --threads must be >= 0 (0: OpenMP's default)");
  if (o.max_iterations < 1) throw UsageError("boundary-layer: --max-iterations must be >= 1");
  o.certify.check("boundary-layer");
  if (!o.vtu.empty() && !hom::tools::ends_with(o.vtu, ".vtu"))
    throw UsageError("boundary-layer: --vtu file name must end in .vtu");
  if (o.vtu == o.out || (!o.json.empty() && (o.json == o.out || o.json == o.vtu)))
    throw UsageError("boundary-layer: -o, --vtu and --json must name different files");
}

int run(int argc, char** argv) {
  BoundaryLayerCli o;
  po::options_description opts(
      "hom boundary-layer IN.msh --walls TAGS --bl-first H -o OUT.msh [options]\n\n"
      "Insert a curved high-order boundary layer into a linear tetrahedral (or planar triangular)\n"
      "mesh (thesis section 6.3.3): split the wall, insert layers of stretched simplices, smooth\n"
      "the linear mesh against the stretched ideal, elevate to degree P with the wall on its\n"
      "geometry, and optimize. Prints every stage's quality statistics (table 6.4). When the\n"
      "smoothed linear mesh is still tangled, stops there and writes it (exit 3).\n"
      "Exit status: 0 the result is valid (with --certify: certified), 3 some elements are\n"
      "inverted or not certified (outputs are written anyway), 1 unreadable input, 2 bad options.\n\noptions");
  opts.add_options()("help,h", "show this help")                                                       //
      ("output,o", po::value(&o.out), "result (.msh, degree P)")                                       //
      ("walls", po::value(&o.walls), "wall tags, comma-separated: physical groups (else entities) of the boundary")  //
      ("bl-first", po::value(&o.first), "height of the first layer")                                   //
      ("bl-growth", po::value(&o.growth)->default_value(2.0), "ratio of consecutive layer heights (>= 1)")  //
      ("bl-layers", po::value(&o.layers)->default_value(7), "number of layers (the last is the transition)")  //
      ("bl-total", po::value(&o.total),
       "instead of --bl-layers: the total height; the fewest layers that reach it")  //
      ("extrusion", po::value(&o.extrusion)->default_value(0.1),
       "the inserted topology is extruded by this fraction of the total height")  //
      ("p", po::value(&o.p)->default_value(2), "polynomial degree of the result")  //
      ("wall-geometry", po::value(&o.geometry)->default_value("none"),
       "the wall's exact shape: sphere:cx,cy,cz,r | circle:cx,cy,r (2D) | plane | none")       //
      ("threads", po::value(&o.threads)->default_value(0), "threads (0: OpenMP's default)")    //
      ("max-iterations", po::value(&o.max_iterations)->default_value(200), "iteration limit per optimization")  //
      ("json", po::value(&o.json), "write every stage's statistics as JSON")                   //
      ("vtu", po::value(&o.vtu), "write the result colored by quality and layer level (ParaView)")  //
      ("verbose,v", po::bool_switch(&o.verbose), "one progress line per iteration (stderr)");
  o.certify.declare(opts,
                    "certify the sign of det everywhere in each element of the result (Bernstein bounds) and repair "
                    "folds between quadrature points");
  po::variables_map vm;
  if (!hom::tools::parse_options("boundary-layer", argc, argv, opts, {{"input", po::value(&o.in)}}, vm)) return 0;
  if (o.first > 0.0)
    o.layers = hom::tools::layers_from_options("boundary-layer", vm, o.first, o.growth, o.total, o.layers);
  check_options(o);
  const auto data = hom::io::read_msh_data(o.in);
  return hom::tools::with_mesh<hom::WarpBlend>(data, [&](auto& mesh) -> int {
    using M = std::decay_t<decltype(mesh)>;
    if constexpr (!M::family::is_simplex || M::space_dim != M::dim) {
      throw UsageError("boundary-layer: " + o.in + " holds " + std::string(M::family::name) +
                       (M::space_dim != M::dim ? " in 3D (a surface mesh)" : "") +
                       "; the boundary layer needs a tetrahedral or planar triangular mesh");
    } else {
      return insert(mesh, o);
    }
  });
}

const hom::tools::RegisterCommand reg{
    {"boundary-layer", "Insert a curved high-order boundary layer into a linear simplex mesh (section 6.3.3)", run}};

}  // namespace
