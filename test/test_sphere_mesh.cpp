// Mesh builders of the hollow-sphere and hexahedral-ring examples
// (bench/sphere_mesh.hpp): counts, orientation, geometry of the curved
// meshes, validity before tangling, and that a small D.4-like hexahedral
// case untangles.

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <set>

#include "../bench/sphere_mesh.hpp"
#include "hom/measure/shape_measure.hpp"
#include "hom/optimize/optimize.hpp"
#include "hom/quadrature/quadrature_policy.hpp"
#include "hom/quality/mesh_quality.hpp"

namespace {

using hom::bench::HexMesh;
using hom::bench::TetMesh;

/// Volume of a (curved) mesh: sum over elements of the integral of det D phi,
/// with a Gauss rule exact for det D phi (degree Dim (p - 1) on simplices,
/// Dim p - 1 per axis on cubes).
template <class MeshT>
double mesh_volume(const MeshT& mesh) {
  using Family = typename MeshT::family;
  const int p = mesh.degree();
  const int exactness = Family::is_simplex ? 3 * (p - 1) : 3 * p - 1;
  const auto& rule = hom::cached_gauss_rule<Family>(std::max(exactness, 1));
  double v = 0.0;
  for (int e = 0; e < mesh.num_elements(); ++e)
    for (int q = 0; q < rule.size(); ++q) v += rule.weights[q] * mesh.jacobian(e, rule.points[q]).determinant();
  return v;
}

/// Number of distinct sorted vertex tuples of size K over the elements'
/// sub-simplices (edges: K = 2, faces: K = 3) of a tetrahedral mesh.
template <int K>
std::size_t count_sub_simplices(const TetMesh& mesh) {
  std::set<std::array<int, K>> s;
  for (int e = 0; e < mesh.num_elements(); ++e)
    for (int mask = 0; mask < 16; ++mask) {
      if (__builtin_popcount(unsigned(mask)) != K) continue;
      std::array<int, K> t{};
      int k = 0;
      for (int v = 0; v < 4; ++v)
        if (mask & (1 << v)) t[k++] = mesh.vertex(e, v);
      std::sort(t.begin(), t.end());
      s.insert(t);
    }
  return s.size();
}

/// Volume enclosed by the boundary facets of a curved tetrahedral mesh,
/// (1/3) sum over facets of the integral of x . (x_s x x_t) (divergence
/// theorem), with a triangle rule exact for it (degree 3p - 2). On a
/// conforming mesh it equals the volume integral up to round-off: an
/// independent check of mesh_volume and of the facets' outward orientation.
double boundary_volume(const TetMesh& mesh) {
  using Tet = hom::Simplex<3>;
  const int p = mesh.degree();
  const auto& rule = hom::cached_gauss_rule<hom::Simplex<2>>(3 * p - 2);
  double v = 0.0;
  for (const auto& f : mesh.boundary_facets()) {
    const auto lv = hom::facet_vertices<Tet>(f.local_facet);
    const Eigen::Vector3d a = Tet::vertex(lv[0]), ds = Tet::vertex(lv[1]) - a, dt = Tet::vertex(lv[2]) - a;
    for (int q = 0; q < rule.size(); ++q) {
      const Eigen::Vector3d xi = a + rule.points[q][0] * ds + rule.points[q][1] * dt;
      const Eigen::Matrix3d J = mesh.jacobian(f.element, xi);
      v += rule.weights[q] * mesh.map(f.element, xi).dot((J * ds).cross(J * dt)) / 3.0;
    }
  }
  return v;
}

int inverted(const auto& mesh) { return hom::mesh_quality(mesh, hom::ShapeMeasure{}).inverted(); }

}  // namespace

