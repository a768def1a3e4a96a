// Gmsh's high-order optimizer as a peer (src/meshing/gmsh_peer.hpp): a
// tangled degree-2 mesh of the unit cube goes through Gmsh in a child
// process and comes back with the same nodes, its fixed nodes in place; the
// timeout, crash and failure paths report what happened.

#include <doctest/doctest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "gmsh_peer.hpp"
#include "hom/measure/shape_measure.hpp"
#include "hom/mesh/elevate.hpp"
#include "hom/mesh/structured.hpp"
#include "hom/quality/mesh_quality.hpp"

using namespace hom;
using TetMesh = Mesh<Simplex<3>>;

namespace {

// Degree-2 tetrahedra of the unit cube (3 x 3 x 3 cells, 162 elements), its
// two interior vertices (1/3,1/3,1/3) and (2/3,2/3,2/3) pushed towards each
// other past the middle, which inverts elements around both.
TetMesh tangled_cube() {
  TetMesh m = elevate(structured_mesh<Simplex<3>>({3, 3, 3}), 2);
  for (int n = 0; n < m.num_nodes(); ++n) {
    const Eigen::Vector3d x = m.node(n);
    if ((x - Eigen::Vector3d::Constant(1.0 / 3)).norm() < 1e-12) m.node(n) = Eigen::Vector3d::Constant(0.58);
    if ((x - Eigen::Vector3d::Constant(2.0 / 3)).norm() < 1e-12) m.node(n) = Eigen::Vector3d::Constant(0.42);
  }
  return m;
}

int count_inverted(const TetMesh& m) { return mesh_quality(m, ShapeMeasure{}).inverted(); }

}  // namespace

TEST_CASE("gmsh peer: a tangled p = 2 cube comes back with its nodes, fixed ones in place") {
  TetMesh in = tangled_cube();
  // A boundary node without an entity (fixed, geometry unknown) must stay too.
  int unclassified = -1;
  for (int n = 0; n < in.num_nodes() && unclassified < 0; ++n)
    if (in.node_class(n).kind == NodeKind::on_entity) unclassified = n;
  REQUIRE(unclassified >= 0);
  in.node_class(unclassified) = NodeClass{NodeKind::fixed, std::nullopt, 0, {}};
  const int inverted_before = count_inverted(in);
  REQUIRE(inverted_before > 0);

  meshing::GmshPeerOptions o;
  o.time_limit_s = 60;
  const auto r = meshing::gmsh_high_order_optimize(in, o);
  INFO("status: " << r.status << ", note: " << r.note);
  REQUIRE(r.finished);
  CHECK(r.status == "ok");
  CHECK(r.tool == "gmsh");
  CHECK(r.version.rfind("4.", 0) == 0);
  CHECK(r.mode == 1);
  CHECK(r.time_s >= 0.0);
  CHECK(r.time_s <= r.wall_s);
  CHECK(r.peak_rss_mb > 0.0);
  CHECK(r.cpu_s > 0.0);
  REQUIRE(r.mesh.num_nodes() == in.num_nodes());
  REQUIRE(r.mesh.num_elements() == in.num_elements());
  CHECK(r.mesh.elements() == in.elements());

  int fixed = 0, moved_free = 0;
  double fixed_move = 0.0;
  for (int n = 0; n < in.num_nodes(); ++n) {
    const double d = (r.mesh.node(n) - in.node(n)).norm();
    if (in.node_class(n).kind == NodeKind::free) {
      moved_free += d > 1e-9;
    } else {
      ++fixed;
      fixed_move = std::max(fixed_move, d);
    }
    CHECK(r.mesh.node_class(n) == in.node_class(n));
  }
  CHECK(fixed > 0);
  CHECK(fixed_move < 1e-12);
  CHECK(r.max_fixed_displacement == doctest::Approx(fixed_move).epsilon(1e-6));
  CHECK(moved_free > 0);  // Gmsh worked on the tangled patch
  // The ideal (straight-sided snapshot) is the input's, so hom's quality of
  // the result is comparable with hom's own result on the same input.
  CHECK(r.mesh.ideal_coordinates() == in.ideal_coordinates());
  const auto q = mesh_quality(r.mesh, ShapeMeasure{}).quality_statistics();
  // Gmsh reports success on this input (its Bezier bound on the scaled
  // Jacobian of every element >= threshold_min = 0.1 > 0, a certificate of
  // validity), and it is deterministic, so hom's judge must find no inverted
  // element either; a wrong node order on the way in or out would show here.
  CHECK(r.note.empty());
  CHECK(q.inverted == 0);
  CHECK(std::isfinite(q.mean));
  CHECK(q.min >= 0.0);
  CHECK(q.max <= 1.0 + 1e-12);
}

TEST_CASE("gmsh peer: the peak memory reported is the child's, not the caller's") {
  // The caller holds 600 MB resident while Gmsh runs; a spawned child starts
  // in the caller's address space, so wait4's ru_maxrss would count them.
  std::vector<char> ballast(600u << 20);
  for (std::size_t i = 0; i < ballast.size(); i += 4096) ballast[i] = char(i);
  meshing::GmshPeerOptions o;
  o.time_limit_s = 60;
  const auto r = meshing::gmsh_high_order_optimize(tangled_cube(), o);
  INFO("status: " << r.status << ", peak " << r.peak_rss_mb << " MB");
  REQUIRE(r.finished);
  CHECK(r.peak_rss_mb > 1.0);
  CHECK(r.peak_rss_mb < 400.0);  // Gmsh on 162 degree-2 elements: tens of MB
  CHECK(ballast[4096] == char(4096));
}

TEST_CASE("gmsh peer: a run over its time limit is killed and reported") {
  meshing::GmshPeerOptions o;
  o.time_limit_s = 1e-3;  // far less than starting Gmsh takes
  const auto r = meshing::gmsh_high_order_optimize(tangled_cube(), o);
  CHECK_FALSE(r.finished);
  CHECK(r.status == "timeout");
  CHECK(r.wall_s >= 1e-3);
  CHECK(r.wall_s < 5.0);
  CHECK(r.mesh.num_nodes() == 0);
}

TEST_CASE("gmsh peer: a crashing or failing child is reported, not fatal") {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("hom_test_gmsh_peer_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path crash = dir / "crash.sh", fail = dir / "fail.sh";
  std::ofstream(crash) << "#!/bin/sh\nkill -SEGV $$\n";
  std::ofstream(fail) << "#!/bin/sh\necho 'no luck' >&2\nexit 3\n";
  fs::permissions(crash, fs::perms::owner_all);
  fs::permissions(fail, fs::perms::owner_all);
  const TetMesh in = tangled_cube();
  meshing::GmshPeerOptions o;
  o.time_limit_s = 20;

  o.helper = crash.string();
  auto r = meshing::gmsh_high_order_optimize(in, o);
  CHECK_FALSE(r.finished);
  CHECK(r.status.rfind("crashed (signal 11", 0) == 0);

  o.helper = fail.string();
  r = meshing::gmsh_high_order_optimize(in, o);
  CHECK_FALSE(r.finished);
  CHECK(r.status.rfind("failed: ", 0) == 0);
  CHECK(r.status.find("no luck") != std::string::npos);

  o.helper = (dir / "missing").string();
  r = meshing::gmsh_high_order_optimize(in, o);
  CHECK_FALSE(r.finished);
  CHECK(r.status.rfind("failed: ", 0) == 0);
  fs::remove_all(dir);

  o = {};
  o.mode = 5;
  CHECK_THROWS_AS(meshing::gmsh_high_order_optimize(in, o), std::invalid_argument);
}
