#pragma once
/// @file ring_mesh.hpp
/// Meshes of the circular ring r <= |x| <= R of appendix D (figure D.1,
/// table D.1) and appendix C (figure C.2), shared by bench/bench_ring.cpp and
/// test/test_ring.cpp.
///
/// What the thesis says about the ring (appendix D.1): 24 triangles; 126,
/// 216, 330 and 1260 nodes at p = 3, 4, 5, 10; "the same straight inner
/// edges" at every degree; tangled elements appear at the inner boundary once
/// it is curved (4 at p = 3, table D.1; 4 at p = 4, appendix C), one of them
/// at the "upper-right inner boundary" (figure D.1(b)). It gives neither the
/// radii nor the arrangement. The node counts fix the topology: with V
/// vertices and E edges, n(p) = V + (p-1) E + 24 (p-1)(p-2)/2 gives V = 18,
/// E = 42 for all four degrees; Euler's relation of an annulus (V - E + F = 0)
/// holds, and 3F = 2E - E_b gives E_b = 12 boundary edges, so 12 boundary and
/// 6 interior vertices.
///
/// hom's reading (`thesis_ring_layout`): three concentric circles of 4, 6
/// and 8 vertices at radii 1, 1.5 and 2 (inner circle r = 1, outer R = 2,
/// the middle one halfway), each pair of neighbouring circles joined by the
/// n_a + n_b triangles of a strip: 10 + 14 = 24 triangles, 18 vertices, 42
/// edges, 12 boundary edges (4 inner, 8 outer). Vertex counts proportional to
/// the radius give edges of about equal length on the three circles, as a
/// size-driven mesher would; four inner vertices at 0, 90, 180 and 270 degrees
/// put one inner boundary edge in each quadrant (a 90-degree arc, whose
/// tangent turns 45 degrees away from its chord), so the four elements on
/// the inner circle are the ones that can tangle. This is a reconstruction,
/// not the thesis's mesh.
///
/// Quadrilateral ring (`ring_quads`): the polar grid of n_theta x n_r cells.
///
/// Model: surface 1 (the ring), curve 1 (inner circle), curve 2 (outer
/// circle); circle vertices are on_entity of their curve, the others free;
/// the boundary edges are classified on their curve, so `elevate` puts the
/// edge nodes on it and `curve_boundary` moves them onto the circle.

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "hom/element/cube.hpp"
#include "hom/element/simplex.hpp"
#include "hom/geometry/circle.hpp"
#include "hom/geometry/curve_boundary.hpp"
#include "hom/geometry/geometry_model.hpp"
#include "hom/mesh/elevate.hpp"
#include "hom/mesh/mesh.hpp"
#include "hom/quadrature/quadrature_policy.hpp"

namespace hom::bench {

inline constexpr int ring_surface_tag = 1;
inline constexpr int ring_inner_tag = 1;  ///< curve tag of the inner circle
inline constexpr int ring_outer_tag = 2;  ///< curve tag of the outer circle

/// Concentric circles of vertices, inner to outer; triangles fill the strip
/// between each pair of neighbouring circles.
struct RingLayout {
  double inner_radius = 1.0;
  double outer_radius = 2.0;
  /// Vertices on each circle, inner to outer (at least two circles, each >= 3).
  std::vector<int> counts = {4, 6, 8};
  /// Angle of the first vertex of each circle (radians); empty: all zero. The
  /// circles' radii are equispaced between inner_radius and outer_radius.
  std::vector<double> offsets;

