#pragma once
/// @file sphere_mesh.hpp
/// Meshes of the thesis's validation examples, built from analytic
/// descriptions (no mesher): shared by bench_sphere and test_sphere_mesh.
///
/// 1. `hollow_sphere`: the hollow sphere of section 3.3.2.1 (tables 3.2, 3.3),
///    inner radius 1, outer radius 3, 160 linear tetrahedra.
///
///    The thesis does not say how its "coarse tetrahedral mesh" was made, but
///    its node counts 302, 2042, 6502 at p = 2, 4, 6 fix the counts of the
///    linear mesh: n(p) = V + (p-1) E + (p-1)(p-2)/2 F + (p-1)(p-2)(p-3)/6 T
///    with T = 160 gives V = 52, E = 250, F = 360 (80 on the boundary; Euler
///    V - E + F - T = 2, a shell). This construction has exactly these counts,
///    so it has the thesis's node counts at every degree; it is not claimed to
///    be the same mesh (the thesis's was presumably unstructured).
///
///    Construction, octant by octant (octant s = (sx, sy, sz), signs +-1):
///      - inner sphere (r = 1): the once-subdivided octahedron, 18 vertices
///        (6 axis points A, 12 edge mid-directions m), 32 triangles; per
///        octant the 4 triangles (A_x m_xy m_xz), (A_y m_yz m_xy),
///        (A_z m_xz m_yz), (m_xy m_yz m_xz);
///      - outer sphere (r = 3): the cube with 2 x 2 quadrilaterals per face,
///        each cut along the diagonal from the face centre F to the cube
///        corner C, 26 vertices (6 F, 12 edge mid-directions M, 8 C),
///        48 triangles; per octant (F_a M_ab C), (F_a C M_ac);
///      - one interior vertex I per octant on the ray through C, at radius
///        sqrt(r_i r_o) (the geometric mean; any radius in [1.6, 2.2] gives a
///        valid mesh with the same minimum quality);
///      - on the three symmetry planes the quadrilaterals (A_a m M F_a) are
///        cut along m-F_a when a is x or y ("around A": A_a then touches one
///        triangle per plane) and along A_z-M when a is z;
///      - A_x and A_y are then "ears" of the octant (three boundary triangles
///        meet there): tetrahedra (A_x m_xy m_xz F_x) and (A_y m_xy m_yz F_y);
///        the remaining 18 boundary triangles of the octant are coned to I.
///    20 tetrahedra per octant, 160 in all. Cutting every plane quadrilateral
///    the same way would give 152 (3 ears per octant) or 176 (none); the x/y
///    versus z choice keeps the symmetries of a square prism (D4h) and makes
///    exactly 16 ears. Straight-sided absolute (regular-ideal) shape quality:
///    min 0.43 (the ears), mean 0.70.
///
///    Model: volume (3, 1); surfaces (2, 1) inner sphere, (2, 2) outer
///    sphere, with their analytic geometry (hom::Sphere). Vertices on a sphere
///    are classified on it, the 8 interior vertices are free.
///
/// 2. `hex_ring`: the hexahedral example of appendix D.3 (table D.4), 68
///    hexahedra. The thesis's CAD part (figure D.5(a)) is not described; this
///    is a 270-degree thick ring (inner radius 1, outer radius 2, height 1)
///    meshed as a structured 2 x 17 x 2 (radial x angular x axial) box in
///    (r, theta, z), mapped to Cartesian coordinates. Boundary: cylinders r = 1
///    (tag 1) and r = 2 (tag 2), planes theta = 0 (3) and theta = 3 pi / 2 (4),
///    z = 0 (5) and z = 1 (6) (structured.hpp's tag rule), the circular edges
///    with their circles and the straight ones with their lines.
///
/// 3. `curved_mesh`: elevate a linear mesh to degree p (the straight-sided
///    mesh is the ideal, section 3.1.2) and put its boundary nodes on the
///    geometry (geometry/curve_boundary.hpp).
///    `curved_hollow_sphere` does the same and then moves the free nodes with
///    the boundary: on this coarse mesh, moving only the boundary nodes leaves
///    the displacement of a curved face to a layer of thickness h / p, which
///    inverts 16 (p = 4) and 48 (p = 6) elements (none at p = 2). The thesis
///    starts from valid curved meshes of every degree and tangles them on
///    purpose, so the free nodes follow the radial map of the straight-sided
///    shell onto the exact one: a point x = rho d (|d| = 1) between the inner
///    and outer polyhedra, at radii rho_i(d) and rho_o(d) along d, goes to
///    (r_i + (r_o - r_i) t) d with t = (rho - rho_i) / (rho_o - rho_i). On the
///    boundary (t = 0, 1) this is the radial projection curve_boundary makes.
///
/// 4. `perturb_free_nodes` (harness.hpp): the "tangling" of both examples: every free
///    (interior) node moves by a random vector, uniform in the ball of radius
///    a * h_i, h_i the shortest straight-sided edge of the elements that
///    contain node i (seeded mt19937_64, bit-reproducible across platforms).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "harness.hpp"

