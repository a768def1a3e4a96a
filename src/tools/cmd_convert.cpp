// hom convert IN OUT [--order p] [--msh-version 4.1|2.2] [--binary] [--ascii]
//
// Converts a Gmsh mesh between MSH versions and encodings, or to a VTK
// Lagrange .vtu for ParaView, optionally changing its order. The mesh is held
// on equispaced nodes, so MSH -> MSH copies coordinates exactly; --order
// evaluates each element's map at the new degree's nodes (an elevation
// reproduces the map; a lower order interpolates it).

#include <iostream>
#include <string>

#include <boost/program_options.hpp>

#include "command.hpp"
#include "hom/mesh/elevate.hpp"
#include "mesh_io.hpp"

namespace po = boost::program_options;

namespace {

int run(int argc, char** argv) {
  po::options_description opts("hom convert IN OUT [options]\n\nConvert a mesh between MSH 4.1 (ASCII/binary), MSH 2.2 and VTU "
                               "(chosen by OUT's extension), optionally changing its order.\n\noptions");
  int order = 0;
  std::string msh_version = "4.1";
  opts.add_options()("help,h", "show this help")  //
      ("order,p", po::value<int>(&order), "element order of the output (1..10)")
      ("msh-version", po::value<std::string>(&msh_version)->default_value("4.1"), "MSH output version: 4.1 or 2.2")
      ("binary", "binary MSH 4.1 output")  //
      ("ascii", "ASCII VTU output (default: base64 binary)");
  po::options_description hidden;
  hidden.add_options()("input", po::value<std::string>())("output", po::value<std::string>());
  po::options_description all;
  all.add(opts).add(hidden);
  po::positional_options_description pos;
  pos.add("input", 1).add("output", 1);
  po::variables_map vm;
  try {
    po::store(po::command_line_parser(argc, argv).options(all).positional(pos).run(), vm);
    po::notify(vm);
  } catch (const po::error& e) {
    throw hom::tools::UsageError(std::string("convert: ") + e.what());
  }
  if (vm.count("help")) {
    std::cout << opts << "\n";
    return 0;
  }
  if (!vm.count("input") || !vm.count("output")) throw hom::tools::UsageError("convert: need IN and OUT (see 'hom convert --help')");
  const std::string in = vm["input"].as<std::string>(), out = vm["output"].as<std::string>();
  if (vm.count("order") && (order < 1 || order > 10)) throw hom::tools::UsageError("convert: --order must be 1..10");
  if (!hom::tools::ends_with(in, ".msh")) throw hom::tools::UsageError("convert: can only read .msh files, not '" + in + "'");
  const auto format = hom::tools::output_format(out, msh_version, vm.count("binary") > 0, vm.count("ascii") > 0);

  const auto data = hom::io::read_msh_data(in);
  hom::tools::with_mesh<hom::Equispaced>(data, [&](auto& mesh) {
    if (order && order != mesh.degree())
      hom::tools::write_mesh(out, hom::change_degree<hom::Equispaced>(mesh, order), format);
    else
      hom::tools::write_mesh(out, mesh, format);
  });
  return 0;
}

const hom::tools::RegisterCommand reg{{"convert", "Convert between MSH 4.1/2.2 and VTU, optionally changing the order", run}};

}  // namespace