  double radius(int k) const {
    return inner_radius + (outer_radius - inner_radius) * double(k) / double(counts.size() - 1);
  }
  double offset(int k) const { return offsets.empty() ? 0.0 : offsets[k]; }
};

/// hom's reading of the thesis's 24-triangle ring (see the file comment):
/// circles of 4, 6, 8 vertices at radii 1, 1.5, 2; the middle circle starts
/// at 30 degrees so that the mesh is symmetric about both axes.
inline RingLayout thesis_ring_layout() {
  RingLayout l;
  l.offsets = {0.0, std::numbers::pi / 6.0, 0.0};
  return l;
}

/// The exact geometry of the ring's two boundary curves.
inline GeometryModel<2> ring_geometry(double inner_radius, double outer_radius) {
  GeometryModel<2> g;
  g.add_curve(ring_inner_tag, Circle<2>(Eigen::Vector2d::Zero(), inner_radius));
  g.add_curve(ring_outer_tag, Circle<2>(Eigen::Vector2d::Zero(), outer_radius));
  return g;
}

namespace detail {

template <ElementFamily Family>
double signed_polygon_area(const Eigen::Matrix<double, 2, Eigen::Dynamic>& x,
                           const std::array<int, Family::num_vertices>& v) {
  double a = 0.0;
  for (int k = 0; k < Family::num_vertices; ++k) {
    const auto p = x.col(v[k]);
    const auto q = x.col(v[(k + 1) % Family::num_vertices]);
    a += p[0] * q[1] - p[1] * q[0];
  }
  return a / 2.0;
}

/// The linear mesh from vertex positions x, each on circle `circle[i]` (0:
/// inner boundary, last: outer boundary, others interior) at index
/// `position[i]` around it, and polygons (put in counter-clockwise order
/// here). Boundary edges: consecutive vertices of the first or last circle.
template <ElementFamily Family>
Mesh<Family> ring_mesh_from(const Eigen::Matrix<double, 2, Eigen::Dynamic>& x, const std::vector<int>& circle,
                            const std::vector<int>& position, const std::vector<int>& circle_sizes,
                            std::vector<std::array<int, Family::num_vertices>> polys) {
  constexpr int nv = Family::num_vertices;
  const int last = int(circle_sizes.size()) - 1;
  typename Mesh<Family>::Connectivity conn(nv, polys.size());
  for (std::size_t e = 0; e < polys.size(); ++e) {
    auto& v = polys[e];
    const double a = signed_polygon_area<Family>(x, v);
    if (!(std::abs(a) > 0.0)) throw std::invalid_argument("hom::bench::ring mesh: degenerate element");
    if (a < 0) std::reverse(v.begin() + 1, v.end());
    for (int k = 0; k < nv; ++k) conn(k, e) = v[k];
  }
  Mesh<Family> mesh(1, x, std::move(conn));
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    NodeClass c;
    if (circle[i] == 0 || circle[i] == last) {
      c.kind = NodeKind::on_entity;
      c.entity = EntityId{1, circle[i] == 0 ? ring_inner_tag : ring_outer_tag};
      c.num_params = 1;
      c.params = {std::atan2(x(1, i), x(0, i)), 0.0};
    } else {
      c.kind = NodeKind::free;
      c.entity = EntityId{2, ring_surface_tag};
    }
    mesh.node_class(i) = c;
  }
  mesh.entities() = {Entity{{2, ring_surface_tag}, {}, {ring_outer_tag, -ring_inner_tag}},
                     Entity{{1, ring_inner_tag}, {}, {}}, Entity{{1, ring_outer_tag}, {}, {}}};
  // Boundary edges: both vertices on the inner (or outer) circle and
  // neighbours on it. Local facet f runs from vertex f to f + 1, counter-
  // clockwise around the element, i.e. outward.
  for (int e = 0; e < mesh.num_elements(); ++e)
    for (int f = 0; f < nv; ++f) {
      const int a = mesh.vertex(e, f), b = mesh.vertex(e, (f + 1) % nv);
      if (circle[a] != circle[b] || (circle[a] != 0 && circle[a] != last)) continue;
      const int n = circle_sizes[circle[a]];
      const int d = (position[a] - position[b] + n) % n;
      if (d != 1 && d != n - 1) continue;
      BoundaryFacet<Family> bf;
      bf.element = e;
      bf.local_facet = f;
      bf.entity_tag = circle[a] == 0 ? ring_inner_tag : ring_outer_tag;
      bf.vertices = {a, b};
      mesh.boundary_facets().push_back(bf);
    }
  return mesh;
}

}  // namespace detail

