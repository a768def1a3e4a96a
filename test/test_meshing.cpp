// Meshing through Gmsh's library (src/meshing): the cube with a spherical
// cavity of thesis section 4.3.1, reading a Gmsh model into a hom Mesh, and
// recognizing analytic geometry from Gmsh's entities.

#include <doctest/doctest.h>

#include <gmsh.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <set>
#include <string>

#include "cube_with_cavity.hpp"
#include "gmsh_model.hpp"
#include "hom/geometry/curve_boundary.hpp"
#include "hom/measure/shape_measure.hpp"
#include "hom/mesh/elevate.hpp"
#include "hom/mesh/flat_corners.hpp"
#include "hom/mesh/topology.hpp"
#include "hom/optimize/optimize.hpp"
#include "hom/quality/certify.hpp"

using namespace hom;

namespace {

double signed_volume(const Mesh<Simplex<3>>& m, int e) {
  const Eigen::Vector3d a = m.node(m.vertex(e, 0));
  Eigen::Matrix3d J;
  for (int k = 0; k < 3; ++k) J.col(k) = m.node(m.vertex(e, k + 1)) - a;
  return J.determinant() / 6.0;
}

}  // namespace

TEST_CASE("cube with a spherical cavity: linear mesh") {
  const auto c = meshing::cube_with_cavity();
  const auto& m = c.mesh;
  CHECK(m.degree() == 1);
  // "About 1441 elements" (thesis); the exact count is Gmsh's.
  CHECK(m.num_elements() > 1200);
  CHECK(m.num_elements() < 1700);

  // Deterministic: a second run gives the same mesh.
  const auto again = meshing::cube_with_cavity();
  REQUIRE(again.mesh.num_nodes() == m.num_nodes());
  REQUIRE(again.mesh.num_elements() == m.num_elements());
  CHECK(again.mesh.elements() == m.elements());
  CHECK((again.mesh.nodes() - m.nodes()).norm() == 0.0);

  // Valid, and the volume is the cube minus the inscribed polyhedron of the
  // sphere (slightly more than 125 - 4/3 pi r^3, less than 125).
  double volume = 0.0;
  for (int e = 0; e < m.num_elements(); ++e) {
    const double v = signed_volume(m, e);
    CHECK(v > 0.0);
    volume += v;
  }
  const double ball = 4.0 / 3.0 * std::numbers::pi * 0.125;
  CHECK(volume > 125.0 - ball);
  CHECK(volume < 125.0 - 0.8 * ball);

  // Every topological boundary face is classified, on the sphere or a face.
  const Topology<Simplex<3>> topo(m);
  CHECK(m.boundary_facets().size() == topo.boundary_facets().size());
  std::set<int> tags;
  for (const auto& f : m.boundary_facets()) {
    tags.insert(f.entity_tag);
    for (int v : f.vertices) {
      const Eigen::Vector3d x = m.node(v);
      if (f.entity_tag == c.sphere_tag) {
        CHECK((x - c.center).norm() == doctest::Approx(c.radius).epsilon(1e-9));
      } else {
        bool on_face = false;
        for (int a = 0; a < 3; ++a)
          for (int s = 0; s < 2; ++s)
            if (f.entity_tag == c.face_tags[2 * a + s]) on_face = std::abs(x[a] - 5.0 * s) < 1e-12;
        CHECK(on_face);
      }
    }
  }
  CHECK(tags.size() == 7);
  std::set<std::string> names;
  for (const auto& g : m.physical_groups()) names.insert(g.name);
  CHECK(names == std::set<std::string>{"cavity", "walls", "domain"});

  // Geometry: the sphere, the six planes, and the twelve straight edges.
  CHECK(c.geometry.surface(c.sphere_tag) != nullptr);
  for (int t : c.face_tags) CHECK(c.geometry.surface(t) != nullptr);
  CHECK(c.geometry.curves().size() >= 12);
}

TEST_CASE("cube with a spherical cavity: elevated and curved") {
  const auto c = meshing::cube_with_cavity({.cube_size = 2.5, .sphere_size = 0.4});
  for (int p : {2, 4}) {
    auto mesh = elevate(c.mesh, p);
    const auto before = mesh;
    const auto report = curve_boundary(mesh, c.geometry);
    CHECK(report.without_geometry == 0);
    CHECK(report.max_displacement > 0.0);
    for (const auto& f : mesh.boundary_facets())
      for (int i : mesh.facet_node_ids(f)) {
        const Eigen::Vector3d x = mesh.node(i);
        if (f.entity_tag == c.sphere_tag) CHECK((x - c.center).norm() == doctest::Approx(c.radius).epsilon(1e-12));
      }
    for (int i = 0; i < mesh.num_nodes(); ++i)
      if (mesh.node_class(i).kind == NodeKind::free) CHECK((mesh.node(i) - before.node(i)).norm() == 0.0);
  }
}

