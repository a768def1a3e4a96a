// Chapter 6's a posteriori pipeline (src/curve): a linear mesh of a CAD model
// elevated and curved onto it. Checked against the geometry itself, not the
// pipeline's own report: edge nodes at Gauss-Lobatto fractions of the arc
// length of circles (angles from the circles' known centres), face nodes on
// the sphere at its radius, every boundary node on its model entity at its
// parameters, validity recomputed with hom::mesh_quality, and clear errors
// for a mesh that does not fit the model.

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "cad_mesher.hpp"
#include "curve_mesh.hpp"
#include "curve_models.hpp"
#include "refine_invalid.hpp"
#include "hom/measure/shape_measure.hpp"
#include "hom/mesh/facet.hpp"
#include "hom/mesh/flat_corners.hpp"
#include "hom/mesh/topology.hpp"
#include "hom/nodes/gauss_lobatto.hpp"
#include "hom/quality/mesh_quality.hpp"

using namespace hom;

namespace {

constexpr double pi = std::numbers::pi;

// The linear triangle mesh of a planar model (in z = 0) at a uniform size.
cad::CurvedMesh<Simplex<2>, 2> planar_triangles(const cad::CadModel& m, double size) {
  cad::CadMeshOptions mo;
  mo.size = size;
  return cad::mesh_cad<Simplex<2>, WarpBlend, 2>(m, mo);
}

cad::CurveOptions options(int p) {
  cad::CurveOptions o;
  o.p = p;
  o.threads = 1;
  return o;
}

// Every node classified on a model vertex, edge or face lies there at its
// parameters (evaluated here, not with the pipeline's check).
template <class MeshT>
void check_nodes_on_cad(const MeshT& mesh, const cad::CadModel& m, double tol) {
  int checked = 0;
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    const auto& c = mesh.node_class(i);
    if (!c.entity || c.kind == NodeKind::free) continue;
    Eigen::Vector3d x = Eigen::Vector3d::Zero();
    x.template head<MeshT::space_dim>() = mesh.node(i);
    CAPTURE(i);
    if (c.entity->dim == 0) {
      CHECK((m.vertex(c.entity->tag) - x).norm() <= tol);
    } else if (c.entity->dim == 1) {
      REQUIRE(c.num_params == 1);
      CHECK((m.curve(c.entity->tag).evaluate(c.params[0]) - x).norm() <= tol);
    } else {
      REQUIRE(c.entity->dim == 2);
      REQUIRE(c.num_params == 2);
      CHECK((m.surface(c.entity->tag).evaluate({c.params[0], c.params[1]}) - x).norm() <= tol);
    }
    ++checked;
  }
  CHECK(checked > 0);
}

// The nodes of every topological boundary facet of a volume or planar mesh
// are classified on the model (none is free).
template <class MeshT>
void check_boundary_classified(const MeshT& mesh) {
  using F = typename MeshT::family;
  const Topology<F> topo(mesh);
  int facets = 0;
  for (const auto& f : topo.boundary_facets()) {
    for (int local : facet_nodes<F>(mesh.degree(), f.local)) {
      const auto& c = mesh.node_class(mesh.elements()(local, f.element));
      CHECK(c.kind != NodeKind::free);
      REQUIRE(c.entity);
      CHECK(c.entity->dim < MeshT::dim);
    }
    ++facets;
  }
  CHECK(facets > 0);
}

// The plate's full circles (holes): centre and radius.
struct Circle {
  Eigen::Vector2d c;
  double r;
};
const std::array<Circle, 3> plate_holes = {{{{1.8, 1.8}, 0.7}, {{8.3, 2.0}, 0.9}, {{2.5, 6.2}, 0.8}}};

// For each element edge whose interior nodes lie on one of the plate's
// holes: the nodes are on the circle, and their angles divide the edge's
// angle at the Gauss-Lobatto fractions (1 + xi_j) / 2 in order.
template <class MeshT>
int check_gll_on_holes(const MeshT& mesh, int p) {
  using F = typename MeshT::family;
  const Eigen::VectorXd gll = gauss_lobatto_points(p);  // ascending in [-1, 1]
  const auto& layout = mesh.layout();
  int edges = 0;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    for (const auto& edge : F::edges()) {
      const int a = mesh.vertex(e, edge[0]), b = mesh.vertex(e, edge[1]);
      const Eigen::Vector2d xa = mesh.node(a).template head<2>(), xb = mesh.node(b).template head<2>();
      const Circle* hole = nullptr;
      for (const auto& h : plate_holes)
        if (std::abs((xa - h.c).norm() - h.r) < 1e-9 && std::abs((xb - h.c).norm() - h.r) < 1e-9) hole = &h;
      if (!hole) continue;
      // Interior nodes of this edge in order from a to b: lattice points
      // between the two vertices' lattice points.
      const auto la = layout.lattice(edge[0]), lb = layout.lattice(edge[1]);
      const double ta = std::atan2(xa[1] - hole->c[1], xa[0] - hole->c[0]);
      double tb = std::atan2(xb[1] - hole->c[1], xb[0] - hole->c[0]);
      tb = ta + std::remainder(tb - ta, 2 * pi);
      for (int j = 1; j < p; ++j) {
        auto l = la;
        for (std::size_t k = 0; k < l.size(); ++k) l[k] = (la[k] * (p - j) + lb[k] * j) / p;
        const int node = mesh.element(e)[layout.index_of(l)];
        const Eigen::Vector2d x = mesh.node(node).template head<2>();
        CHECK((x - hole->c).norm() == doctest::Approx(hole->r).epsilon(1e-12));
        const double t = ta + std::remainder(std::atan2(x[1] - hole->c[1], x[0] - hole->c[0]) - ta, 2 * pi);
        CHECK((t - ta) / (tb - ta) == doctest::Approx((1 + gll[j]) / 2).epsilon(1e-10));
      }
      ++edges;
    }
  }
  return edges;
}