/// The linear (straight-sided) triangle mesh of a ring layout:
/// sum over strips of (n_k + n_{k+1}) triangles.
///
/// Strip between circles a (inner) and b: walking counter-clockwise, each
/// triangle advances one step on one of the two circles, the one whose next
/// vertex comes first in angle (ties: the inner circle), starting from the
/// vertex of b closest in angle to a's first vertex.
inline Mesh<Simplex<2>> ring_triangles(const RingLayout& layout) {
  const int nc = int(layout.counts.size());
  if (nc < 2) throw std::invalid_argument("hom::bench::ring_triangles: need at least two circles");
  if (!(layout.inner_radius > 0.0 && layout.outer_radius > layout.inner_radius))
    throw std::invalid_argument("hom::bench::ring_triangles: need 0 < inner_radius < outer_radius");
  if (!layout.offsets.empty() && int(layout.offsets.size()) != nc)
    throw std::invalid_argument("hom::bench::ring_triangles: one offset per circle");
  std::vector<int> first(nc + 1, 0);
  for (int k = 0; k < nc; ++k) {
    if (layout.counts[k] < 3) throw std::invalid_argument("hom::bench::ring_triangles: need >= 3 vertices per circle");
    first[k + 1] = first[k] + layout.counts[k];
  }
  const double two_pi = 2.0 * std::numbers::pi;
  auto angle = [&](int k, int i) { return layout.offset(k) + two_pi * double(i) / layout.counts[k]; };
  Eigen::Matrix<double, 2, Eigen::Dynamic> x(2, first[nc]);
  std::vector<int> circle(first[nc]), position(first[nc]);
  for (int k = 0; k < nc; ++k)
    for (int i = 0; i < layout.counts[k]; ++i) {
      const int id = first[k] + i;
      x.col(id) = layout.radius(k) * Eigen::Vector2d(std::cos(angle(k, i)), std::sin(angle(k, i)));
      circle[id] = k;
      position[id] = i;
    }
  std::vector<std::array<int, 3>> tris;
  for (int k = 0; k + 1 < nc; ++k) {
    const int na = layout.counts[k], nb = layout.counts[k + 1];
    const double a0 = angle(k, 0);
    // b's start: the vertex whose angle, unwrapped into [a0 - pi, a0 + pi), is closest to a0.
    int j0 = 0;
    double best = 1e300, b0 = 0.0;
    for (int j = 0; j < nb; ++j) {
      double t = angle(k + 1, j);
      t -= two_pi * std::floor((t - a0 + std::numbers::pi) / two_pi);
      if (std::abs(t - a0) < best - 1e-12) {
        best = std::abs(t - a0);
        j0 = j;
        b0 = t;
      }
    }
    auto A = [&](int i) { return first[k] + (i % na); };
    auto B = [&](int j) { return first[k + 1] + ((j0 + j) % nb); };
    int i = 0, j = 0;
    while (i < na || j < nb) {
      const double next_a = a0 + two_pi * double(i + 1) / na;
      const double next_b = b0 + two_pi * double(j + 1) / nb;
      const bool advance_a = j == nb || (i < na && next_a <= next_b + 1e-12);
      if (advance_a) {
        tris.push_back({A(i), A(i + 1), B(j)});
        ++i;
      } else {
        tris.push_back({A(i), B(j), B(j + 1)});
        ++j;
      }
    }
  }
  std::vector<int> sizes(layout.counts.begin(), layout.counts.end());
  return detail::ring_mesh_from<Simplex<2>>(x, circle, position, sizes, std::move(tris));
}

/// The linear polar-grid quadrilateral mesh of the ring: n_theta cells
/// around, n_r across, vertices at angles offset + 2 pi i / n_theta and radii
/// equispaced from inner_radius to outer_radius.
inline Mesh<Cube<2>> ring_quads(int n_theta, int n_r, double inner_radius, double outer_radius, double offset = 0.0) {
  if (n_theta < 3 || n_r < 1) throw std::invalid_argument("hom::bench::ring_quads: need n_theta >= 3 and n_r >= 1");
  if (!(inner_radius > 0.0 && outer_radius > inner_radius))
    throw std::invalid_argument("hom::bench::ring_quads: need 0 < inner_radius < outer_radius");
  const int nc = n_r + 1;
  Eigen::Matrix<double, 2, Eigen::Dynamic> x(2, nc * n_theta);
  std::vector<int> circle(nc * n_theta), position(nc * n_theta);
  auto id = [&](int k, int i) { return k * n_theta + (i % n_theta); };
  for (int k = 0; k < nc; ++k)
    for (int i = 0; i < n_theta; ++i) {
      const double r = inner_radius + (outer_radius - inner_radius) * double(k) / n_r;
      const double t = offset + 2.0 * std::numbers::pi * double(i) / n_theta;
      x.col(id(k, i)) = r * Eigen::Vector2d(std::cos(t), std::sin(t));
      circle[id(k, i)] = k;
      position[id(k, i)] = i;
    }
  std::vector<std::array<int, 4>> quads;
  for (int k = 0; k < n_r; ++k)
    for (int i = 0; i < n_theta; ++i) quads.push_back({id(k, i), id(k, i + 1), id(k + 1, i + 1), id(k + 1, i)});
  return detail::ring_mesh_from<Cube<2>>(x, circle, position, std::vector<int>(nc, n_theta), std::move(quads));
}

