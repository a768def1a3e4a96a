// Helper for the Python cross-checks of hom's file I/O against Gmsh and VTK
// (check_gmsh_ordering.py, check_vtu.py, check_gmsh_roundtrip.py).
//
//   io_helper orderings          print hom's Gmsh and VTK node orders
//   io_helper vtu DIR            write curved VTU meshes and the positions
//                                hom's map takes at sample points (DIR/cases.json)
//   io_helper reread IN OUT      read IN on warp & blend nodes, write OUT (MSH 4.1)
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <random>
#include <sstream>
#include <string>

#include "hom/io/msh.hpp"
#include "hom/io/vtu.hpp"
#include "hom/mesh/elevate.hpp"
#include "hom/mesh/structured.hpp"
#include "mesh_io.hpp"

using namespace hom;

namespace {

template <int D>
std::string lattice_str(const Lattice<D>& l) {
  std::string s;
  for (int k = 0; k < D; ++k) s += (k ? "," : "") + std::to_string(l[k]);
  return s;
}

template <ElementFamily F>
void print_orderings(const char* name, int max_gmsh) {
  for (int p = 1; p <= 10; ++p) {
    if (p <= max_gmsh) {
      std::cout << "gmsh " << name << " " << p;
      for (const auto& l : io::gmsh_node_lattice<F>(p)) std::cout << " " << lattice_str<F::dim>(l);
      std::cout << "\n";
    }
    std::cout << "vtk " << name << " " << p;
    for (const auto& l : io::vtk_node_lattice<F>(p)) std::cout << " " << lattice_str<F::dim>(l);
    std::cout << "\n";
  }
}

template <int D>
Eigen::Matrix<double, D, 1> bend(const Eigen::Matrix<double, D, 1>& x) {
  Eigen::Matrix<double, D, 1> y = x;
  y[0] += 0.1 * std::sin(2.0 * x[1] + 0.5);
  y[1] += 0.07 * std::cos(1.5 * x[0]) * (1.0 + x[0]);
  if constexpr (D == 3) y[2] += 0.06 * std::sin(x[0] + x[1]) + 0.05 * x[2] * x[0];
  return y;
}

// Writes DIR/NAME_pP.vtu (base64) and DIR/NAME_pP_ascii.vtu, and appends the
// expected positions at random points to `json`.
template <ElementFamily F>
void write_vtu_case(const std::string& dir, const char* name, int p, std::ostringstream& json, bool& first) {
  std::array<int, F::dim> cells{};
  cells.fill(1);
  cells[0] = 2;
  auto m = elevate(structured_mesh<F>(cells), p);
  for (int i = 0; i < m.num_nodes(); ++i) m.node(i) = bend<F::dim>(m.node(i));
  // A smooth point field and a cell field.
  io::VtuField f{"field", 1, {}};
  for (int i = 0; i < m.num_nodes(); ++i) f.values.push_back(m.node(i).squaredNorm());
  io::VtuField c{"cell_id", 1, {}};
  for (int e = 0; e < m.num_elements(); ++e) c.values.push_back(e);
  const std::string base = dir + "/" + name + "_p" + std::to_string(p);
  io::write_vtu(base + ".vtu", m, {f}, {c});
  io::VtuOptions ascii;
  ascii.encoding = io::VtuOptions::Encoding::ascii;
  io::write_vtu(base + "_ascii.vtu", m, {f}, {c}, ascii);

  std::mt19937 rng(p);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  json << (first ? "" : ",\n") << "{\"name\": \"" << name << "\", \"p\": " << p << ", \"file\": \"" << base
       << ".vtu\", \"cell_type\": " << io::vtk_lagrange_cell_type<F> << ", \"cells\": " << m.num_elements()
       << ", \"points\": " << m.num_nodes() << ", \"samples\": [";
  first = false;
  bool first_sample = true;
  for (int e = 0; e < m.num_elements(); ++e)
    for (int s = 0; s < 3; ++s) {
      typename F::Point xi;
      do {
        for (int k = 0; k < F::dim; ++k) xi[k] = u(rng);
      } while (F::is_simplex && xi.sum() > 1.0);
      typename F::Point ref = xi;
      if constexpr (!F::is_simplex) ref = 2.0 * xi.array() - 1.0;  // VTK [0,1]^d -> hom [-1,1]^d
      const auto x = m.map(e, ref);
      const Eigen::VectorXd N = m.basis().value(ref);
      double field = 0;
      for (int j = 0; j < m.nodes_per_element(); ++j) field += N[j] * m.node(m.element(e)[j]).squaredNorm();
      json << (first_sample ? "" : ", ") << "{\"cell\": " << e << ", \"pcoords\": [";
      first_sample = false;
      for (int k = 0; k < 3; ++k) json << (k ? ", " : "") << (k < F::dim ? xi[k] : 0.0);
      json << "], \"x\": [";
      for (int k = 0; k < 3; ++k) json << (k ? ", " : "") << (k < F::dim ? x[k] : 0.0);
      json << "], \"field\": " << field << "}";
    }
  json << "]}";
}

int vtu_cases(const std::string& dir) {
  std::ostringstream json;
  json << std::setprecision(17) << "[\n";
  bool first = true;
  for (int p : {1, 2, 3, 4, 5, 7, 10}) {
    write_vtu_case<Simplex<2>>(dir, "triangle", p, json, first);
    write_vtu_case<Cube<2>>(dir, "quadrilateral", p, json, first);
    write_vtu_case<Simplex<3>>(dir, "tetrahedron", p, json, first);
    if (p <= 7) write_vtu_case<Cube<3>>(dir, "hexahedron", p, json, first);
  }
  json << "\n]\n";
  std::ofstream(dir + "/cases.json") << json.str();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string cmd = argc > 1 ? argv[1] : "";
  try {
    if (cmd == "orderings") {
      print_orderings<Simplex<2>>("triangle", 10);
      print_orderings<Cube<2>>("quadrilateral", 10);
      print_orderings<Simplex<3>>("tetrahedron", 10);
      print_orderings<Cube<3>>("hexahedron", 9);
      for (int p = 1; p <= 10; ++p) {
        std::cout << "gmsh line " << p;
        for (int i : io::gmsh_line_positions(p)) std::cout << " " << i;
        std::cout << "\n";
      }
      return 0;
    }
    if (cmd == "vtu" && argc == 3) return vtu_cases(argv[2]);
    if (cmd == "reread" && argc == 4) {
      const auto data = io::read_msh_data(argv[2]);
      tools::with_mesh<WarpBlend>(data, [&](auto& m) { io::write_msh(argv[3], m); });
      return 0;
    }
  } catch (const std::exception& e) {
    std::cerr << "io_helper: " << e.what() << "\n";
    return 1;
  }
  std::cerr << "usage: io_helper orderings | vtu DIR | reread IN OUT\n";
  return 2;
}