// The cube with a spherical cavity meshed at size 1.62, 0.3 at the cavity's
// vertices.
cad::CurvedMesh<Simplex<3>, 3> cavity_mesh(const cad::CadModel& m) {
  cad::CadMeshOptions mo;
  mo.size = 1.62;
  for (int v = 1; v <= m.num_vertices(); ++v)
    mo.vertex_sizes[v] = (m.vertex(v) - Eigen::Vector3d::Constant(2.5)).norm() < 1.0 ? 0.3 : 1.62;
  return cad::mesh_cad<Simplex<3>>(m, mo);
}

}  // namespace

TEST_CASE("curved cube with a spherical cavity at p = 2 and 3: valid, boundary on the CAD") {
  const auto m = cad::cube_with_cavity_model();
  const auto linear = cavity_mesh(m);
  auto split = linear;  // what the pipeline curves (flat corners split)
  split_flat_corners(split);
  for (int p : {2, 3}) {
    CAPTURE(p);
    const auto r = cad::curve_mesh<Simplex<3>, 3>(m, linear, options(p));
    CHECK(r.valid);
    CHECK(r.conformity.ok);
    CHECK(r.mesh.degree() == p);
    CHECK(r.mesh.num_elements() == split.num_elements());
    // Independent validity check.
    const auto q = mesh_quality(r.mesh, ShapeMeasure{}, IdealKind::straight_sided);
    CHECK(q.inverted() == 0);
    CHECK(q.quality_statistics().min > 0.1);
    // Stages: linear, surface initial / optimized, volume initial / optimized.
    REQUIRE(r.stages.size() == 5);
    CHECK(r.stages[0].stage == "linear");
    CHECK(r.stages[0].quality.min == doctest::Approx(1.0));
    CHECK(r.stages.back().part == "volume");
    CHECK(r.stages.back().quality.inverted == 0);
    CHECK(r.stages[2].part == "surface");
    CHECK(r.stages[2].quality.inverted == 0);
    check_nodes_on_cad(r.mesh, m, 1e-10 * m.size());
    check_boundary_classified(r.mesh);
    // Every node of the cavity's boundary at the sphere's radius (exact
    // geometry, independent of the model's parameterization).
    int on_sphere = 0;
    for (int i = 0; i < r.mesh.num_nodes(); ++i) {
      const auto& c = r.mesh.node_class(i);
      if (c.entity && c.entity->dim == 2 && m.surface(c.entity->tag).type() == "sphere") {
        CHECK((r.mesh.node(i) - Eigen::Vector3d::Constant(2.5)).norm() == doctest::Approx(0.5).epsilon(1e-10));
        ++on_sphere;
      }
    }
    CHECK(on_sphere > 0);
  }
}

TEST_CASE("a cone's sharp apex at p = 3: the folds where it is thinner than the elements split, certified valid") {
  // Near the apex the cone is thinner than the elements: a tetrahedron's
  // two boundary edges from a node go round it, and curved on it they turn
  // the other way round than their chords (det D phi < 0 at the node,
  // whatever the free nodes do) unless the interior face between them is
  // split first (mesh/flat_corners.hpp). The apex's normal is the cone's
  // at each element's own angle around the axis (surface/unit_normal.hpp).
  const auto m = cad::cone_model(3.0, 10.0);
  REQUIRE(m.num_faces() == 2);
  cad::CadMeshOptions mo;
  mo.size = 2.0;
  const auto linear = cad::mesh_cad<Simplex<3>>(m, mo);
  auto o = options(3);
  o.certify = true;
  const auto r = cad::curve_mesh<Simplex<3>, 3>(m, linear, o);
  CHECK(r.flat_corners.faces_split > 0);
  CHECK(r.mesh.num_elements() > linear.num_elements());
  CHECK(r.valid);
  CHECK(r.inverted == 0);
  REQUIRE(r.certification);
  CHECK(r.certification->certified());
  CHECK(cad::failing_elements(r).elements.empty());
  check_nodes_on_cad(r.mesh, m, 1e-10 * m.size());
  // The conical face's nodes on the cone (exact geometry): at height z the
  // radius is 3 (1 - z / 10).
  int on_cone = 0;
  for (int i = 0; i < r.mesh.num_nodes(); ++i) {
    const auto& c = r.mesh.node_class(i);
    if (!c.entity || c.entity->dim != 2 || m.surface(c.entity->tag).type() != "cone") continue;
    const Eigen::Vector3d x = r.mesh.node(i);
    CHECK(x.head<2>().norm() == doctest::Approx(3.0 * (1.0 - x[2] / 10.0)).epsilon(1e-9));
    ++on_cone;
  }
  CHECK(on_cone > 0);
}