#include "hom/element/cube.hpp"
#include "hom/element/simplex.hpp"
#include "hom/geometry/circle.hpp"
#include "hom/geometry/curve_boundary.hpp"
#include "hom/geometry/cylinder.hpp"
#include "hom/geometry/geometry_model.hpp"
#include "hom/geometry/line.hpp"
#include "hom/geometry/plane.hpp"
#include "hom/geometry/sphere.hpp"
#include "hom/mesh/elevate.hpp"
#include "hom/mesh/facet.hpp"
#include "hom/mesh/mesh.hpp"
#include "hom/mesh/structured.hpp"

namespace hom::bench {

using TetMesh = Mesh<Simplex<3>>;
using HexMesh = Mesh<Cube<3>>;

/// A linear mesh with the analytic geometry of its boundary entities.
template <class MeshT>
struct MeshWithGeometry {
  MeshT mesh;
  GeometryModel<3> geometry;
};

// ---------------------------------------------------------------------------
// Hollow sphere (tables 3.2, 3.3)

struct HollowSphereOptions {
  double inner_radius = 1.0;
  double outer_radius = 3.0;
  /// Radius of the 8 interior vertices; default sqrt(inner * outer).
  std::optional<double> interior_radius;
};

inline constexpr int hollow_sphere_inner_surface = 1;
inline constexpr int hollow_sphere_outer_surface = 2;

namespace detail {

/// Vertex numbering of the hollow sphere: A (inner axis points) 0-5,
/// F (outer axis points) 6-11, m (inner edge directions) 12-23,
/// M (outer edge directions) 24-35, C (outer corners) 36-43, I (interior) 44-51.
struct HollowSphereIds {
  static int sign_bit(int s) { return s < 0 ? 1 : 0; }
  static int A(int a, int s) { return 2 * a + sign_bit(s); }
  static int F(int a, int s) { return 6 + A(a, s); }
  // Axis pair (a, b), a < b: (0,1) -> 0, (0,2) -> 1, (1,2) -> 2.
  static int pair(int a, int b) { return a + b - 1; }
  static int m(int a, int b, int sa, int sb) { return 12 + 4 * pair(a, b) + 2 * sign_bit(sa) + sign_bit(sb); }
  static int M(int a, int b, int sa, int sb) { return 12 + m(a, b, sa, sb); }
  static int C(int sx, int sy, int sz) { return 36 + 4 * sign_bit(sx) + 2 * sign_bit(sy) + sign_bit(sz); }
  static int I(int sx, int sy, int sz) { return 8 + C(sx, sy, sz); }
  static constexpr int count = 52;
};

}  // namespace detail

/// The linear 160-tetrahedron hollow sphere (file comment, item 1).
inline MeshWithGeometry<TetMesh> hollow_sphere(const HollowSphereOptions& options = {}) {
  using Ids = detail::HollowSphereIds;
  const double ri = options.inner_radius, ro = options.outer_radius;
  const double rI = options.interior_radius.value_or(std::sqrt(ri * ro));
  if (!(ri > 0.0) || !(ro > ri) || !(rI > ri) || !(rI < ro))
    throw std::invalid_argument("hom::bench::hollow_sphere: need 0 < inner radius < interior radius < outer radius");

  Eigen::Matrix3Xd X(3, Ids::count);
  std::vector<int> surface(Ids::count, 0);  // 1 inner, 2 outer, 0 interior
  auto place = [&](int id, Eigen::Vector3d direction, double r, int surf) {
    X.col(id) = r * direction.normalized();
    surface[id] = surf;
  };
  for (int a = 0; a < 3; ++a)
    for (int s : {1, -1}) {
      const Eigen::Vector3d e = s * Eigen::Vector3d::Unit(a);
      place(Ids::A(a, s), e, ri, hollow_sphere_inner_surface);
      place(Ids::F(a, s), e, ro, hollow_sphere_outer_surface);
    }
  for (int a = 0; a < 3; ++a)
    for (int b = a + 1; b < 3; ++b)
      for (int sa : {1, -1})
        for (int sb : {1, -1}) {
          const Eigen::Vector3d d = sa * Eigen::Vector3d::Unit(a) + sb * Eigen::Vector3d::Unit(b);
          place(Ids::m(a, b, sa, sb), d, ri, hollow_sphere_inner_surface);
          place(Ids::M(a, b, sa, sb), d, ro, hollow_sphere_outer_surface);
        }
  for (int sx : {1, -1})
    for (int sy : {1, -1})
      for (int sz : {1, -1}) {
        const Eigen::Vector3d d(sx, sy, sz);
        place(Ids::C(sx, sy, sz), d, ro, hollow_sphere_outer_surface);
        place(Ids::I(sx, sy, sz), d, rI, 0);
      }

  std::vector<std::array<int, 4>> tets;
  for (int sx : {1, -1})
    for (int sy : {1, -1})
      for (int sz : {1, -1}) {
        const int s[3] = {sx, sy, sz};
        auto A = [&](int a) { return Ids::A(a, s[a]); };
        auto F = [&](int a) { return Ids::F(a, s[a]); };
        auto m = [&](int a, int b) { return Ids::m(a, b, s[a], s[b]); };
        auto M = [&](int a, int b) { return Ids::M(a, b, s[a], s[b]); };
        const int C = Ids::C(sx, sy, sz), I = Ids::I(sx, sy, sz);
        // The two ears.
        tets.push_back({A(0), m(0, 1), m(0, 2), F(0)});
        tets.push_back({A(1), m(0, 1), m(1, 2), F(1)});
        // The other boundary triangles of the octant, coned to I.
        const std::array<std::array<int, 3>, 18> cone = {{
            // inner sphere (the ears took (A_x m_xy m_xz) and (A_y m_yz m_xy))
            {A(2), m(0, 2), m(1, 2)},
            {m(0, 1), m(1, 2), m(0, 2)},
            // the ears' inner faces
            {m(0, 1), m(0, 2), F(0)},
            {m(1, 2), m(0, 1), F(1)},
            // outer sphere
            {F(0), M(0, 1), C},
            {F(0), C, M(0, 2)},
            {F(1), M(1, 2), C},
            {F(1), C, M(0, 1)},
            {F(2), M(0, 2), C},
            {F(2), C, M(1, 2)},
            // plane z = 0: quadrilaterals around A_x and A_y cut along m-F
            {m(0, 1), M(0, 1), F(0)},
            {m(0, 1), M(0, 1), F(1)},
            // plane y = 0: around A_x cut along m-F, around A_z along A_z-M
            {m(0, 2), M(0, 2), F(0)},
            {A(2), m(0, 2), M(0, 2)},
            {A(2), M(0, 2), F(2)},
            // plane x = 0: around A_y cut along m-F, around A_z along A_z-M
            {m(1, 2), M(1, 2), F(1)},
            {A(2), m(1, 2), M(1, 2)},
            {A(2), M(1, 2), F(2)},
        }};
        for (const auto& f : cone) tets.push_back({f[0], f[1], f[2], I});
      }

  // Orient every tetrahedron positively. A (near) zero volume would mean the
  // construction is broken, not a choice of orientation.
  Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic> conn(4, tets.size());
  const double tiny = 1e-10 * ro * ro * ro;
  for (std::size_t e = 0; e < tets.size(); ++e) {
    auto v = tets[e];
    Eigen::Matrix3d J;
    for (int k = 0; k < 3; ++k) J.col(k) = X.col(v[k + 1]) - X.col(v[0]);
    const double det = J.determinant();
    if (std::abs(det) < tiny) throw std::logic_error("hom::bench::hollow_sphere: degenerate tetrahedron");
    if (det < 0) std::swap(v[1], v[2]);
    for (int k = 0; k < 4; ++k) conn(k, e) = v[k];
  }

  TetMesh mesh(1, X, conn);
  for (int i = 0; i < Ids::count; ++i) {
    NodeClass c;
    if (surface[i] == 0) {
      c.kind = NodeKind::free;
      c.entity = EntityId{3, 1};
    } else {
      c.kind = NodeKind::on_entity;
      c.entity = EntityId{2, surface[i]};
    }
    mesh.node_class(i) = c;
  }
  mesh.entities() = {Entity{EntityId{3, 1}, {1}, {-hollow_sphere_inner_surface, hollow_sphere_outer_surface}},
                     Entity{EntityId{2, hollow_sphere_inner_surface}, {2}, {}},
                     Entity{EntityId{2, hollow_sphere_outer_surface}, {3}, {}}};
  mesh.physical_groups() = {PhysicalGroup{3, 1, "shell"}, PhysicalGroup{2, 2, "inner_sphere"},
                            PhysicalGroup{2, 3, "outer_sphere"}};

  // Boundary facets: faces of exactly one tetrahedron, classified on the
  // sphere all their vertices lie on.
  std::map<std::array<int, 3>, int> count;
  auto key = [&](int e, int f) {
    const auto lv = facet_vertices<Simplex<3>>(f);
    std::array<int, 3> k{mesh.vertex(e, lv[0]), mesh.vertex(e, lv[1]), mesh.vertex(e, lv[2])};
    std::sort(k.begin(), k.end());
    return k;
  };
  for (int e = 0; e < mesh.num_elements(); ++e)
    for (int f = 0; f < 4; ++f) ++count[key(e, f)];
  for (int e = 0; e < mesh.num_elements(); ++e)
    for (int f = 0; f < 4; ++f) {
      if (count[key(e, f)] != 1) continue;
      const auto lv = facet_vertices<Simplex<3>>(f);
      BoundaryFacet<Simplex<3>> bf;
      bf.element = e;
      bf.local_facet = f;
      for (int k = 0; k < 3; ++k) bf.vertices[k] = mesh.vertex(e, lv[k]);
      const int tag = surface[bf.vertices[0]];
      if (tag == 0 || surface[bf.vertices[1]] != tag || surface[bf.vertices[2]] != tag)
        throw std::logic_error("hom::bench::hollow_sphere: a boundary face is not on one sphere");
      bf.entity_tag = tag;
      mesh.boundary_facets().push_back(bf);
    }

  MeshWithGeometry<TetMesh> out{std::move(mesh), {}};
  out.geometry.add_surface(hollow_sphere_inner_surface, Sphere(Eigen::Vector3d::Zero(), ri));
  out.geometry.add_surface(hollow_sphere_outer_surface, Sphere(Eigen::Vector3d::Zero(), ro));
  return out;
}

// ---------------------------------------------------------------------------
// Thick ring of hexahedra (table D.4)

struct HexRingOptions {
  double inner_radius = 1.0;
  double outer_radius = 2.0;
  double height = 1.0;
  double angle = 1.5 * std::numbers::pi;  ///< angular extent (< 2 pi: the ring is open)
  std::array<int, 3> cells{2, 17, 2};     ///< radial, angular, axial; 2 x 17 x 2 = 68 (thesis)
};

/// The linear hexahedral ring (file comment, item 2).
inline MeshWithGeometry<HexMesh> hex_ring(const HexRingOptions& o = {}) {
  if (!(o.inner_radius > 0.0) || !(o.outer_radius > o.inner_radius) || !(o.height > 0.0) || !(o.angle > 0.0) ||
      !(o.angle < 2.0 * std::numbers::pi))
    throw std::invalid_argument("hom::bench::hex_ring: need 0 < inner < outer radius, height > 0, 0 < angle < 2 pi");
  // Structured box in (r, theta, z); its classification and boundary facets
  // are topological, so they survive the change of coordinates.
  HexMesh mesh = structured_mesh<Cube<3>>(o.cells, Eigen::Vector3d(o.inner_radius, 0.0, 0.0),
                                          Eigen::Vector3d(o.outer_radius, o.angle, o.height));
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    const Eigen::Vector3d q = mesh.node(i);
    mesh.node(i) = Eigen::Vector3d(q[0] * std::cos(q[1]), q[0] * std::sin(q[1]), q[2]);
  }
  // d(x, y, z) / d(r, theta, z) has determinant r > 0: orientation is kept.
  mesh.reset_ideal();

