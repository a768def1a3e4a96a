// hom info MESH | MODEL.step|.iges|.brep [--vertices]
//
// Prints what a Gmsh mesh file holds: format, element types and counts, the
// mesh hom reads from it (family, order, nodes, node classification,
// topology), entities, physical groups and bounding box. For a CAD file
// (STEP, IGES, BREP by extension; src/cad): the healed model's solids,
// shells, faces, edges and vertices, surface and curve kinds, healing,
// validity and bounding box; with --vertices, each model vertex's tag and
// position (hom curve --vertex-size takes those tags).

#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>
#include <string>

#include <boost/program_options.hpp>

#ifdef HOM_HAVE_CAD
#include "cad_model.hpp"
#endif
#include "command.hpp"
#include "hom/mesh/topology.hpp"
#include "mesh_io.hpp"
#include "options.hpp"

namespace po = boost::program_options;

namespace {

std::string type_name(int type) {
  const auto info = hom::io::gmsh_element_info(type);
  if (!info) return "type " + std::to_string(type);
  if (info->shape == hom::io::GmshShape::point) return "point";
  return std::string(hom::io::shape_name(info->shape)) + " order " + std::to_string(info->order);
}

#ifdef HOM_HAVE_CAD
bool is_cad_file(const std::string& path) {
  try {
    hom::cad::cad_format(path);
    return true;
  } catch (const hom::cad::CadError&) {
    return false;
  }
}

/// The model's summary; with `vertices`, each model vertex's tag and position
/// (the tags `hom curve --vertex-size` takes).
int describe_cad(const std::string& path, bool vertices) {
  const auto m = hom::cad::read_cad(path);
  const auto box = m.bounding_box();
  auto kinds = [](const std::map<std::string, int>& k) {
    std::string s;
    for (const auto& [name, n] : k) s += (s.empty() ? "" : ", ") + std::to_string(n) + " " + name;
    return s.empty() ? std::string("none") : s;
  };
  std::ostringstream o;
  o << m.summary() << "\n";
  o << "format:          " << (hom::cad::cad_format(path) == hom::cad::CadFormat::step   ? "STEP"
                               : hom::cad::cad_format(path) == hom::cad::CadFormat::iges ? "IGES"
                                                                                          : "BREP")
    << " (OpenCASCADE)\n";
  o << "solids:          " << m.num_solids() << "\n";
  o << "shells:          " << m.num_shells() << "\n";
  o << "faces:           " << m.num_faces() << " (" << kinds(m.surface_types()) << ")\n";
  o << "edges:           " << m.num_edges() << " (" << kinds(m.curve_types()) << ")\n";
  o << "vertices:        " << m.num_vertices() << "\n";
  o << "bounding box:    [" << box[0][0] << ", " << box[0][1] << ", " << box[0][2] << "] - [" << box[1][0] << ", "
    << box[1][1] << ", " << box[1][2] << "]\n";
  if (m.num_solids() > 0) o << "volume:          " << m.volume() << "\n";
  o << "area:            " << m.area() << "\n";
  o << "valid:           " << (m.valid() ? "yes" : "no") << " (BRepCheck_Analyzer)\n";
  o << "healing:         " << (m.healing().empty() ? std::string("none needed") : m.healing().front()) << "\n";
  for (std::size_t i = 1; i < m.healing().size(); ++i) o << "                 " << m.healing()[i] << "\n";
  if (vertices)
    for (int v = 1; v <= m.num_vertices(); ++v)
      o << "vertex " << v << ": " << m.vertex(v)[0] << " " << m.vertex(v)[1] << " " << m.vertex(v)[2] << "\n";
  std::cout << o.str();
  return 0;
}
#endif

int run(int argc, char** argv) {
  po::options_description opts(
      "hom info MESH | MODEL.step|.iges|.brep [--vertices]\n\nDescribe a Gmsh .msh file or a CAD model.\n\noptions");
  bool vertices = false;
  opts.add_options()("help,h", "show this help")  //
      ("vertices", po::bool_switch(&vertices),
       "a CAD model: list its vertices, tag and position (the tags of hom curve --vertex-size)");
  po::variables_map vm;
  if (!hom::tools::parse_options("info", argc, argv, opts, {{"mesh", po::value<std::string>()}}, vm)) return 0;
  if (!vm.count("mesh")) throw hom::tools::UsageError("info: need a mesh file (see 'hom info --help')");
  const std::string path = vm["mesh"].as<std::string>();
#ifdef HOM_HAVE_CAD
  if (is_cad_file(path)) return describe_cad(path, vertices);
#endif
  if (vertices)
    throw hom::tools::UsageError("info: --vertices lists the vertices of a CAD model (.step, .iges, .brep), not of " +
                                 path);
  const auto data = hom::io::read_msh_data(path);
  const auto s = hom::io::summarize(data);

  std::ostringstream o;
  o << "file:            " << path << "\n";
  o << "format:          MSH " << data.version_major << "." << data.version_minor << (data.binary ? " binary" : " ASCII")
    << "\n";
  o << "file nodes:      " << data.nodes.size() << "\n";
  o << "file elements:   " << data.elements.size() << "\n";
  for (const auto& [type, n] : s.type_counts) o << "  " << std::left << std::setw(24) << type_name(type) << n << "\n";
  o << "bounding box:    [" << s.lo[0] << ", " << s.lo[1] << ", " << s.lo[2] << "] - [" << s.hi[0] << ", " << s.hi[1]
    << ", " << s.hi[2] << "]\n";
  std::map<int, int> per_dim;
  for (const auto& en : data.entities) ++per_dim[en.id.dim];
  o << "entities:        " << per_dim[0] << " points, " << per_dim[1] << " curves, " << per_dim[2] << " surfaces, "
    << per_dim[3] << " volumes\n";
  if (!data.physical_names.empty()) {
    o << "physical groups:\n";
    for (const auto& g : data.physical_names) o << "  " << g.dim << "D " << g.tag << " \"" << g.name << "\"\n";
  }
  std::cout << o.str();

  if (s.top_shapes.size() > 1) {
    // Describing such a file is fine; using it is not (convert, quality, ...).
    std::cout << "mesh:            mixes";
    for (auto shape : s.top_shapes) std::cout << " " << hom::io::shape_name(shape);
    std::cout << " elements: hom reads one element family per mesh\n";
    return 0;
  }
  hom::tools::with_mesh<hom::Equispaced>(data, [&](auto& m) {
    using M = std::decay_t<decltype(m)>;
    using F = typename M::family;
    const hom::Topology<F> topo(m);
    int kinds[3] = {0, 0, 0}, with_params = 0;
    for (const auto& c : m.node_classes()) {
      ++kinds[static_cast<int>(c.kind)];
      with_params += c.num_params > 0;
    }
    std::ostringstream t;
    t << "mesh:            " << F::name << (M::space_dim != F::dim ? " surface mesh in 3D" : " mesh") << ", order "
      << m.degree() << "\n";
    t << "  elements:      " << m.num_elements() << "\n";
    t << "  nodes:         " << m.num_nodes() << " (" << topo.num_vertices() << " vertices)\n";
    t << "  node classes:  " << kinds[0] << " free, " << kinds[1] << " fixed, " << kinds[2] << " on entities ("
      << with_params << " with parametric coordinates)\n";
    t << "  edges:         " << topo.num_edges() << "\n";
    if constexpr (F::dim == 3) t << "  faces:         " << topo.num_faces() << "\n";
    t << "  boundary:      " << topo.boundary_facets().size() << (F::dim == 2 ? " edges" : " faces") << ", "
      << m.boundary_facets().size() << " classified on entities\n";
    t << "  Euler char.:   " << topo.euler_characteristic() << "\n";
    std::cout << t.str();
  });
  return 0;
}

const hom::tools::RegisterCommand reg{{"info", "Describe a mesh file (format, elements, entities, topology) or a CAD model", run}};

}  // namespace