TEST_CASE("planar plate with holes: edge nodes at Gauss-Lobatto positions in arc length, valid") {
  const auto m = cad::plate_with_holes_model();
  REQUIRE(m.num_faces() == 1);
  const auto placed = cad::place_in_xy_plane(m);
  REQUIRE(placed);
  CHECK_FALSE(placed->moved);  // built in z = 0
  cad::CadMeshOptions mo;
  mo.size = 0.9;
  SUBCASE("triangles, p = 5") {
    const auto linear = cad::mesh_cad<Simplex<2>, WarpBlend, 2>(m, mo);
    const auto r = cad::curve_mesh<Simplex<2>, 2>(m, linear, options(5));
    CHECK(r.valid);
    CHECK(mesh_quality(r.mesh, ShapeMeasure{}, IdealKind::straight_sided).inverted() == 0);
    CHECK(check_gll_on_holes(r.mesh, 5) >= 12);
    check_nodes_on_cad(r.mesh, m, 1e-10 * m.size());
    check_boundary_classified(r.mesh);
  }
  SUBCASE("quadrilaterals, p = 3") {
    const auto linear = cad::mesh_cad<Cube<2>, WarpBlend, 2>(m, mo);
    const auto r = cad::curve_mesh<Cube<2>, 2>(m, linear, options(3));
    CHECK(r.valid);
    CHECK(mesh_quality(r.mesh, ShapeMeasure{}, IdealKind::straight_sided).inverted() == 0);
    CHECK(check_gll_on_holes(r.mesh, 3) >= 12);
    check_nodes_on_cad(r.mesh, m, 1e-10 * m.size());
  }
}

TEST_CASE("surface mesh of the NURBS sphere: face nodes on the sphere, valid on every patch") {
  const auto m = cad::nurbs_sphere_model(Eigen::Vector3d::Zero(), 0.5);
  cad::CadMeshOptions mo;
  mo.size = 0.2;
  const auto linear = cad::mesh_cad<Simplex<2>, WarpBlend, 3>(m, mo);
  const auto r = cad::curve_mesh<Simplex<2>, 3>(m, linear, options(4));
  CHECK(r.valid);
  REQUIRE(r.stages.size() == 3);
  CHECK(r.stages.back().part == "surface");
  CHECK(r.stages.back().quality.inverted == 0);
  int faces = 0;
  for (int i = 0; i < r.mesh.num_nodes(); ++i) {
    CHECK(r.mesh.node(i).norm() == doctest::Approx(0.5).epsilon(1e-10));
    const auto& c = r.mesh.node_class(i);
    REQUIRE(c.entity);
    faces += c.entity->dim == 2;
  }
  CHECK(faces > r.mesh.num_nodes() / 3);
  check_nodes_on_cad(r.mesh, m, 1e-10);
}