  auto tag = [](int r, int t, int z) { return hom::detail::box_entity_tag<3>({r, t, z}); };  // 0 lo, 1 hi, 2 free
  const Eigen::Vector3d origin = Eigen::Vector3d::Zero(), ez = Eigen::Vector3d::UnitZ();
  const double radius[2] = {o.inner_radius, o.outer_radius};
  const double theta[2] = {0.0, o.angle};
  const double zs[2] = {0.0, o.height};
  auto point = [&](double r, double t, double z) { return Eigen::Vector3d(r * std::cos(t), r * std::sin(t), z); };
  MeshWithGeometry<HexMesh> out{std::move(mesh), {}};
  auto& g = out.geometry;
  for (int k = 0; k < 2; ++k) {
    g.add_surface(tag(k, 2, 2), Cylinder(origin, ez, radius[k]));
    // Plane theta = const: contains the axis and the radial direction.
    const Eigen::Vector3d radial(std::cos(theta[k]), std::sin(theta[k]), 0.0);
    g.add_surface(tag(2, k, 2), Plane(origin, ez.cross(radial)));
    g.add_surface(tag(2, 2, k), Plane(zs[k] * ez, ez));
  }
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b) {
      g.add_curve(tag(a, 2, b), Circle<3>(zs[b] * ez, radius[a], ez));                                   // circles
      g.add_curve(tag(a, b, 2), Line<3>(point(radius[a], theta[b], zs[0]), point(radius[a], theta[b], zs[1])));  // axial
      g.add_curve(tag(2, a, b), Line<3>(point(radius[0], theta[a], zs[b]), point(radius[1], theta[a], zs[b])));  // radial
    }
  return out;
}