TEST_CASE("hollow sphere: the linear mesh has the thesis's counts and tiles the polyhedral shell") {
  const auto hs = hom::bench::hollow_sphere();
  const TetMesh& m = hs.mesh;
  CHECK(m.num_elements() == 160);  // table 3.2 caption
  CHECK(m.num_nodes() == 52);
  const auto E = count_sub_simplices<2>(m), F = count_sub_simplices<3>(m);
  CHECK(E == 250);
  CHECK(F == 360);
  CHECK(52 - int(E) + int(F) - 160 == 2);  // Euler characteristic of a shell (a sphere's)
  // The thesis's node counts (table 3.2): V + (p-1) E + (p-1)(p-2)/2 F + (p-1)(p-2)(p-3)/6 T.
  for (auto [p, nodes] : {std::pair{2, 302}, std::pair{4, 2042}, std::pair{6, 6502}})
    CHECK(52 + (p - 1) * int(E) + (p - 1) * (p - 2) / 2 * int(F) + (p - 1) * (p - 2) * (p - 3) / 6 * 160 == nodes);

  // 40 boundary triangles on each sphere, vertices on their sphere.
  REQUIRE(m.boundary_facets().size() == 80);
  std::map<int, int> per_surface;
  for (const auto& f : m.boundary_facets()) {
    ++per_surface[f.entity_tag];
    const double r = f.entity_tag == hom::bench::hollow_sphere_inner_surface ? 1.0 : 3.0;
    for (int v : f.vertices) CHECK(std::abs(m.node(v).norm() - r) < 1e-14);
  }
  CHECK(per_surface[1] == 32);  // once-subdivided octahedron
  CHECK(per_surface[2] == 48);  // cube, 2 x 2 quadrilaterals per face, halved

  // Every tetrahedron positive; their volumes add up to the volume enclosed
  // by the boundary facets (divergence theorem over the outward facets: the
  // outer polyhedron minus the inner one), so they neither overlap nor leave gaps.
  double tets = 0.0;
  for (int e = 0; e < m.num_elements(); ++e) {
    Eigen::Matrix3d J;
    for (int k = 0; k < 3; ++k) J.col(k) = m.node(m.vertex(e, k + 1)) - m.node(m.vertex(e, 0));
    CHECK(J.determinant() > 0.0);
    tets += J.determinant() / 6.0;
  }
  double enclosed = 0.0;
  for (const auto& f : m.boundary_facets()) {
    Eigen::Matrix3d P;
    for (int k = 0; k < 3; ++k) P.col(k) = m.node(f.vertices[k]);
    enclosed += P.determinant() / 6.0;
  }
  CHECK(tets == doctest::Approx(enclosed).epsilon(1e-13));
  CHECK(enclosed < 4.0 / 3.0 * std::numbers::pi * 26.0);  // inscribed in r = 3, circumscribes nothing of r = 1
}

TEST_CASE("hollow sphere: curved meshes lie on the spheres, are valid, and converge to the shell's volume") {
  const auto hs = hom::bench::hollow_sphere();
  const double exact = 4.0 / 3.0 * std::numbers::pi * (27.0 - 1.0);
  double previous_error = 1.0;
  for (int p : {2, 4, 6}) {
    CAPTURE(p);
    // The free nodes follow the boundary (curved_hollow_sphere), so the
    // curved mesh is valid before it is tangled.
    const TetMesh m = hom::bench::curved_hollow_sphere(hs, p);
    // Boundary nodes on their sphere to round-off; counts from the surface
    // triangulations (V + (p-1) E + (p-1)(p-2)/2 F per sphere).
    int inner = 0, outer = 0;
    for (int i = 0; i < m.num_nodes(); ++i) {
      const auto& c = m.node_class(i);
      if (c.kind != hom::NodeKind::on_entity) continue;
      REQUIRE(c.entity);
      REQUIRE(c.entity->dim == 2);
      const double r = c.entity->tag == 1 ? 1.0 : 3.0;
      CHECK(std::abs(m.node(i).norm() - r) < 1e-12);
      (c.entity->tag == 1 ? inner : outer) += 1;
    }
    CHECK(inner == 18 + (p - 1) * 48 + (p - 1) * (p - 2) / 2 * 32);
    CHECK(outer == 26 + (p - 1) * 72 + (p - 1) * (p - 2) / 2 * 48);
    CHECK(inverted(m) == 0);
    // The volume integral agrees with the boundary integral to round-off
    // (both rules are exact for their polynomial integrands) ...
    const double volume = mesh_volume(m);
    CHECK(volume == doctest::Approx(boundary_volume(m)).epsilon(1e-12));
    // ... and approaches the exact shell's as p grows: the spheres are
    // interpolated, to O(h^(p+1)), so the volume is not exact; at p = 4
    // within 2e-4 of 4/3 pi (27 - 1).
    const double error = std::abs(volume - exact) / exact;
    CHECK(error < previous_error);
    if (p == 4) CHECK(error < 2e-4);
    previous_error = error;
  }
}