TEST_CASE("optimize_on_cad: face nodes slid in (u, v) come back, stay on the surface, edge nodes stay") {
  const auto m = cad::nurbs_sphere_model(Eigen::Vector3d::Zero(), 0.5);
  cad::CadMeshOptions mo;
  mo.size = 0.25;
  const auto linear = cad::mesh_cad<Simplex<2>, WarpBlend, 3>(m, mo);
  const auto curved = cad::curve_mesh<Simplex<2>, 3>(m, linear, options(3));
  REQUIRE(curved.valid);
  // Slide every face node along its surface by a deterministic (u, v) offset
  // of a twentieth of the parameter spacing; CAD-edge and vertex nodes stay.
  auto moved = curved.mesh;
  int slid = 0;
  for (int i = 0; i < moved.num_nodes(); ++i) {
    auto& c = moved.node_class(i);
    if (!(c.entity && c.entity->dim == 2 && c.num_params == 2)) continue;
    const auto s = m.surface(c.entity->tag);
    const double du = 0.005 * std::sin(7.0 * i), dv = 0.005 * std::cos(5.0 * i);
    c.params = {s.range(0).normalize(c.params[0] + du * (s.range(0).hi - s.range(0).lo)),
                s.range(1).normalize(c.params[1] + dv * (s.range(1).hi - s.range(1).lo))};
    moved.node(i) = s.evaluate({c.params[0], c.params[1]});
    ++slid;
  }
  REQUIRE(slid > 0);
  cad::CurveOptions o = options(2);  // the degree is the mesh's own (3)
  const auto r = cad::optimize_on_cad<Simplex<2>, 3>(m, moved, o);
  REQUIRE(r.stages.size() == 2);
  CHECK(r.stages.front().stage == "initial");
  CHECK(r.stages.back().stage == "optimized");
  CHECK(r.mesh.degree() == 3);
  CHECK(r.valid);
  // Quality is back to (at least nearly) the curved mesh's optimum, and
  // better than the slid start's.
  CHECK(r.stages.back().quality.min > r.stages.front().quality.min);
  CHECK(r.stages.back().quality.mean >= curved.stages.back().quality.mean - 1e-3);
  for (int i = 0; i < r.mesh.num_nodes(); ++i) {
    CHECK(r.mesh.node(i).norm() == doctest::Approx(0.5).epsilon(1e-10));
    const auto& c = r.mesh.node_class(i);
    if (c.entity && c.entity->dim < 2) CHECK((r.mesh.node(i) - curved.mesh.node(i)).norm() <= 1e-14);
  }
  check_nodes_on_cad(r.mesh, m, 1e-10);
  // (the extra parentheses keep the template's comma out of the macro's arguments)
  CHECK_THROWS_AS((cad::optimize_on_cad<Simplex<2>, 3>(m, linear, o)), std::invalid_argument);
}

TEST_CASE("certify: the planar pipeline's certificate is the result's, and decides validity") {
  const auto m = cad::plate_with_holes_model();
  const auto linear = planar_triangles(m, 0.9);
  const auto plain = cad::curve_mesh<Simplex<2>, 2>(m, linear, options(4));
  CHECK_FALSE(plain.certification);
  auto o = options(4);
  o.certify = true;
  const auto r = cad::curve_mesh<Simplex<2>, 2>(m, linear, o);
  REQUIRE(r.certification);
  const auto& c = *r.certification;
  CHECK_FALSE(c.on_surface);
  CHECK(c.valid + c.invalid + c.undecided == r.mesh.num_elements());
  // An independent certification of the mesh the pipeline returns.
  CertifyOptions co;
  co.max_depth = o.certify_depth;
  const auto again = certify_mesh(r.mesh, co);
  CHECK(again.valid == c.valid);
  CHECK(again.invalid == c.invalid);
  CHECK(again.undecided == c.undecided);
  CHECK(again.min_scaled_jacobian == doctest::Approx(c.min_scaled_jacobian));
  CHECK(r.valid == (r.inverted == 0 && r.conformity.ok && c.certified()));
  check_nodes_on_cad(r.mesh, m, 1e-10 * m.size());
}

TEST_CASE("refine_invalid: every failing element, why by the first reason that applies, a ball around each") {
  const auto m = cad::plate_with_holes_model();
  const auto linear = planar_triangles(m, 0.9);
  const auto valid = cad::curve_mesh<Simplex<2>, 2>(m, linear, options(2));
  REQUIRE(valid.valid);
  REQUIRE(cad::count_folded_at_nodes(valid) == 0);
  CHECK(cad::failing_elements(valid).why == cad::Failure::none);
  CHECK(cad::failing_elements(valid).elements.empty());
  const int n = valid.mesh.num_elements();
  REQUIRE(n > 10);

  auto r = valid;  // a fold at a node of element 5 only: no quadrature point sees it
  r.element_scaled_jacobian[5] = -0.1;
  CHECK(cad::folded_at_node(r, 5));
  CHECK(cad::failing_elements(r).why == cad::Failure::folded_at_node);
  CHECK(cad::failing_elements(r).elements == std::vector<int>{5});
  r.certification.emplace();  // certified: elements 2 and 7 not
  r.certification->invalid = 2;
  r.certification->uncertified = {2, 7};
  r.valid = false;
  CHECK(cad::failing_elements(r).why == cad::Failure::uncertified);
  CHECK(cad::failing_elements(r).elements == std::vector<int>{2, 5, 7});  // every reason's elements
  r.element_scaled_jacobian[5] = 0.3;
  CHECK(cad::failing_elements(r).elements == std::vector<int>{2, 7});
  r.conformity.ok = false;  // a node off the CAD comes first, and blames no element of its own
  CHECK(cad::failing_elements(r).why == cad::Failure::off_cad);
  CHECK(cad::failing_elements(r).elements == std::vector<int>{2, 7});
  r.inverted = 2;  // inverted at quadrature points comes before everything
  r.element_valid[n - 1] = false;
  r.element_valid[3] = false;
  CHECK(cad::failing_elements(r).why == cad::Failure::inverted);
  CHECK(cad::failing_elements(r).elements == std::vector<int>{2, 3, 7, n - 1});
  r.certification.reset();
  r.conformity.ok = true;
  CHECK(cad::failing_elements(r).elements == std::vector<int>{3, n - 1});

  const auto balls = cad::balls_around(valid.mesh, {3, n - 1});
  REQUIRE(balls.size() == 2);
  for (int k = 0; k < 2; ++k) {
    const Eigen::MatrixXd x = valid.mesh.element_coordinates(k == 0 ? 3 : n - 1);
    const Eigen::Vector2d centroid = x.rowwise().mean();
    CHECK((balls[k].center.head<2>() - centroid).norm() < 1e-12);
    CHECK(balls[k].center.z() == 0.0);
    double width = 0.0, reach = 0.0;  // widest pair of nodes; farthest node from the centroid
    for (int i = 0; i < int(x.cols()); ++i) {
      reach = std::max(reach, (x.col(i) - centroid).norm());
      for (int j = 0; j < int(x.cols()); ++j) width = std::max(width, (x.col(i) - x.col(j)).norm());
    }
    CHECK(balls[k].radius == doctest::Approx(width));
    CHECK(balls[k].radius >= reach);  // the ball holds the whole element
    CHECK(balls[k].size == doctest::Approx(width / 2));
  }
}