TEST_CASE("coarse cube with a cavity: certified valid at p = 2 once its flat corners are split") {
  // Gmsh's coarse mesh has a tetrahedron with two faces on the sphere: at
  // the two vertices of their common edge, all three edges lie on the
  // sphere, so det D phi there is set by the curved boundary alone
  // (mesh/flat_corners.hpp).
  const auto c = meshing::cube_with_cavity({.cube_size = 2.0, .sphere_size = 0.3});
  const auto corners = find_flat_corners(c.mesh);
  REQUIRE(!corners.empty());
  for (const auto& k : corners) CHECK(k.entity == c.sphere_tag);
  auto certified_after_optimization = [&](const Mesh<Simplex<3>>& linear) {
    auto mesh = elevate(linear, 2);
    curve_boundary(mesh, c.geometry);
    OptimizeOptions opt;
    opt.p_continuation = true;
    opt.threads = 1;
    optimize<ShapeMeasure, DefaultExactness>(mesh, opt);
    return certify_mesh(mesh);
  };
  CHECK(certified_after_optimization(c.mesh).invalid > 0);  // a flat corner's element

  auto split = c.mesh;
  const auto s = split_flat_corners(split);
  CHECK(s.corners == int(corners.size()));
  CHECK(s.edges_split > 0);
  CHECK(find_flat_corners(split).empty());
  const auto cert = certified_after_optimization(split);
  CHECK(cert.invalid == 0);
  CHECK(cert.undecided == 0);
  CHECK(cert.valid == split.num_elements());
}

TEST_CASE("analytic geometry and mesh from a Gmsh model") {
  const meshing::GmshSession session;
  gmsh::model::add("test_recognize");
  gmsh::model::occ::addSphere(1.0, 2.0, 3.0, 0.75);
  gmsh::model::occ::addBox(4, 0, 0, 1, 2, 3);
  gmsh::model::occ::synchronize();
  gmsh::option::setNumber("Mesh.MeshSizeMax", 0.5);
  gmsh::model::mesh::generate(3);
  const auto geometry = meshing::analytic_geometry_from_gmsh_model();
  int spheres = 0, planes = 0;
  gmsh::vectorpair surfaces;
  gmsh::model::getEntities(surfaces, 2);
  for (const auto& [d, tag] : surfaces) {
    std::string type;
    gmsh::model::getType(2, tag, type);
    const AnySurface* g = geometry.surface(tag);
    REQUIRE(g != nullptr);
    // A node of the entity's mesh lies on the recognized geometry.
    std::vector<std::size_t> nodes;
    std::vector<double> x, uv;
    gmsh::model::mesh::getNodes(nodes, x, uv, 2, tag, true, false);
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      const Eigen::Vector3d p(x[3 * i], x[3 * i + 1], x[3 * i + 2]);
      CHECK((g->evaluate(g->project(p)) - p).norm() < 1e-9);
    }
    spheres += type == "Sphere";
    planes += type == "Plane";
  }
  CHECK(spheres == 1);
  CHECK(planes == 6);

  const auto mesh = meshing::linear_mesh_from_gmsh_model<Simplex<3>>();
  std::vector<int> types;
  std::vector<std::vector<std::size_t>> tags, nodes;
  gmsh::model::mesh::getElements(types, tags, nodes, 3);
  std::size_t tets = 0;
  for (const auto& t : tags) tets += t.size();
  CHECK(std::size_t(mesh.num_elements()) == tets);
  gmsh::model::remove();
}

namespace {
[[noreturn]] void throw_as_gmsh_does(const char* message) { throw std::string(message); }
}  // namespace

// A Gmsh error inside its OpenMP meshing loop reaches std::terminate (see
// GmshSession). The child process stands for `hom curve`: it opens a session,
// lets a std::string escape a noexcept function as Gmsh's loop does, and must
// exit with status 1 and one line naming the subject and Gmsh's message.
TEST_CASE("a Gmsh error that reaches std::terminate exits with status 1 and names the model") {
  int err[2];
  REQUIRE(pipe(err) == 0);
  std::fflush(stdout);  // (the child flushes its copy of the buffer on exit)
  const pid_t child = fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    dup2(err[1], 2);
    const meshing::GmshSession session({false, 1, "part.step"});
    []() noexcept { throw_as_gmsh_does("Impossible to mesh periodic surface 1"); }();
    std::_Exit(7);  // not reached: std::terminate exits
  }
  close(err[1]);
  std::string message;
  char buffer[256];
  for (ssize_t n; (n = read(err[0], buffer, sizeof buffer)) > 0;) message.append(buffer, static_cast<std::size_t>(n));
  close(err[0]);
  int status = 0;
  REQUIRE(waitpid(child, &status, 0) == child);
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 1);
  CHECK(message.find("hom: part.step: Gmsh failed: Impossible to mesh periodic surface 1") == 0);
}