/// Where the nodes of a boundary edge go on its circle.
enum class BoundaryPlacement {
  /// Closest point of the straight-sided position (geometry/curve_boundary.hpp):
  /// radial projection of the chord's nodes. On a 90-degree arc this crowds
  /// the nodes towards the ends (a degree-3 edge's nodes land at 21 and 69
  /// degrees), and the interpolated arc visibly wobbles.
  closest_point,
  /// At the circle's angle parameter interpolated like the chord's nodes:
  /// a node at fraction s of its chord goes to angle u_a + s (u_b - u_a), the
  /// edge's node distribution transplanted to the arc.
  parametric,
};

/// Degree-p mesh with straight inner edges and the boundary nodes on the
/// circles: the "initial curved mesh" of appendices C and D. Its ideal is the
/// straight-sided elevated mesh. Boundary nodes end on_entity of their circle
/// with their angle as parameter.
template <ElementFamily Family, NodeSet Nodes>
Mesh<Family, Nodes> curved_ring(const Mesh<Family, Nodes>& linear, int p, double inner_radius, double outer_radius,
                                BoundaryPlacement placement = BoundaryPlacement::parametric) {
  auto mesh = elevate(linear, p);
  const auto geometry = ring_geometry(inner_radius, outer_radius);
  if (placement == BoundaryPlacement::closest_point) {
    curve_boundary(mesh, geometry);
    return mesh;
  }
  for (const auto& f : mesh.boundary_facets()) {
    const auto* circle = geometry.curve(f.entity_tag);
    const auto ids = mesh.facet_node_ids(f);  // a, b, then the interior nodes from a to b
    const Eigen::Vector2d a = mesh.node(ids[0]), b = mesh.node(ids[1]);
    const double ua = circle->project(a);
    double du = circle->project(b) - ua;
    du -= 2.0 * std::numbers::pi * std::round(du / (2.0 * std::numbers::pi));  // the short way round
    for (std::size_t k = 0; k < ids.size(); ++k) {
      const double s = (mesh.node(ids[k]) - a).dot(b - a) / (b - a).squaredNorm();
      const double u = circle->range().normalize(ua + s * du);
      mesh.node(ids[k]) = circle->evaluate(u);
      NodeClass& c = mesh.node_class(ids[k]);
      c.kind = NodeKind::on_entity;
      c.entity = EntityId{1, f.entity_tag};
      c.num_params = 1;
      c.params = {u, 0.0};
    }
  }
  return mesh;
}

/// Area of the mesh, sum over elements of the integral of det D phi with a
/// rule exact for it (degree 2(p-1) on triangles, 2p-1 per variable on
/// quadrilaterals): the area enclosed by the mesh's polynomial boundary.
template <ElementFamily Family, NodeSet Nodes>
double mesh_area(const Mesh<Family, Nodes>& mesh) {
  const int p = mesh.degree();
  const auto& rule = cached_gauss_rule<Family>(Family::is_simplex ? 2 * (p - 1) : 2 * p - 1);
  double area = 0.0;
  for (int e = 0; e < mesh.num_elements(); ++e)
    for (int q = 0; q < rule.size(); ++q) area += rule.weights[q] * mesh.jacobian(e, rule.points[q]).determinant();
  return area;
}

/// Smallest det D phi over every element, sampled at the equispaced lattice
/// with n intervals per edge (vertices and edges included): an independent
/// validity check, since hom's element validity looks at quadrature points
/// only (remark 3.3) and a fold can hide between them and a vertex.
template <ElementFamily Family, NodeSet Nodes>
  requires(Family::dim == 2)
double min_sampled_jacobian(const Mesh<Family, Nodes>& mesh, int n) {
  std::vector<typename Family::Point> points;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      if constexpr (Family::is_simplex) {
        if (i + j <= n) points.emplace_back(double(i) / n, double(j) / n);
      } else {
        points.emplace_back(-1.0 + 2.0 * i / n, -1.0 + 2.0 * j / n);
      }
    }
  const auto g = mesh.basis().gradients(points);  // [axis](point, node)
  double m = std::numeric_limits<double>::infinity();
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const auto x = mesh.element_coordinates(e);
    const Eigen::MatrixXd d0 = x * g[0].transpose(), d1 = x * g[1].transpose();  // 2 x #points
    for (Eigen::Index k = 0; k < d0.cols(); ++k) m = std::min(m, d0(0, k) * d1(1, k) - d0(1, k) * d1(0, k));
  }
  return m;
}

}  // namespace hom::bench