TEST_CASE("refine_around: the balls added; the earlier mesh's sizes kept only where they would lower the floor") {
  const auto m = cad::plate_with_holes_model();
  const auto linear = planar_triangles(m, 0.9);
  const auto balls = cad::balls_around(linear, {0, 1});
  REQUIRE(balls.size() == 2);
  const double finest = std::min(balls[0].size, balls[1].size);
  cad::CadMeshOptions o;
  o.size_min = finest / 2;  // the balls above the floor: Gmsh's floor stays
  o.size_from_curvature = 12;
  auto added = balls;
  CHECK_FALSE(cad::refine_around(o, added, linear));
  CHECK(o.local_sizes.size() == 2);
  CHECK(o.earlier_sizes.empty());
  o = {};
  o.size_min = 2 * finest;  // now below it, but without curvature sizing the floor alone is lowered
  added = balls;
  CHECK_FALSE(cad::refine_around(o, added, linear));
  CHECK(o.earlier_sizes.empty());
  o = {};
  o.size_min = 2 * finest;
  o.size_from_curvature = 12;
  added = balls;
  CHECK(cad::refine_around(o, added, linear));
  CHECK(cad::balls_lower_curvature_floor(o));
  CHECK(o.local_sizes.size() == 2);
  const auto first = cad::size_map(linear);
  REQUIRE(o.earlier_sizes.points.size() == first.points.size());
  CHECK(o.earlier_sizes.sizes == first.sizes);
  // A later, finer mesh does not replace the first mesh's sizes (it holds the balls' sizes).
  const auto finer = planar_triangles(m, 0.45);
  added = balls;
  CHECK(cad::refine_around(o, added, finer));
  CHECK(o.earlier_sizes.sizes == first.sizes);
  // The same places failed again: those balls get half the sizes of the
  // earlier balls they lie in; a ball elsewhere keeps its own.
  CHECK(o.local_sizes.size() == 4);
  for (int k = 0; k < 2; ++k) {
    double expected = balls[k].size;
    for (const auto& b : balls)
      if ((balls[k].center - b.center).norm() < b.radius) expected = std::min(expected, b.size / 2);
    CHECK(added[k].size == doctest::Approx(expected));
    CHECK(added[k].size <= balls[k].size / 2);
  }
  std::vector<cad::LocalSize> elsewhere = {balls[0]};
  elsewhere[0].center += Eigen::Vector3d(100, 0, 0);
  CHECK(cad::refine_around(o, elsewhere, finer));
  CHECK(elsewhere[0].size == balls[0].size);
}

