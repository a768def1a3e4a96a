// hom info MESH
//
// Prints what a Gmsh mesh file holds: format, element types and counts, the
// mesh hom reads from it (family, order, nodes, node classification,
// topology), entities, physical groups and bounding box.

#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>
#include <string>

#include <boost/program_options.hpp>

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

int run(int argc, char** argv) {
  po::options_description opts("hom info MESH\n\nDescribe a Gmsh .msh file.\n\noptions");
  opts.add_options()("help,h", "show this help");
  po::variables_map vm;
  if (!hom::tools::parse_options("info", argc, argv, opts, {{"mesh", po::value<std::string>()}}, vm)) return 0;
  if (!vm.count("mesh")) throw hom::tools::UsageError("info: need a mesh file (see 'hom info --help')");
  const std::string path = vm["mesh"].as<std::string>();
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

const hom::tools::RegisterCommand reg{{"info", "Describe a mesh file: format, elements, entities, topology", run}};

}  // namespace