// ---------------------------------------------------------------------------

/// Degree-p mesh: p-elevation of `linear` (straight-sided; it stays the
/// ideal) with its boundary nodes on the geometry.
template <class MeshT>
MeshT curved_mesh(const MeshWithGeometry<MeshT>& linear, int p) {
  MeshT mesh = elevate(linear.mesh, p);
  curve_boundary(mesh, linear.geometry);
  return mesh;
}

namespace detail {

/// Radius rho(d) of a star-shaped (from the origin) closed triangulated
/// surface along the unit direction d: the facet whose cone contains d,
/// [x0 x1 x2] lambda = d with lambda >= 0, is hit at d / sum(lambda).
class RadialSurface {
 public:
  void add(const Eigen::Matrix3d& vertices) { inverses_.push_back(vertices.inverse()); }
  double radius(const Eigen::Vector3d& d) const {
    const double tol = -1e-12;
    for (const auto& inv : inverses_) {
      const Eigen::Vector3d l = inv * d;
      if (l.minCoeff() >= tol) return 1.0 / l.sum();
    }
    throw std::logic_error("hom::bench::RadialSurface: no facet along this direction");
  }

 private:
  std::vector<Eigen::Matrix3d> inverses_;
};

}  // namespace detail

/// Degree-p hollow sphere: curved_mesh, then the free nodes moved by the
/// radial map of the polyhedral shell onto the exact one (file comment,
/// item 3). `linear` must come from hollow_sphere (with these radii).
inline TetMesh curved_hollow_sphere(const MeshWithGeometry<TetMesh>& linear, int p,
                                    const HollowSphereOptions& options = {}) {
  TetMesh mesh = curved_mesh(linear, p);
  detail::RadialSurface inner, outer;
  for (const auto& f : linear.mesh.boundary_facets()) {
    Eigen::Matrix3d v;
    for (int k = 0; k < 3; ++k) v.col(k) = linear.mesh.node(f.vertices[k]);
    (f.entity_tag == hollow_sphere_inner_surface ? inner : outer).add(v);
  }
  const double ri = options.inner_radius, ro = options.outer_radius;
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    if (mesh.node_class(i).kind != NodeKind::free) continue;
    const Eigen::Vector3d x = mesh.node(i);
    const double rho = x.norm();
    const Eigen::Vector3d d = x / rho;
    const double rho_i = inner.radius(d), rho_o = outer.radius(d);
    const double t = (rho - rho_i) / (rho_o - rho_i);
    mesh.node(i) = (ri + (ro - ri) * t) * d;
  }
  return mesh;
}

}  // namespace hom::bench