TEST_CASE("curve_refining_invalid: tries until nothing fails, at most 1 + N, a failed meshing ends them") {
  const auto m = cad::plate_with_holes_model();
  const auto first = planar_triangles(m, 0.9);
  const auto ball = cad::balls_around(first, {0});
  using Linear = cad::CurvedMesh<Simplex<2>, 2>;
  struct Log {
    int tries = 0;
    std::vector<int> curved, meshed;  // element counts of the meshes curved, and of those remeshed
    std::vector<bool> last;
    std::vector<int> next_try;
    std::vector<std::size_t> balls_in_options;
    int final_elements = 0;
  };
  // A curving that fails (one ball) on its first `failures` tries; meshing
  // fails at try `meshing_fails_at`.
  auto run = [&](int extra_tries, int failures, int meshing_fails_at) {
    Log log;
    cad::CadMeshOptions o;
    auto linear = first;
    auto curve = [&](const Linear& mesh, bool last) {
      log.curved.push_back(mesh.num_elements());
      log.last.push_back(last);
      return int(log.last.size()) <= failures ? ball : std::vector<cad::LocalSize>{};
    };
    auto remesh = [&](const cad::Refinement& r) -> std::optional<Linear> {
      log.next_try.push_back(r.next_try);
      log.balls_in_options.push_back(r.options.local_sizes.size());
      if (r.next_try == meshing_fails_at) return std::nullopt;
      auto mesh = planar_triangles(m, 0.9 / r.next_try);
      log.meshed.push_back(mesh.num_elements());
      return mesh;
    };
    log.tries = cad::curve_refining_invalid(o, linear, extra_tries, curve, remesh);
    log.final_elements = linear.num_elements();
    return log;
  };
  SUBCASE("no tries after the first: it is the last") {
    const auto log = run(0, 5, -1);
    CHECK(log.tries == 1);
    CHECK(log.last == std::vector<bool>{true});
    CHECK(log.next_try.empty());
  }
  SUBCASE("valid on the second mesh: two tries, neither the last allowed") {
    const auto log = run(3, 1, -1);
    CHECK(log.tries == 2);
    CHECK(log.last == std::vector<bool>{false, false});
    CHECK(log.next_try == std::vector<int>{2});
    CHECK(log.balls_in_options == std::vector<std::size_t>{1});
    REQUIRE(log.meshed.size() == 1);
    CHECK(log.curved == std::vector<int>{first.num_elements(), log.meshed[0]});
    CHECK(log.final_elements == log.meshed[0]);
  }
  SUBCASE("never valid: 1 + N tries, the balls of each kept, only the last one last") {
    const auto log = run(2, 5, -1);
    CHECK(log.tries == 3);
    CHECK(log.last == std::vector<bool>{false, false, true});
    CHECK(log.next_try == std::vector<int>{2, 3});
    CHECK(log.balls_in_options == std::vector<std::size_t>{1, 2});
    REQUIRE(log.meshed.size() == 2);
    CHECK(log.curved == std::vector<int>{first.num_elements(), log.meshed[0], log.meshed[1]});
    CHECK(log.final_elements == log.meshed[1]);
  }
  SUBCASE("meshing fails at try 3: the tries end at try 2, whose mesh stays") {
    const auto log = run(3, 5, 3);
    CHECK(log.tries == 2);
    CHECK(log.last == std::vector<bool>{false, false});
    CHECK(log.next_try == std::vector<int>{2, 3});
    REQUIRE(log.meshed.size() == 1);
    CHECK(log.final_elements == log.meshed[0]);
  }
}

// Two nodes on one face whose parameters are within a tenth of the face's
// parameter box: no periodic seam between them.
static bool near_in_parameters(const cad::CadModel& m, const NodeClass& a, const NodeClass& b) {
  const auto s = m.surface(a.entity->tag);
  for (int k = 0; k < 2; ++k)
    if (std::abs(a.params[k] - b.params[k]) > 0.1 * (s.range(k).hi - s.range(k).lo)) return false;
  return true;
}

// A fold site: a face-interior node used by one element only (a surface
// triangle's interior node, or at p = 3 the face node of a boundary
// tetrahedron's triangle), on a CAD face, that `accept`s it, and a vertex of
// its element on the same face, near it in parameters.
struct FoldSite {
  int element = -1, node = -1, vertex = -1;
};

template <class MeshT, class Accept>
FoldSite fold_site(const cad::CadModel& m, const MeshT& mesh, Accept accept) {
  std::vector<int> uses(mesh.num_nodes(), 0);
  for (int e = 0; e < mesh.num_elements(); ++e)
    for (int i = 0; i < mesh.nodes_per_element(); ++i) ++uses[mesh.elements()(i, e)];
  for (int e = 0; e < mesh.num_elements(); ++e)
    for (int i = 0; i < mesh.nodes_per_element(); ++i) {
      const int g = mesh.elements()(i, e);
      const auto& cl = mesh.node_class(g);
      if (uses[g] != 1 || !cl.entity || cl.entity->dim != 2 || cl.num_params != 2 || !accept(g)) continue;
      for (int v = 0; v <= MeshT::dim; ++v) {
        const auto& cv = mesh.node_class(mesh.vertex(e, v));
        if (cv.entity && cv.entity->dim == 2 && cv.entity->tag == cl.entity->tag && near_in_parameters(m, cl, cv))
          return {e, g, mesh.vertex(e, v)};
      }
    }
  return {};
}

// The mesh with the site's node pushed in (u, v) past its vertex, by half
// their distance again: its element folds on the CAD face.
template <class MeshT>
MeshT folded_at(const cad::CadModel& m, MeshT mesh, const FoldSite& site) {
  auto& cl = mesh.node_class(site.node);
  const auto& cv = mesh.node_class(site.vertex);
  const auto s = m.surface(cl.entity->tag);
  for (int a = 0; a < 2; ++a) cl.params[a] = s.range(a).normalize(cv.params[a] + 1.5 * (cv.params[a] - cl.params[a]));
  mesh.node(site.node) = s.evaluate({cl.params[0], cl.params[1]});
  return mesh;
}

