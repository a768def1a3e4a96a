// Tests of VTU output (include/hom/io/vtu.hpp, vtk_cells.hpp). VTK itself
// reads the files back in check_vtu.py; here the files are decoded by hand.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "hom/io/vtu.hpp"
#include "hom/mesh/elevate.hpp"
#include "hom/mesh/structured.hpp"

using namespace hom;
using namespace hom::io;

#define HOM_FAMILIES Simplex<2>, Simplex<3>, Cube<2>, Cube<3>

namespace {

namespace fs = std::filesystem;

fs::path scratch_dir() {
  const fs::path d = fs::temp_directory_path() / ("hom_test_io_vtu_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string base64_decode(std::string_view s) {
  auto val = [](char c) -> int {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    return -1;
  };
  std::string out;
  for (std::size_t i = 0; i + 3 < s.size(); i += 4) {
    const int a = val(s[i]), b = val(s[i + 1]), c = val(s[i + 2]), d = val(s[i + 3]);
    out.push_back(char((a << 2) | (b >> 4)));
    if (s[i + 2] != '=') out.push_back(char(((b & 15) << 4) | (c >> 2)));
    if (s[i + 3] != '=') out.push_back(char(((c & 3) << 6) | d));
  }
  return out;
}

// Values of the DataArray called `name`, from either encoding.
template <class T>
std::vector<T> read_array(const std::string& file, const std::string& name) {
  const auto at = file.find("Name=\"" + name + "\"");
  REQUIRE(at != std::string::npos);
  const auto tag_end = file.find('>', at);
  const std::string tag = file.substr(at, tag_end - at);
  std::vector<T> out;
  if (tag.find("format=\"ascii\"") != std::string::npos) {
    const auto end = file.find("</DataArray>", tag_end);
    std::istringstream in(file.substr(tag_end + 1, end - tag_end - 1));
    double v;
    while (in >> v) out.push_back(static_cast<T>(v));
  } else {
    const auto o = tag.find("offset=\"");
    const std::size_t offset = std::stoul(tag.substr(o + 8));
    const auto data = file.find('_', file.find("<AppendedData")) + 1;
    // The array's base64 stream runs to the next array's offset; decode its
    // 8-byte header first to know the length.
    const std::string head = base64_decode(file.substr(data + offset, 12));
    std::uint64_t bytes;
    std::memcpy(&bytes, head.data(), 8);
    const std::size_t chars = 4 * ((8 + bytes + 2) / 3);
    const std::string raw = base64_decode(file.substr(data + offset, chars));
    REQUIRE(raw.size() == 8 + bytes);
    out.resize(bytes / sizeof(T));
    std::memcpy(out.data(), raw.data() + 8, bytes);
  }
  return out;
}

template <int D>
Eigen::Matrix<double, D, 1> bend(const Eigen::Matrix<double, D, 1>& x) {
  Eigen::Matrix<double, D, 1> y = x;
  y[0] += 0.1 * std::sin(2.0 * x[1]);
  y[1] += 0.05 * x[0] * x[0];
  return y;
}

}  // namespace

TEST_CASE_TEMPLATE("VTK node order is a permutation with vertices, then edges first", F, HOM_FAMILIES) {
  for (int p = 1; p <= 10; ++p) {
    const auto& perm = vtk_to_hom<F>(p);
    CHECK(int(perm.size()) == F::num_nodes(p));
    std::set<int> s(perm.begin(), perm.end());
    CHECK(int(s.size()) == F::num_nodes(p));
    CHECK(*s.begin() == 0);
    for (int v = 0; v < F::num_vertices; ++v) CHECK(perm[v] == v);
    const auto& layout = node_layout<F>(p);
    const int ne = int(F::edges().size());
    for (int k = F::num_vertices; k < F::num_vertices + ne * (p - 1); ++k) CHECK(layout.entity(perm[k]).dim == 1);
    for (int k = F::num_vertices + ne * (p - 1); k < F::num_nodes(p); ++k) CHECK(layout.entity(perm[k]).dim >= 2);
  }
}

TEST_CASE_TEMPLATE("VTU points are hom's map at VTK's equispaced nodes, in both encodings", F, HOM_FAMILIES) {
  const auto dir = scratch_dir();
  for (int p : {1, 3, 6}) {
    std::array<int, F::dim> cells{};
    cells.fill(F::dim == 2 ? 2 : 1);
    auto m = elevate(structured_mesh<F>(cells), p);
    for (int i = 0; i < m.num_nodes(); ++i) m.node(i) = bend<F::dim>(m.node(i));
    VtuField flag{"flag", 1, std::vector<double>(m.num_nodes(), 0.0)};
    flag.values[0] = 1;
    VtuField vec{"vector", 3, std::vector<double>(3 * m.num_elements(), 2.5)};
    VtuOptions binary, ascii;
    ascii.encoding = VtuOptions::Encoding::ascii;
    binary.interpolate_point_data = ascii.interpolate_point_data = false;
    write_vtu((dir / "b.vtu").string(), m, {flag}, {vec}, binary);
    write_vtu((dir / "a.vtu").string(), m, {flag}, {vec}, ascii);
    const auto fb = slurp(dir / "b.vtu"), fa = slurp(dir / "a.vtu");
    CHECK(fb.find("version=\"2.2\"") != std::string::npos);
    const auto pts = read_array<double>(fb, "Points");
    const auto conn = read_array<std::int64_t>(fb, "connectivity");
    const auto offs = read_array<std::int64_t>(fb, "offsets");
    const auto types = read_array<std::uint8_t>(fb, "types");
    REQUIRE(pts.size() == 3 * std::size_t(m.num_nodes()));
    REQUIRE(conn.size() == std::size_t(m.num_elements()) * m.nodes_per_element());
    CHECK(offs.back() == std::int64_t(conn.size()));
    for (auto t : types) CHECK(int(t) == vtk_lagrange_cell_type<F>);
    // ASCII holds the same numbers (shortest round-trip representation).
    CHECK(read_array<double>(fa, "Points") == pts);
    CHECK(read_array<std::int64_t>(fa, "connectivity") == conn);
    CHECK(read_array<double>(fa, "flag") == flag.values);
    CHECK(read_array<double>(fb, "flag") == flag.values);
    CHECK(read_array<double>(fb, "vector") == vec.values);
    CHECK(read_array<std::int32_t>(fb, "entity").size() == std::size_t(m.num_elements()));
    // Point k of cell e is the map at VTK's k-th (equispaced) reference node.
    const auto lat = vtk_node_lattice<F>(p);
    for (int e = 0; e < m.num_elements(); ++e)
      for (int k = 0; k < m.nodes_per_element(); ++k) {
        const auto x = m.map(e, F::equispaced_point(lat[k], p));
        const auto id = conn[std::size_t(e) * m.nodes_per_element() + k];
        for (int a = 0; a < F::dim; ++a) CHECK(std::abs(pts[3 * id + a] - x[a]) < 1e-13);
      }
  }
}

TEST_CASE("write_vtu refuses fields of the wrong size and leaves no file") {
  const auto dir = scratch_dir();
  const auto m = structured_mesh<Simplex<2>>({2, 2});
  const auto path = (dir / "bad.vtu").string();
  fs::remove(path);
  CHECK_THROWS_AS(write_vtu(path, m, {{"f", 1, {1.0, 2.0}}}), IoError);
  CHECK_THROWS_AS(write_vtu(path, m, {}, {{"c", 2, std::vector<double>(m.num_elements())}}), IoError);
  CHECK(!fs::exists(path));
  CHECK(!fs::exists(path + ".tmp"));
}
