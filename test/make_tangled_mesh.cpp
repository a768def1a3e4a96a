// Test helper for check_cli_optimize.sh.
//
//   make_tangled_mesh make FAMILY P N OUT.msh [MSH_VERSION [AMPLITUDE [SEED]]]
//     A curved, tangled mesh of degree P: the structured mesh of the unit
//     square / cube with N cells per axis (FAMILY tri, quad, tet, hex),
//     sheared by a smooth map so that its boundary is curved (y += 0.1 sin(pi x)
//     in 2D, z += 0.1 sin(pi x) sin(pi y) in 3D; the shear has det 1, so the
//     curved mesh is valid), then every free node moved by a pseudo-random
//     displacement of up to AMPLITUDE (default 0.35) times the cell size per
//     coordinate. Written as MSH 4.1 or 2.2 (default 4.1). Prints the number
//     of inverted elements and exits 1 when there is none (the test would
//     prove nothing).
//
//   make_tangled_mesh fixed-match IN.msh OUT.msh
//     Exits 0 when the nodes that are not free in IN.msh (boundary nodes) sit
//     at the same places in OUT.msh (sorted coordinate lists agree to 1e-10)
//     and some free node moved; prints what differs otherwise.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "hom/measure/shape_measure.hpp"
#include "hom/mesh/elevate.hpp"
#include "hom/mesh/structured.hpp"
#include "hom/nodes/equispaced.hpp"
#include "hom/quality/mesh_quality.hpp"
#include "mesh_io.hpp"

namespace {

/// Uniform in [-1, 1] from the fully specified mt19937_64 (the standard
/// distributions are implementation-defined), so the mesh is the same everywhere.
double symmetric_unit(std::mt19937_64& rng) { return 2.0 * (double(rng() >> 11) * 0x1.0p-53) - 1.0; }

template <hom::ElementFamily Family>
int make(int p, int n, const std::string& out, const std::string& version, double amplitude, std::uint64_t seed) {
  constexpr int D = Family::dim;
  std::array<int, D> cells;
  cells.fill(n);
  auto mesh = hom::elevate(hom::structured_mesh<Family, hom::Equispaced>(cells), p);
  const double pi = std::numbers::pi;
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    auto x = mesh.nodes().col(i);
    if constexpr (D == 2)
      x[1] += 0.1 * std::sin(pi * x[0]);
    else
      x[2] += 0.1 * std::sin(pi * x[0]) * std::sin(pi * x[1]);
  }
  std::mt19937_64 rng(seed);
  const double h = 1.0 / n;
  int moved = 0;
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    if (mesh.node_class(i).kind != hom::NodeKind::free) continue;
    for (int a = 0; a < D; ++a) mesh.nodes()(a, i) += amplitude * h * symmetric_unit(rng);
    ++moved;
  }
  const auto q = hom::mesh_quality(mesh, hom::ShapeMeasure{});
  hom::io::MshFormat f;
  f.version = version == "2.2" ? hom::io::MshFormat::Version::v22 : hom::io::MshFormat::Version::v41;
  hom::io::write_msh(out, mesh, f);
  std::printf("%s: %s, p = %d, %d elements, %d nodes, %d free nodes moved, %d inverted\n", out.c_str(),
              std::string(Family::name).c_str(), p, mesh.num_elements(), mesh.num_nodes(), moved, q.inverted());
  return q.inverted() > 0 ? 0 : 1;
}

template <class MeshT>
std::vector<std::array<double, 3>> sorted_positions(const MeshT& m, bool free) {
  std::vector<std::array<double, 3>> v;
  for (int i = 0; i < m.num_nodes(); ++i) {
    if ((m.node_class(i).kind == hom::NodeKind::free) != free) continue;
    std::array<double, 3> x{};
    for (int a = 0; a < MeshT::space_dim; ++a) x[a] = m.nodes()(a, i);
    v.push_back(x);
  }
  // Rounded keys so that round-off does not reorder equal points.
  auto key = [](const std::array<double, 3>& x) {
    std::array<long long, 3> k{};
    for (int a = 0; a < 3; ++a) k[a] = std::llround(x[a] * 1e8);
    return k;
  };
  std::sort(v.begin(), v.end(), [&](const auto& a, const auto& b) { return key(a) < key(b); });
  return v;
}

double max_difference(const std::vector<std::array<double, 3>>& a, const std::vector<std::array<double, 3>>& b) {
  double d = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i)
    for (int k = 0; k < 3; ++k) d = std::max(d, std::abs(a[i][k] - b[i][k]));
  return d;
}

int fixed_match(const std::string& in, const std::string& out) {
  const auto din = hom::io::read_msh_data(in), dout = hom::io::read_msh_data(out);
  return hom::tools::with_mesh<hom::Equispaced>(din, [&](auto& a) -> int {
    return hom::tools::with_mesh<hom::Equispaced>(dout, [&](auto& b) -> int {
      if constexpr (!std::is_same_v<std::decay_t<decltype(a)>, std::decay_t<decltype(b)>>) {
        std::printf("fixed-match: %s and %s hold different mesh types\n", in.c_str(), out.c_str());
        return 1;
      } else {
        if (a.num_nodes() != b.num_nodes() || a.num_elements() != b.num_elements()) {
          std::printf("fixed-match: node or element counts differ\n");
          return 1;
        }
        const auto fa = sorted_positions(a, false), fb = sorted_positions(b, false);
        if (fa.size() != fb.size()) {
          std::printf("fixed-match: %zu fixed nodes in %s, %zu in %s\n", fa.size(), in.c_str(), fb.size(), out.c_str());
          return 1;
        }
        const double fixed_diff = max_difference(fa, fb);
        double free_move = 0.0;
        const auto ga = sorted_positions(a, true), gb = sorted_positions(b, true);
        if (ga.size() == gb.size()) free_move = max_difference(ga, gb);
        std::printf("fixed-match: %zu fixed nodes, max difference %.3e; %zu free nodes, max sorted difference %.3e\n",
                    fa.size(), fixed_diff, ga.size(), free_move);
        return fixed_diff <= 1e-10 && free_move > 1e-6 ? 0 : 1;
      }
    });
  });
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  try {
    if (args.size() == 3 && args[0] == "fixed-match") return fixed_match(args[1], args[2]);
    if (args.size() >= 5 && args.size() <= 8 && args[0] == "make") {
      const int p = std::stoi(args[2]), n = std::stoi(args[3]);
      const std::string version = args.size() > 5 ? args[5] : "4.1";
      const double amplitude = args.size() > 6 ? std::stod(args[6]) : 0.35;
      const std::uint64_t seed = args.size() > 7 ? std::stoull(args[7]) : 1;
      const std::string& family = args[1];
      if (family == "tri") return make<hom::Simplex<2>>(p, n, args[4], version, amplitude, seed);
      if (family == "quad") return make<hom::Cube<2>>(p, n, args[4], version, amplitude, seed);
      if (family == "tet") return make<hom::Simplex<3>>(p, n, args[4], version, amplitude, seed);
      if (family == "hex") return make<hom::Cube<3>>(p, n, args[4], version, amplitude, seed);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "make_tangled_mesh: %s\n", e.what());
    return 2;
  }
  std::fprintf(stderr,
               "usage: make_tangled_mesh make tri|quad|tet|hex P N OUT.msh [4.1|2.2 [AMPLITUDE [SEED]]]\n"
               "       make_tangled_mesh fixed-match IN.msh OUT.msh\n");
  return 2;
}