TEST_CASE("certify: a surface element folded in its face's (u, v) is certified invalid, the others valid") {
  const auto m = cad::nurbs_sphere_model(Eigen::Vector3d::Zero(), 0.5);
  cad::CadMeshOptions mo;
  mo.size = 0.25;
  const auto linear = cad::mesh_cad<Simplex<2>, WarpBlend, 3>(m, mo);
  const auto curved = cad::curve_mesh<Simplex<2>, 3>(m, linear, options(3));
  REQUIRE(curved.valid);
  cad::CurveOptions o = options(3);
  o.certify = true;
  o.optimize_surface = false;  // certify what is given: no surface optimization, so no repair either
  const auto good = cad::optimize_on_cad<Simplex<2>, 3>(m, curved.mesh, o);
  REQUIRE(good.certification);
  CHECK(good.certification->on_surface);
  CHECK(good.certification->reason == RepairStop::certified);
  CHECK(good.certification->valid == good.mesh.num_elements());
  CHECK(good.valid);

  // The interior node of a triangle on a face, away from edges and poles,
  // pushed in (u, v) past a vertex of its element: the element folds.
  const auto site = fold_site(m, curved.mesh, [&](int g) { return std::abs(curved.mesh.node(g).z()) < 0.3; });
  REQUIRE(site.element >= 0);
  const int element = site.element;
  const auto folded = folded_at(m, curved.mesh, site);
  const auto bad = cad::optimize_on_cad<Simplex<2>, 3>(m, folded, o);
  REQUIRE(bad.certification);
  const auto& u = bad.certification->uncertified;
  CHECK(std::find(u.begin(), u.end(), element) != u.end());
  CHECK(bad.certification->reason == RepairStop::not_repaired);
  CHECK(bad.certification->valid + int(u.size()) == bad.mesh.num_elements());
  CHECK_FALSE(bad.valid);
}

TEST_CASE("skip_volume_if_faces_uncertified: a folded CAD-face triangle skips the volume stage, its element blamed") {
  const auto m = cad::cube_with_cavity_model();
  const auto linear = cavity_mesh(m);
  const auto curved = cad::curve_mesh<Simplex<3>, 3>(m, linear, options(3));
  REQUIRE(curved.valid);
  cad::CurveOptions o = options(3);
  o.certify = true;
  o.optimize_surface = false;  // no surface optimization, so no repair of the face either
  o.skip_volume_if_faces_uncertified = true;
  o.max_iterations = 3;  // whether the volume stage runs is what counts here, not where it converges
  const auto good = cad::optimize_on_cad<Simplex<3>, 3>(m, curved.mesh, o);
  CHECK(good.volume_skipped_for.empty());  // certified faces: the volume stage runs
  CHECK(good.stages.back().stage == "optimized");
  REQUIRE(good.certification);
  CHECK(good.valid == good.certification->certified());

  // The face-interior node of a boundary triangle on one of the cube's planes
  // (at p = 3 used by one tetrahedron only), pushed in (u, v) past a vertex
  // of the triangle: the triangle folds on its CAD face.
  const auto site = fold_site(m, curved.mesh, [&](int g) {
    return m.surface(curved.mesh.node_class(g).entity->tag).type() == "plane";
  });
  REQUIRE(site.element >= 0);
  const int element = site.element;
  const auto folded = folded_at(m, curved.mesh, site);

  const auto skipped = cad::optimize_on_cad<Simplex<3>, 3>(m, folded, o);
  const auto& blamed = skipped.volume_skipped_for;
  CHECK(std::find(blamed.begin(), blamed.end(), element) != blamed.end());
  CHECK(std::is_sorted(blamed.begin(), blamed.end()));
  CHECK(std::adjacent_find(blamed.begin(), blamed.end()) == blamed.end());
  for (int e : blamed) {  // each has a boundary triangle: some node on a CAD face
    bool on_face = false;
    for (int i = 0; i < skipped.mesh.nodes_per_element(); ++i) {
      const auto& c = skipped.mesh.node_class(skipped.mesh.elements()(i, e));
      on_face = on_face || (c.entity && c.entity->dim == 2);
    }
    CHECK(on_face);
  }
  CHECK(int(blamed.size()) < skipped.mesh.num_elements() / 10);  // the fold's, not the whole mesh
  CHECK_FALSE(skipped.valid);
  CHECK_FALSE(skipped.certification);  // no volume certificate: that stage did not run
  CHECK(skipped.stages.back().part == "volume");
  CHECK(skipped.stages.back().stage == "initial");
  const auto failing = cad::failing_elements(skipped);
  CHECK(failing.why == cad::Failure::faces_uncertified);
  CHECK(failing.elements == blamed);

  o.skip_volume_if_faces_uncertified = false;  // the last try: the volume stage runs all the same
  const auto ran = cad::optimize_on_cad<Simplex<3>, 3>(m, folded, o);
  CHECK(ran.volume_skipped_for.empty());
  CHECK(ran.stages.back().stage == "optimized");
  CHECK(ran.certification);
  CHECK(cad::failing_elements(ran).why != cad::Failure::faces_uncertified);
}