TEST_CASE("perturb_free_nodes moves exactly the free nodes, reproducibly") {
  const auto hs = hom::bench::hollow_sphere();
  const TetMesh base = hom::bench::curved_hollow_sphere(hs, 3);
  TetMesh a = base, b = base, c = base;
  const int moved = hom::bench::perturb_free_nodes(a, 0.3, 7);
  hom::bench::perturb_free_nodes(b, 0.3, 7);
  hom::bench::perturb_free_nodes(c, 0.3, 8);
  int free = 0;
  for (int i = 0; i < base.num_nodes(); ++i) {
    const bool is_free = base.node_class(i).kind == hom::NodeKind::free;
    free += is_free;
    if (!is_free) CHECK(a.node(i) == base.node(i));
  }
  CHECK(moved == free);
  CHECK(a.nodes() == b.nodes());
  CHECK(a.nodes() != c.nodes());
  // A large amplitude tangles the mesh (what bench_sphere relies on).
  TetMesh t = base;
  hom::bench::perturb_free_nodes(t, 0.5, 1);
  CHECK(inverted(t) > 0);
}

TEST_CASE("hexahedral ring: 68 hexahedra, boundary on the geometry, valid, volume") {
  const auto ring = hom::bench::hex_ring();
  CHECK(ring.mesh.num_elements() == 68);  // table D.4
  const HexMesh m = hom::bench::curved_mesh(ring, 4);
  CHECK(m.num_nodes() == 9 * 69 * 9);
  for (int i = 0; i < m.num_nodes(); ++i) {
    const auto& c = m.node_class(i);
    if (c.kind == hom::NodeKind::free) continue;
    const Eigen::Vector3d x = m.node(i);
    const double r = std::hypot(x[0], x[1]);
    const double theta = std::atan2(x[1], x[0]);
    // On one of the six boundary surfaces (a node of an edge lies on two).
    const bool on = std::abs(r - 1.0) < 1e-12 || std::abs(r - 2.0) < 1e-12 || std::abs(x[2]) < 1e-12 ||
                    std::abs(x[2] - 1.0) < 1e-12 || (std::abs(x[1]) < 1e-12 && x[0] > 0) ||
                    (std::abs(x[0]) < 1e-12 && x[1] < 0);
    CAPTURE(i);
    CAPTURE(theta);
    CHECK(on);
  }
  CHECK(inverted(m) == 0);
  // 3/4 of an annulus (radii 1, 2) times height 1.
  const double exact = 0.75 * std::numbers::pi * (4.0 - 1.0);
  CHECK(std::abs(mesh_volume(m) - exact) / exact < 1e-5);
  // The straight-sided ideal scores exactly 1 (table D.4, row "Ideal").
  const HexMesh straight = hom::elevate(ring.mesh, 4);
  const auto q = hom::mesh_quality(straight, hom::ShapeMeasure{}).quality_statistics();
  CHECK(q.min == doctest::Approx(1.0).epsilon(1e-12));
}

TEST_CASE("a small D.4-like hexahedral case untangles") {
  hom::bench::HexRingOptions o;
  o.cells = {2, 4, 2};
  o.angle = std::numbers::pi / 2;
  const auto ring = hom::bench::hex_ring(o);
  HexMesh m = hom::bench::curved_mesh(ring, 3);
  hom::bench::perturb_free_nodes(m, 0.35, 1);
  REQUIRE(inverted(m) == m.num_elements());  // every element tangled, as in figure D.5(c)
  hom::OptimizeOptions opt;
  opt.solver = hom::SolverKind::newton;
  const auto r = hom::optimize(m, opt);
  CHECK(r.result.inverted == 0);
  const auto q = hom::mesh_quality(m, hom::ShapeMeasure{}).quality_statistics();
  CHECK(q.inverted == 0);
  CHECK(q.min > 0.9);
}
