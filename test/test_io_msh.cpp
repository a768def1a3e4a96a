// Tests of Gmsh MSH I/O (include/hom/io/msh*.hpp, gmsh_elements.hpp):
// round trips in every format for every family and order, parametric
// coordinates, surface meshes, node orderings, and malformed input.
// Gmsh itself checks the orderings and files in check_gmsh_*.py.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>

#include "hom/io/msh.hpp"
#include "hom/mesh/elevate.hpp"
#include "hom/mesh/structured.hpp"

using namespace hom;
using namespace hom::io;

#define HOM_FAMILIES Simplex<2>, Simplex<3>, Cube<2>, Cube<3>

namespace {

namespace fs = std::filesystem;

fs::path scratch_dir() {
  const fs::path d = fs::temp_directory_path() / ("hom_test_io_msh_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

template <int D>
Eigen::Matrix<double, D, 1> bend(const Eigen::Matrix<double, D, 1>& x) {
  Eigen::Matrix<double, D, 1> y = x;
  y[0] += 0.08 * std::sin(2.0 * x[1] + 0.5);
  y[1] += 0.06 * std::cos(1.5 * x[0]) * (1.0 + x[0]);
  if constexpr (D == 3) y[2] += 0.05 * std::sin(x[0] + x[1]) + 0.04 * x[2] * x[0];
  return y;
}

template <ElementFamily F>
std::array<int, F::dim> small_cells() {
  if constexpr (F::dim == 2)
    return {2, 1};
  else
    return {1, 1, 1};
}

// A curved degree-p mesh: a structured mesh elevated, then bent by a smooth
// map, with physical groups on one side and on the domain.
template <ElementFamily F, NodeSet N = WarpBlend>
Mesh<F, N> curved_mesh(int p) {
  auto m = elevate(structured_mesh<F, N>(small_cells<F>()), p);
  for (int i = 0; i < m.num_nodes(); ++i) m.node(i) = bend<F::dim>(m.node(i));
  for (auto& en : m.entities()) {
    if (en.id.dim == F::dim) en.physical_tags = {7};
    if (en.id.dim == F::dim - 1 && en.id.tag == 1) en.physical_tags = {3};
  }
  m.physical_groups() = {{F::dim, 7, "domain"}, {F::dim - 1, 3, "inlet side"}};
  return m;
}

template <ElementFamily F>
typename F::Point random_reference_point(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  typename F::Point x;
  if constexpr (F::is_simplex) {
    do {
      for (int k = 0; k < F::dim; ++k) x[k] = u(rng);
    } while (x.sum() > 1.0);
  } else {
    for (int k = 0; k < F::dim; ++k) x[k] = 2.0 * u(rng) - 1.0;
  }
  return x;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Parse + convert; returns the ParseError message ("" if it parsed).
template <ElementFamily F = Simplex<2>>
std::string error_of(const std::string& content) {
  try {
    (void)to_mesh<F>(parse_msh(content, "bad.msh"));
  } catch (const ParseError& e) {
    return e.what();
  } catch (const IoError& e) {
    return std::string("IoError: ") + e.what();
  }
  return "";
}

const std::string kHead22 = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n";

std::string tri22(const std::string& nodes, const std::string& elements, int nn = 4, int ne = 2) {
  return kHead22 + "$Nodes\n" + std::to_string(nn) + "\n" + nodes + "$EndNodes\n$Elements\n" + std::to_string(ne) +
         "\n" + elements + "$EndElements\n";
}

const std::string kNodes = "1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n";  // lines 6-9
const std::string kElems = "1 2 2 0 1 1 2 3\n2 2 2 0 1 1 3 4\n";    // lines 13-14

void check_error(const std::string& msg, int line, const std::string& what) {
  INFO(msg);
  CHECK(msg.rfind("bad.msh:" + std::to_string(line) + ": ", 0) == 0);
  CHECK(msg.find(what) != std::string::npos);
}

}  // namespace

TEST_CASE_TEMPLATE("Gmsh node order is a permutation with the vertices first and the family's node count", F,
                   HOM_FAMILIES) {
  for (int p = 1; p <= 10; ++p) {
    const auto& perm = gmsh_to_hom<F>(p);
    CHECK(int(perm.size()) == F::num_nodes(p));
    std::set<int> s(perm.begin(), perm.end());
    CHECK(int(s.size()) == F::num_nodes(p));
    CHECK(*s.begin() == 0);
    for (int v = 0; v < F::num_vertices; ++v) CHECK(perm[v] == v);
    // Edge nodes come right after the vertices, one edge at a time, in Gmsh's
    // edge order: each block of p - 1 nodes lies on one hom edge.
    const auto& layout = node_layout<F>(p);
    const int ne = int(F::edges().size());
    for (int k = F::num_vertices; k < F::num_vertices + ne * (p - 1); ++k) CHECK(layout.entity(perm[k]).dim == 1);
  }
  CHECK(gmsh_element_info(gmsh_element_type(gmsh_shape_of<F>, 3))->order == 3);
}

TEST_CASE("Gmsh element type table") {
  CHECK(gmsh_element_type(GmshShape::triangle, 2) == 9);
  CHECK(gmsh_element_type(GmshShape::tetrahedron, 10) == 75);
  CHECK(gmsh_element_type(GmshShape::hexahedron, 9) == 98);
  CHECK_THROWS_AS(gmsh_element_type(GmshShape::hexahedron, 10), IoError);
  CHECK_THROWS_AS(gmsh_element_type(GmshShape::triangle, 11), IoError);
  CHECK(!gmsh_element_info(16).has_value());  // 8-node serendipity quad
  CHECK(gmsh_unsupported_type_name(16).find("serendipity") != std::string::npos);
  CHECK(gmsh_unsupported_type_name(6) == "prism");
  for (int t = 1; t < 140; ++t)
    if (auto info = gmsh_element_info(t); info && info->shape != GmshShape::point)
      CHECK(gmsh_element_type(info->shape, info->order) == t);
}

TEST_CASE_TEMPLATE("MSH round trip reproduces the map for every order and format", F, HOM_FAMILIES) {
  const auto dir = scratch_dir();
  std::mt19937 rng(11);
  const int max_p = F::is_simplex || F::dim == 2 ? 10 : 9;
  const MshFormat formats[] = {{MshFormat::Version::v41, false}, {MshFormat::Version::v41, true},
                               {MshFormat::Version::v22, false}};
  for (int p = 1; p <= max_p; ++p) {
    const auto m = curved_mesh<F>(p);
    for (const auto& fmt : formats) {
      CAPTURE(p);
      CAPTURE(fmt.binary);
      const bool v41 = fmt.version == MshFormat::Version::v41;
      const auto path = (dir / "rt.msh").string();
      write_msh(path, m, fmt);
      CHECK(!fs::exists(path + ".tmp"));
      const auto r = read_msh<F>(path);
      REQUIRE(r.num_nodes() == m.num_nodes());
      REQUIRE(r.num_elements() == m.num_elements());
      CHECK(r.degree() == p);
      CHECK(r.elements() == m.elements());
      CHECK((r.nodes() - m.nodes()).cwiseAbs().maxCoeff() < 1e-12);
      for (int e = 0; e < m.num_elements(); ++e) {
        const auto xi = random_reference_point<F>(rng);
        CHECK((r.map(e, xi) - m.map(e, xi)).norm() < 1e-12);
      }
      CHECK(r.element_entities() == m.element_entities());
      CHECK(r.boundary_facets() == m.boundary_facets());
      CHECK(r.physical_groups() == m.physical_groups());
      if (v41) {
        // MSH 4 keeps every node's entity; MSH 2 only knows the elements'.
        for (int i = 0; i < m.num_nodes(); ++i) CHECK(r.node_class(i) == m.node_class(i));
        REQUIRE(r.entities().size() == m.entities().size());
        for (const auto& en : m.entities()) {
          const Entity* back = r.find_entity(en.id);
          REQUIRE(back != nullptr);
          CHECK(back->physical_tags == en.physical_tags);
          CHECK(back->boundary == en.boundary);
        }
      } else {
        for (int i = 0; i < m.num_nodes(); ++i) {
          const bool interior = m.node_class(i).kind == NodeKind::free;
          CHECK((r.node_class(i).kind == NodeKind::free) == interior);
        }
      }
    }
  }
}

TEST_CASE_TEMPLATE("MSH with equispaced nodes round-trips bit for bit", F, HOM_FAMILIES) {
  const auto dir = scratch_dir();
  const auto m = curved_mesh<F, Equispaced>(4);
  for (bool binary : {false, true}) {
    const auto path = (dir / "eq.msh").string();
    write_msh(path, m, {MshFormat::Version::v41, binary});
    const auto r = read_msh<F, Equispaced>(path);
    CHECK(r.nodes() == m.nodes());
    // Writing it again gives the same file.
    const auto again = (dir / "eq2.msh").string();
    write_msh(again, r, {MshFormat::Version::v41, binary});
    CHECK(slurp(path) == slurp(again));
  }
}

TEST_CASE("parametric coordinates are written and read (MSH 4.1)") {
  const auto dir = scratch_dir();
  auto m = elevate(structured_mesh<Simplex<2>, Equispaced>({2, 2}), 3);
  int with_params = 0;
  for (int i = 0; i < m.num_nodes(); ++i) {
    auto& c = m.node_class(i);
    if (c.entity && c.entity->dim == 1) {
      c.num_params = 1;
      c.params[0] = 0.25 + m.node(i).sum();
      ++with_params;
    }
  }
  REQUIRE(with_params > 0);
  for (bool binary : {false, true}) {
    const auto path = (dir / "param.msh").string();
    write_msh(path, m, {MshFormat::Version::v41, binary});
    const auto r = read_msh<Simplex<2>, Equispaced>(path);
    for (int i = 0; i < m.num_nodes(); ++i) CHECK(r.node_class(i) == m.node_class(i));
    // With warp & blend nodes only vertices keep their (exact) parameters.
    const auto w = read_msh<Simplex<2>>(path);
    const auto vertex = w.vertex_mask();
    for (int i = 0; i < w.num_nodes(); ++i)
      if (m.node_class(i).num_params) CHECK(w.node_class(i).num_params == (vertex[i] ? 1 : 0));
  }
}

TEST_CASE("surface meshes (triangles and quadrilaterals in 3D) round-trip; planar reading refuses them") {
  const auto dir = scratch_dir();
  auto planar = elevate(structured_mesh<Cube<2>>({2, 2}), 3);
  Mesh<Cube<2>, WarpBlend, 3>::Coordinates X(3, planar.num_nodes());
  for (int i = 0; i < planar.num_nodes(); ++i) {
    const auto x = planar.node(i);
    X.col(i) << x[0], x[1], 0.3 * std::sin(x[0] + 2 * x[1]);
  }
  Mesh<Cube<2>, WarpBlend, 3> s(3, X, planar.elements());
  const auto path = (dir / "surf.msh").string();
  for (bool binary : {false, true}) {
    write_msh(path, s, {MshFormat::Version::v41, binary});
    const auto r = read_msh<Cube<2>, WarpBlend, 3>(path);
    CHECK((r.nodes() - s.nodes()).cwiseAbs().maxCoeff() < 1e-12);
    CHECK(r.elements() == s.elements());
    // Surface nodes lie on the surface entity: they are not free to leave it.
    for (int i = 0; i < r.num_nodes(); ++i) CHECK(r.node_class(i).kind != NodeKind::free);
  }
  const auto msg = [&] {
    try {
      (void)read_msh<Cube<2>>(path);
    } catch (const ParseError& e) {
      return std::string(e.what());
    }
    return std::string();
  }();
  CHECK(msg.find("not a planar mesh") != std::string::npos);
  // A 3D file is not a 2D mesh either.
  write_msh(path, elevate(structured_mesh<Simplex<3>>({1, 1, 1}), 2));
  CHECK_THROWS_AS((void)read_msh<Simplex<2>>(path), ParseError);
}

TEST_CASE("a planar mesh of the other orientation is reflected, not rejected") {
  auto m = elevate(structured_mesh<Simplex<2>>({2, 2}), 3);
  for (int i = 0; i < m.num_nodes(); ++i) m.node(i)[1] = -m.node(i)[1];  // mirror: all elements negative
  auto d = to_msh_data(m);
  d.path = "mirror.msh";
  const auto r = to_mesh<Simplex<2>>(d);
  const Simplex<2>::Point c(1.0 / 3, 1.0 / 3);
  for (int e = 0; e < r.num_elements(); ++e) CHECK(r.jacobian(e, c).determinant() > 0);
  // Same nodes as the mirrored mesh.
  CHECK((r.nodes() - m.nodes()).cwiseAbs().maxCoeff() < 1e-12);
}

TEST_CASE("malformed MSH files give FILE:LINE errors") {
  CHECK(error_of(tri22(kNodes, kElems)).empty());
  check_error(error_of(tri22("1 0 0 0\n2 nan 0 0\n3 1 1 0\n4 0 1 0\n", kElems)), 7, "non-finite");
  check_error(error_of(tri22("1 0 0 0\n2 1 0 0\n3 inf 1 0\n4 0 1 0\n", kElems)), 8, "non-finite");
  check_error(error_of(tri22("1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 x\n", kElems)), 9, "expected a number");
  check_error(error_of(tri22(kNodes, "1 2 2 0 1 1 2 3\n2 2 2 0 1 1 3 5\n")), 14, "missing node 5");
  check_error(error_of(tri22(kNodes, "1 2 2 0 1 1 2 3\n2 6 2 0 1 1 3 4 2 3 4\n")), 14,
              "unsupported element type 6 (prism)");
  check_error(error_of(tri22(kNodes, "1 2 2 0 1 1 2 3\n2 16 2 0 1 1 3 4 2 1 2 3 4 1\n")), 14, "serendipity");
  check_error(error_of(tri22(kNodes, "1 2 2 0 1 1 2 3\n2 2 2 0 1 3 1 4\n")), 14, "oriented inconsistently");
  check_error(error_of(tri22(kNodes, "1 2 2 0 1 1 2 3\n2 2 2 0 1 1 3 1\n")), 14, "twice");
  check_error(error_of(tri22(kNodes, "1 2 2 0 1 1 2 3\n2 3 2 0 1 1 3 4 2\n")), 14, "mixes");
  check_error(error_of(tri22("1 0 0 0\n2 1 0 0\n3 1 1 0\n3 0 1 0\n", kElems)), 9, "duplicate node tag 3");
  check_error(error_of(tri22(kNodes, kElems, 5)), 10, "declares 5 nodes but holds 4");
  check_error(error_of(tri22(kNodes, kElems, 3)), 9, "more than the 3 nodes");
  check_error(error_of(tri22(kNodes, kElems, 4, 3)), 15, "declares 3 elements but holds 2");
  check_error(error_of(tri22("1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0.5\n", kElems)), 9, "not a planar mesh");
  // Truncated: the file stops inside $Nodes.
  const auto full = tri22(kNodes, kElems);
  check_error(error_of(full.substr(0, full.find("3 1 1 0"))), 5, "truncated");
  check_error(error_of(full.substr(0, full.find("2 2 2 0 1 1 3 4"))), 14, "unexpected end of file in $Elements");
  check_error(error_of(full.substr(0, full.find("$EndElements"))), 15, "end of file");
  check_error(error_of("$MeshFormat\n4 0 8\n$EndMeshFormat\n"), 2, "not supported");
  check_error(error_of("$MeshFormat\n2.2 1 8\n$EndMeshFormat\n"), 2, "binary MSH 2");
  check_error(error_of("hello\n"), 1, "not a Gmsh MSH file");
  check_error(error_of(""), 1, "empty file");
  check_error(error_of(kHead22 + "$Nodes\n0\n$EndNodes\n"), 7, "no $Elements");
  check_error(error_of(kHead22 + "$Comments\nnever closed\n"), 4, "not terminated");

  // A non-conforming pair of quadratic triangles: the shared edge 1-3 has
  // midside node 7 in one and 8 in the other.
  const std::string nodes10 =
      "1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n5 .5 0 0\n6 1 .5 0\n7 .5 .5 0\n8 .5 .5 0\n9 .5 1 0\n10 0 .5 0\n";
  check_error(error_of(tri22(nodes10, "1 9 2 0 1 1 2 3 5 6 7\n2 9 2 0 1 1 3 4 8 9 10\n", 10)), 20,
              "non-conforming");
  // A node used at two places (as a midside node and as a vertex).
  check_error(error_of(tri22(nodes10, "1 9 2 0 1 1 2 3 5 6 7\n2 9 2 0 1 1 3 4 7 9 5\n", 10)), 20,
              "another place");

  // MSH 4.1 count and block checks.
  const std::string head41 = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";
  const std::string nodes41 = "$Nodes\n1 4 1 4\n2 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n$EndNodes\n";
  const std::string elems41 = "$Elements\n1 2 1 2\n2 1 2 2\n1 1 2 3\n2 1 3 4\n$EndElements\n";
  CHECK(error_of(head41 + nodes41 + elems41).empty());
  check_error(error_of(head41 + "$Nodes\n1 5 1 5\n2 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n$EndNodes\n" +
                       elems41),
              5, "declares 5 nodes but its blocks hold 4");
  check_error(error_of(head41 + nodes41 + "$Elements\n1 2 1 2\n1 1 2 2\n1 1 2 3\n2 1 3 4\n$EndElements\n"), 18,
              "block of entity dimension 1");
  check_error(error_of(head41 + nodes41 + "$Elements\n1 2 1 2\n2 1 2 3\n1 1 2 3\n2 1 3 4\n$EndElements\n"), 18,
              "more elements than the 2 declared");
  check_error(error_of(head41 + "$Nodes\n1 4 1 4\n2 1 0 4\n1\n2\n3\n9\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n$EndNodes\n" +
                       elems41),
              10, "outside the declared range");
  // A boundary line that is not an edge of any triangle.
  check_error(error_of(head41 + nodes41 +
                       "$Elements\n2 3 1 3\n1 1 1 1\n3 2 4\n2 1 2 2\n1 1 2 3\n2 1 3 4\n$EndElements\n"),
              19, "does not lie on an edge");
  // A count far beyond the file's size is refused before allocating.
  check_error(error_of(head41 + "$Nodes\n1 999999999999 1 999999999999\n"), 5, "truncated");
}

TEST_CASE("truncated and corrupted binary MSH 4.1 files give errors, never crashes") {
  const auto dir = scratch_dir();
  const auto path = (dir / "bin.msh").string();
  write_msh(path, curved_mesh<Simplex<3>>(2), {MshFormat::Version::v41, true});
  const auto content = slurp(path);
  REQUIRE(error_of<Simplex<3>>(content).empty());
  int errors = 0;
  for (std::size_t cut = 0; cut < content.size(); cut += 97) {
    const auto msg = error_of<Simplex<3>>(content.substr(0, cut));
    CHECK(!msg.empty());
    errors += msg.rfind("bad.msh:", 0) == 0;
  }
  CHECK(errors > 0);
  // Flip bytes: either a clean error or a (different) valid mesh.
  std::mt19937 rng(5);
  for (int t = 0; t < 200; ++t) {
    std::string c = content;
    c[rng() % c.size()] ^= char(1 + rng() % 255);
    (void)error_of<Simplex<3>>(c);
  }
}

TEST_CASE("writers leave no partial file") {
  const auto dir = scratch_dir();
  const auto path = (dir / "hex10.msh").string();
  fs::remove(path);
  const auto hex = elevate(structured_mesh<Cube<3>>({1, 1, 1}), 10);
  CHECK_THROWS_AS(write_msh(path, hex), IoError);
  CHECK(!fs::exists(path));
  CHECK(!fs::exists(path + ".tmp"));
  CHECK_THROWS_AS(write_msh((dir / "no" / "such" / "dir.msh").string(), curved_mesh<Simplex<2>>(2)), IoError);
  CHECK_THROWS_AS(write_msh(path, curved_mesh<Simplex<2>>(2), {MshFormat::Version::v22, true}), IoError);
  CHECK_THROWS_AS((void)read_msh<Simplex<2>>((dir / "missing.msh").string()), IoError);
}

// Inputs that once broke a reader, found by fuzz/run or by hand: each must
// give an IoError (or parse), never crash. Add crash-* files from fuzz/run
// here as string literals.
TEST_CASE("fuzzer regressions") {
  const std::string cases[] = {
      std::string("$MeshFormat\n4.1 1 8\n", 20),                     // binary header cut before the endianness int
      "$MeshFormat\n4.1 1 8\n\x01\x00\x00\x00\n$EndMeshFormat\n$Nodes\n",  // binary section cut at its start
      "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n18446744073709551615 1 1 1\n",
      "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 1 1 1\n2 1 1 1\n1\n0 0 0 0.5 0.5\n$EndNodes\n",
      "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 1 1 1\n9 1 0 1\n1\n0 0 0\n$EndNodes\n",
      "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Elements\n1\n1 2 99 0 1 1 2 3\n$EndElements\n",
      "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n2 1 \"unterminated\n$EndPhysicalNames\n",
      "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$EndNodes\n",
      "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 1e999 0 0\n$EndNodes\n",
      "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n-5 0 0 0\n$EndNodes\n",
      // A line element whose two vertices coincide, as a boundary of triangles.
      kHead22 + "$Nodes\n3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n$EndNodes\n$Elements\n2\n1 1 2 0 1 1 1\n2 2 2 0 1 1 2 3\n$EndElements\n",
  };
  for (const auto& c : cases) {
    INFO(c);
    try {
      const auto d = parse_msh(c, "bad.msh");
      (void)to_mesh<Simplex<2>>(d);
    } catch (const IoError& e) {
      CHECK(std::string(e.what()).rfind("bad.msh", 0) == 0);
    }
  }
}