TEST_CASE("a mesh that does not fit the model is an error naming what is wrong") {
  const auto m = cad::plate_with_holes_model();
  auto linear = planar_triangles(m, 2.0);
  SUBCASE("an element on a face the model lacks") {
    linear.element_entities()[3] = 42;
    try {
      cad::curve_mesh<Simplex<2>, 2>(m, linear, options(2));
      FAIL("no error");
    } catch (const cad::MeshingError& e) {
      const std::string what = e.what();
      CHECK(what.find("element 3") != std::string::npos);
      CHECK(what.find("face 42") != std::string::npos);
    }
  }
  SUBCASE("a boundary node classified on no model entity") {
    const Topology<Simplex<2>> topo(linear);
    const auto f = topo.boundary_facets().front();
    const int node = linear.vertex(f.element, facet_vertices<Simplex<2>>(f.local)[0]);
    linear.node_class(node) = NodeClass{NodeKind::fixed, std::nullopt, 0, {}};
    try {
      cad::curve_mesh<Simplex<2>, 2>(m, linear, options(2));
      FAIL("no error");
    } catch (const cad::MeshingError& e) {
      CHECK(std::string(e.what()).find("node " + std::to_string(node)) != std::string::npos);
    }
  }
  CHECK_THROWS_AS((cad::curve_mesh<Simplex<2>, 2>(m, linear, options(1))), std::invalid_argument);
}

namespace {

// The faces of `m` that are B-spline surfaces periodic in some parameter
// (for hom); for each, the seam closes (S at lo and at hi agree) and the
// surface continues periodically beyond the range, value and derivatives
// (OpenCASCADE would extrapolate a surface that is only closed).
int periodic_bspline_faces(const cad::CadModel& m) {
  int found = 0;
  for (int f = 1; f <= m.num_faces(); ++f) {
    const auto s = m.surface(f);
    if (s.type() != "bspline") continue;
    found += s.range(0).periodic || s.range(1).periodic;  // a face periodic in both parameters counts once
    for (int k = 0; k < 2; ++k) {
      const ParameterRange r = s.range(k), other = s.range(1 - k);
      if (!r.periodic) continue;
      CAPTURE(f);
      CAPTURE(k);
      const double tol = 1e-9 * s.size();
      for (double t : {0.1, 0.45, 0.8}) {
        Eigen::Vector2d a;
        a[1 - k] = other.lo + 0.37 * other.length();
        a[k] = r.lo + t * r.length();
        Eigen::Vector2d b = a, lo = a, hi = a;
        b[k] += r.length();
        lo[k] = r.lo;
        hi[k] = r.hi;
        CHECK((s.evaluate(a) - s.evaluate(b)).norm() <= tol);
        CHECK((s.derivatives(a) - s.derivatives(b)).norm() <= 1e-9 * s.derivatives(a).norm());
        CHECK((s.evaluate(lo) - s.evaluate(hi)).norm() <= 1e-7 * s.size());
      }
    }
  }
  return found;
}

}  // namespace

TEST_CASE("propeller_model: one solid, blades fused to the hub, lofted blade faces periodic around their sections") {
  for (int blades : {3, 4}) {
    CAPTURE(blades);
    const auto m = cad::propeller_model(blades);
    CHECK(m.num_solids() == 1);
    CHECK(m.num_faces() == 3 + 2 * blades);  // hub side and ends; each blade's loft face and flat tip
    CHECK(periodic_bspline_faces(m) == blades);
  }
  CHECK_THROWS_AS(cad::propeller_model(1), std::invalid_argument);
}

TEST_CASE("wing_domain_model: a box around a NACA 0012 half-wing whose sides meet at edges, not at a seam") {
  const auto m = cad::wing_domain_model();
  CHECK(m.num_solids() == 1);
  // The box's 6 faces (z = 0 with the root's hole) and the wing's upper and
  // lower loft faces and flat tip; no closed surface.
  CHECK(m.num_faces() == 9);
  CHECK(periodic_bspline_faces(m) == 0);
  // The wing's surface: every point of the root section lies on the box's
  // face z = 0 and the sharp trailing edge at (1, 0, 0) is a model vertex.
  bool trailing_edge = false;
  for (int v = 1; v <= m.num_vertices(); ++v) trailing_edge |= (m.vertex(v) - Eigen::Vector3d(1, 0, 0)).norm() < 1e-9;
  CHECK(trailing_edge);
  CHECK_THROWS_AS(cad::wing_domain_model(0.0), std::invalid_argument);
}
