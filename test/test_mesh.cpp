// Tests of the mesh model (include/hom/mesh/): structured meshes, topology,
// p-elevation with shared nodes, classification, coloring, the linear
// sub-mesh and the ideal mesh.
#include <doctest/doctest.h>

#include <cmath>
#include <map>
#include <optional>
#include <random>
#include <set>

#include <Eigen/Dense>

#include "hom/mesh/coloring.hpp"
#include "hom/mesh/elevate.hpp"
#include "hom/mesh/flat_corners.hpp"
#include "hom/mesh/mesh.hpp"
#include "hom/mesh/structured.hpp"
#include "hom/mesh/sub_mesh.hpp"
#include "hom/mesh/topology.hpp"
#include "hom/nodes/equispaced.hpp"
#include "hom/quadrature/quadrature_policy.hpp"

using namespace hom;

#define HOM_FAMILIES Simplex<2>, Simplex<3>, Cube<2>, Cube<3>

namespace {

template <ElementFamily F>
std::array<int, F::dim> cells() {
  if constexpr (F::dim == 2)
    return {3, 2};
  else
    return {2, 2, 1};
}

// Smooth analytic map of the unit box onto a curved domain (injective:
// a small perturbation of the identity).
template <int D>
Eigen::Matrix<double, D, 1> bend(const Eigen::Matrix<double, D, 1>& x) {
  Eigen::Matrix<double, D, 1> y = x;
  y[0] += 0.08 * std::sin(2.0 * x[1] + 0.5);
  y[1] += 0.06 * std::cos(1.5 * x[0]) * (1.0 + x[0]);
  if constexpr (D == 3) y[2] += 0.05 * std::sin(x[0] + x[1]) + 0.04 * x[2] * x[0];
  return y;
}

template <class MeshT>
void apply_bend(MeshT& m) {
  for (int i = 0; i < m.num_nodes(); ++i) m.node(i) = bend<MeshT::space_dim>(m.node(i));
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

// Volume of a mesh: sum over elements of the integral of det D phi.
template <class MeshT>
double volume(const MeshT& m) {
  using F = typename MeshT::family;
  const auto& rule = cached_gauss_rule<F>(3 * m.degree() + 2);
  const auto grads = m.basis().gradients(rule.points);
  double v = 0;
  for (int e = 0; e < m.num_elements(); ++e) {
    const auto X = m.element_coordinates(e);
    for (int q = 0; q < rule.size(); ++q) {
      Eigen::Matrix<double, F::dim, F::dim> J;
      for (int k = 0; k < F::dim; ++k) J.col(k) = X * grads[k].row(q).transpose();
      v += rule.weights[q] * J.determinant();
    }
  }
  return v;
}

long nodes_formula_2d(bool simplex, long V, long E, long F, int p) {
  return V + E * (p - 1) + F * (simplex ? long(p - 1) * (p - 2) / 2 : long(p - 1) * (p - 1));
}

}  // namespace

TEST_CASE_TEMPLATE("structured mesh: counts, orientation, volume, Euler characteristic", F, HOM_FAMILIES) {
  const auto n = cells<F>();
  const auto m = structured_mesh<F>(n);
  int cells_total = 1, points = 1;
  for (int a = 0; a < F::dim; ++a) {
    cells_total *= n[a];
    points *= n[a] + 1;
  }
  const int per_cell = F::is_simplex ? (F::dim == 2 ? 2 : 6) : 1;
  CHECK(m.num_elements() == cells_total * per_cell);
  CHECK(m.num_nodes() == points);
  CHECK(volume(m) == doctest::Approx(1.0).epsilon(1e-13));
  for (int e = 0; e < m.num_elements(); ++e) {
    const typename F::Point c = F::is_simplex ? F::Point::Constant(1.0 / (F::dim + 1)) : F::Point::Zero();
    CHECK(m.jacobian(e, c).determinant() > 0);
  }
  const Topology<F> topo(m);
  CHECK(topo.euler_characteristic() == 1);  // a box is contractible
  CHECK(topo.num_vertices() == points);
  // Boundary facets: the structured count, and the generator classified them all.
  long boundary_cells = 0;
  for (int a = 0; a < F::dim; ++a) {
    long side = 1;
    for (int b = 0; b < F::dim; ++b)
      if (b != a) side *= n[b];
    boundary_cells += 2 * side;
  }
  const long facets_per_cell_side = F::is_simplex && F::dim == 3 ? 2 : 1;
  CHECK(long(topo.boundary_facets().size()) == boundary_cells * facets_per_cell_side);
  CHECK(m.boundary_facets().size() == topo.boundary_facets().size());
}

TEST_CASE("topology counts of structured triangle and tetrahedron meshes") {
  const auto t = structured_mesh<Simplex<2>>({4, 3});
  const Topology<Simplex<2>> tt(t);
  CHECK(tt.num_edges() == 4 * 4 + 3 * 5 + 12);  // horizontal + vertical + diagonals
  const auto h = structured_mesh<Cube<3>>({2, 3, 4});
  const Topology<Cube<3>> th(h);
  CHECK(th.num_edges() == 2 * 4 * 5 + 3 * 3 * 5 + 4 * 3 * 4);
  CHECK(th.num_faces() == 3 * 3 * 4 + 4 * 2 * 4 + 5 * 2 * 3);
}

TEST_CASE_TEMPLATE("topology: interior facets are seen with opposite orientations, face orientation codes", F,
                   HOM_FAMILIES) {
  auto m = structured_mesh<F>(cells<F>());
  const Topology<F> topo(m);
  constexpr int nf = facet_num_vertices<F>;
  for (int i = 0; i < topo.num_facets_total(); ++i) {
    const auto refs = topo.facet_elements(i);
    REQUIRE(refs.size() >= 1);
    if (refs.size() < 2) continue;
    // Outward vertex cycles of the two sides.
    std::array<std::array<int, nf>, 2> cyc;
    for (int s = 0; s < 2; ++s) {
      const auto lv = facet_vertices<F>(refs[s].local);
      for (int k = 0; k < nf; ++k) cyc[s][k] = m.vertex(refs[s].element, lv[k]);
    }
    // cyc[1] reversed must be a rotation of cyc[0].
    std::array<int, nf> rev;
    for (int k = 0; k < nf; ++k) rev[k] = cyc[1][nf - 1 - k];
    bool rotation = false;
    if (nf == 2) CHECK(rev == cyc[0]);  // edges: exactly reversed
    for (int r = 0; r < nf; ++r) {
      bool same = true;
      for (int k = 0; k < nf; ++k) same = same && rev[(k + r) % nf] == cyc[0][k];
      rotation = rotation || same;
    }
    CHECK(rotation);
  }
  if constexpr (F::dim == 3) {
    for (int e = 0; e < m.num_elements(); ++e)
      for (int k = 0; k < num_facets<F>; ++k) {
        const auto c = topo.faces()[topo.element_face(e, k)];
        const auto o = topo.element_face_orientation(e, k);
        std::array<int, nf> rebuilt = c;
        if (o.reflected) std::reverse(rebuilt.begin() + 1, rebuilt.end());
        const auto lv = facet_vertices<F>(k);
        for (int i = 0; i < nf; ++i) CHECK(rebuilt[i] == m.vertex(e, lv[(o.rotation + i) % nf]));
      }
  }
  for (int e = 0; e < m.num_elements(); ++e)
    for (int k = 0; k < Topology<F>::num_local_edges; ++k) {
      const auto ed = topo.edges()[topo.element_edge(e, k)];
      const auto le = F::edges()[k];
      const int a = m.vertex(e, le[0]), b = m.vertex(e, le[1]);
      CHECK(ed[0] < ed[1]);
      CHECK((topo.element_edge_sign(e, k) > 0 ? std::array{a, b} : std::array{b, a}) == ed);
    }
}

TEST_CASE_TEMPLATE("elevation: shared nodes created once, node count formula", F, HOM_FAMILIES) {
  const auto lin = structured_mesh<F>(cells<F>());
  const Topology<F> topo(lin);
  const long V = topo.num_vertices(), E = topo.num_edges(), C = lin.num_elements();
  for (int p = 1; p <= (F::dim == 2 ? 6 : 4); ++p) {
    const auto m = elevate(lin, p);
    long expected;
    if constexpr (F::dim == 2) {
      expected = nodes_formula_2d(F::is_simplex, V, E, C, p);
    } else {
      const long Fc = topo.num_faces();
      if (F::is_simplex)
        expected = V + E * (p - 1) + Fc * long(p - 1) * (p - 2) / 2 + C * long(p - 1) * (p - 2) * (p - 3) / 6;
      else
        expected = V + E * (p - 1) + Fc * long(p - 1) * (p - 1) + C * long(p - 1) * (p - 1) * (p - 1);
    }
    CHECK(m.num_nodes() == expected);
    // Every node referenced, no element references a node twice.
    std::vector<int> used(m.num_nodes(), 0);
    for (int e = 0; e < m.num_elements(); ++e) {
      std::set<int> s(m.element(e).begin(), m.element(e).end());
      CHECK(int(s.size()) == m.nodes_per_element());
      for (int i : s) used[i] = 1;
    }
    CHECK(std::count(used.begin(), used.end(), 1) == m.num_nodes());
    // Vertices keep their ids and positions.
    for (int e = 0; e < m.num_elements(); ++e)
      for (int v = 0; v < F::num_vertices; ++v) CHECK(m.vertex(e, v) == lin.vertex(e, v));
  }
}

TEST_CASE_TEMPLATE("elevation reproduces a curved map and places shared nodes the same from every side", F,
                   HOM_FAMILIES) {
  std::mt19937 rng(7);
  auto quad = elevate(structured_mesh<F>(cells<F>()), 2);
  apply_bend(quad);  // a curved degree-2 mesh
  for (int p : {3, 5}) {
    const auto m = elevate(quad, p);
    for (int e = 0; e < m.num_elements(); ++e)
      for (int t = 0; t < 3; ++t) {
        const auto xi = random_reference_point<F>(rng);
        CHECK((m.map(e, xi) - quad.map(e, xi)).norm() < 1e-12);
      }
    // The node seen by element e at local i equals e's own map at that node.
    const auto& ref = WarpBlend::points<F>(p);
    for (int e = 0; e < m.num_elements(); ++e)
      for (int i = 0; i < m.nodes_per_element(); ++i)
        CHECK((m.node(m.element(e)[i]) - quad.map(e, ref[i])).norm() < 1e-13);
  }
  // Changing the node set keeps the map too.
  const auto eq = change_degree<Equispaced>(quad, 4);
  for (int e = 0; e < eq.num_elements(); ++e) {
    const auto xi = random_reference_point<F>(rng);
    CHECK((eq.map(e, xi) - quad.map(e, xi)).norm() < 1e-12);
  }
}

TEST_CASE_TEMPLATE("elevation classifies new nodes on the box's sub-entities", F, HOM_FAMILIES) {
  const auto lin = structured_mesh<F>(cells<F>());
  const auto m = elevate(lin, 3);
  for (int i = 0; i < m.num_nodes(); ++i) {
    detail::BoxState<F::dim> s{};
    for (int a = 0; a < F::dim; ++a) {
      const double x = m.node(i)[a];
      s[a] = std::abs(x) < 1e-12 ? 0 : (std::abs(x - 1.0) < 1e-12 ? 1 : 2);
    }
    const int d = detail::box_entity_dim<F::dim>(s);
    const auto& c = m.node_class(i);
    REQUIRE(c.entity.has_value());
    CHECK(c.entity->dim == d);
    CHECK(c.entity->tag == detail::box_entity_tag<F::dim>(s));
    CHECK(c.kind == (d == F::dim ? NodeKind::free : (d == 0 ? NodeKind::fixed : NodeKind::on_entity)));
  }
  // Boundary facets follow their elements, and their nodes lie on their side.
  for (const auto& f : m.boundary_facets()) {
    const auto ids = m.facet_node_ids(f);
    CHECK(int(ids.size()) == facet_num_nodes<F>(3));
    for (int id : ids) {
      const auto& c = m.node_class(id);
      REQUIRE(c.entity.has_value());
      CHECK(c.entity->dim <= F::dim - 1);
    }
  }
}

TEST_CASE_TEMPLATE("coloring: no element holds two nodes of a color, no node is in two elements of a color", F,
                   HOM_FAMILIES) {
  const auto m = elevate(structured_mesh<F>(cells<F>()), 3);
  const Topology<F> topo(m);
  const auto nc = color_nodes(m, topo);
  std::vector<int> color(m.num_nodes(), -1);
  int colored = 0;
  for (int c = 0; c < nc.num_colors(); ++c)
    for (int n : nc.groups[c]) {
      CHECK(color[n] == -1);
      color[n] = c;
      ++colored;
    }
  CHECK(colored == m.num_nodes());
  CHECK(nc.num_colors() >= m.nodes_per_element());
  for (int e = 0; e < m.num_elements(); ++e) {
    std::set<int> seen;
    for (int n : m.element(e)) CHECK(seen.insert(color[n]).second);
  }
  const auto ec = color_elements(m, topo);
  std::vector<int> ecolor(m.num_elements(), -1);
  for (int c = 0; c < ec.num_colors(); ++c)
    for (int e : ec.groups[c]) ecolor[e] = c;
  for (int n = 0; n < m.num_nodes(); ++n) {
    std::set<int> seen;
    for (int e : topo.node_elements(n)) CHECK(seen.insert(ecolor[e]).second);
  }
  // A subset (e.g. free nodes) is colored alone.
  std::vector<int> free_nodes;
  for (int n = 0; n < m.num_nodes(); ++n)
    if (m.node_class(n).kind == NodeKind::free) free_nodes.push_back(n);
  const auto fc = color_nodes(m, topo, free_nodes);
  std::size_t total = 0;
  for (const auto& g : fc.groups) total += g.size();
  CHECK(total == free_nodes.size());
}

TEST_CASE_TEMPLATE("linear sub-mesh: shares the nodes, tiles the element, carries the ideal", F, HOM_FAMILIES) {
  for (int p : {1, 2, 4}) {
    auto m = elevate(structured_mesh<F>(cells<F>()), p);
    auto sub = linear_sub_mesh(m);
    const int per = F::dim == 2 ? p * p : p * p * p;
    CHECK(sub.mesh.num_elements() == per * m.num_elements());
    CHECK(sub.mesh.num_nodes() == m.num_nodes());
    CHECK(volume(sub.mesh) == doctest::Approx(volume(m)).epsilon(1e-12));
    // Straight mesh: ideal = nodes.
    for (int e = 0; e < sub.mesh.num_elements(); ++e)
      CHECK((sub.mesh.ideal_vertices(e) - sub.mesh.element_coordinates(e)).norm() < 1e-14);
    // Curve the high-order mesh: the sub-mesh ideal stays the straight one,
    // each sub-element's ideal is its parent's ideal sub-element.
    apply_bend(m);
    sub = linear_sub_mesh(m);
    const auto split = linear_sub_elements<F>(p);
    for (int s = 0; s < sub.mesh.num_elements(); ++s) {
      const auto parent_ideal = m.ideal_element_coordinates(sub.parent[s]);
      for (int k = 0; k < F::num_vertices; ++k)
        CHECK((sub.mesh.ideal_vertices(s).col(k) - parent_ideal.col(split[sub.local[s]][k])).norm() < 1e-14);
      CHECK((sub.mesh.element_coordinates(s).col(0) - m.node(m.element(sub.parent[s])[split[sub.local[s]][0]])).norm() ==
            0.0);
    }
    // Move the sub-mesh and recover: the high-order nodes are the moved ones.
    sub.mesh.nodes().array() += 0.01;
    recover_from_sub_mesh(sub, m);
    CHECK((m.nodes() - sub.mesh.nodes()).norm() == 0.0);
  }
}

TEST_CASE_TEMPLATE("ideal mesh is a snapshot of the straight-sided mesh", F, HOM_FAMILIES) {
  std::mt19937 rng(3);
  auto m = elevate(structured_mesh<F>(cells<F>()), 3);
  const auto straight = m;
  apply_bend(m);
  for (int e = 0; e < m.num_elements(); ++e) {
    CHECK((m.ideal_element_coordinates(e) - straight.element_coordinates(e)).norm() < 1e-13);
    const auto xi = random_reference_point<F>(rng);
    CHECK((m.ideal_map(e, xi) - straight.map(e, xi)).norm() < 1e-13);
  }
  m.reset_ideal();
  for (int e = 0; e < m.num_elements(); ++e)
    for (int v = 0; v < F::num_vertices; ++v) CHECK((m.ideal_vertices(e).col(v) - m.node(m.vertex(e, v))).norm() == 0.0);
  if constexpr (true) {
    const auto ideal = m.straight_sided_ideal();
    CHECK(ideal.size() == m.num_elements());
  }
}

TEST_CASE("facet_nodes: corner order, rejection of non-facets") {
  for (int p = 1; p <= 5; ++p) {
    for (int f = 0; f < 6; ++f) {
      const auto& n = facet_nodes<Cube<3>>(p, f);
      CHECK(int(n.size()) == (p + 1) * (p + 1));
      std::set<int> s(n.begin(), n.end());
      CHECK(s.size() == n.size());
    }
    CHECK_THROWS_AS(facet_nodes<Cube<3>>(p, FacetVertices<Cube<3>>{0, 1, 6, 7}), std::invalid_argument);
    CHECK_THROWS_AS(facet_nodes<Cube<2>>(p, FacetVertices<Cube<2>>{0, 2}), std::invalid_argument);
  }
}

TEST_CASE("mesh constructor validates its input") {
  Mesh<Simplex<2>>::Coordinates X(2, 3);
  X << 0, 1, 0, 0, 0, 1;
  Mesh<Simplex<2>>::Connectivity c(3, 1);
  c << 0, 1, 3;
  CHECK_THROWS_AS((Mesh<Simplex<2>>(1, X, c)), std::invalid_argument);
  Mesh<Simplex<2>>::Connectivity c2(6, 1);
  c2.setZero();
  CHECK_THROWS_AS((Mesh<Simplex<2>>(1, X, c2)), std::invalid_argument);
}

TEST_CASE_TEMPLATE("surface meshes (2D families in 3D): elevation, topology, sub-mesh", F, Simplex<2>, Cube<2>) {
  const auto planar = structured_mesh<F>({3, 2});
  typename Mesh<F, WarpBlend, 3>::Coordinates X(3, planar.num_nodes());
  for (int i = 0; i < planar.num_nodes(); ++i) {
    const auto x = planar.node(i);
    X.col(i) << x[0], x[1], 0.2 * x[0] * x[1];  // a bilinear (ruled) surface
  }
  Mesh<F, WarpBlend, 3> s(1, X, planar.elements());
  s.node_classes() = planar.node_classes();
  for (auto& c : s.node_classes())
    if (c.kind == NodeKind::free) c.kind = NodeKind::on_entity;  // on the surface, not free in space
  s.entities() = planar.entities();
  for (const auto& f : planar.boundary_facets()) s.boundary_facets().push_back(f);
  const auto m = elevate(s, 4);
  CHECK(Topology<F>(m).euler_characteristic() == 1);
  std::mt19937 rng(1);
  for (int e = 0; e < m.num_elements(); ++e) {
    const auto xi = random_reference_point<F>(rng);
    CHECK((m.map(e, xi) - s.map(e, xi)).norm() < 1e-13);
    CHECK(m.jacobian(e, xi).cols() == 2);
  }
  for (int i = 0; i < m.num_nodes(); ++i) {
    const auto& c = m.node_class(i);
    REQUIRE(c.entity.has_value());
    // Interior nodes of a surface mesh stay on their surface.
    if (c.entity->dim == 2) CHECK(c.kind == NodeKind::on_entity);
  }
  const auto sub = linear_sub_mesh(m);
  CHECK(sub.mesh.num_elements() == 16 * m.num_elements());
}

TEST_CASE("physical tags of an element's entity") {
  auto m = structured_mesh<Simplex<2>>({1, 1});
  CHECK(m.physical_tags(EntityId{2, 1}).empty());
  for (auto& en : m.entities())
    if (en.id == EntityId{2, 1}) en.physical_tags = {4, 9};
  CHECK(m.physical_tags(EntityId{2, m.element_entities()[0]}) == std::vector<int>{4, 9});
  CHECK(m.physical_tags(EntityId{3, 1}).empty());
}

namespace {

// Boundary facets of a linear simplex mesh given by vertex sets and entity
// tags: each facet is found among its element's local facets.
template <int D>
void add_boundary_facets(Mesh<Simplex<D>>& mesh, const std::vector<std::pair<std::vector<int>, int>>& tagged) {
  for (const auto& [verts, tag] : tagged) {
    const std::set<int> want(verts.begin(), verts.end());
    bool found = false;
    for (int e = 0; e < mesh.num_elements() && !found; ++e)
      for (int f = 0; f < num_facets<Simplex<D>> && !found; ++f) {
        const auto lv = facet_vertices<Simplex<D>>(f);
        BoundaryFacet<Simplex<D>> bf;
        std::set<int> have;
        for (int k = 0; k < D; ++k) have.insert(bf.vertices[k] = mesh.vertex(e, lv[k]));
        if (have != want) continue;
        bf.element = e;
        bf.local_facet = f;
        bf.entity_tag = tag;
        mesh.boundary_facets().push_back(bf);
        found = true;
      }
    REQUIRE(found);
  }
}

template <int D>
double signed_volume(const Mesh<Simplex<D>>& mesh, int e) {
  Eigen::Matrix<double, D, D> j;
  for (int k = 0; k < D; ++k) j.col(k) = mesh.node(mesh.vertex(e, k + 1)) - mesh.node(mesh.vertex(e, 0));
  return j.determinant();
}

// Every boundary facet's owner holds the facet's vertices at its local facet.
template <int D>
void check_facet_owners(const Mesh<Simplex<D>>& mesh) {
  for (const auto& bf : mesh.boundary_facets()) {
    const auto lv = facet_vertices<Simplex<D>>(bf.local_facet);
    std::set<int> have, want(bf.vertices.begin(), bf.vertices.end());
    for (int k = 0; k < D; ++k) have.insert(mesh.vertex(bf.element, lv[k]));
    CHECK(have == want);
  }
}

// An octahedron with poles a = (0, 0, h), b = (0, 0, -h) and equator
// p0..p3 on the unit circle, cut into the four tetrahedra (b, a, p_i,
// p_i+1) around its axis a-b; face (pole, p_i, p_i+1) on surface tag(i, pole).
template <class Tag>
Mesh<Simplex<3>> octahedron(double h, Tag tag) {
  Eigen::Matrix3Xd x(3, 6);
  x << 0, 0, 1, 0, -1, 0,  //
      0, 0, 0, 1, 0, -1,   //
      h, -h, 0, 0, 0, 0;
  Eigen::MatrixXi t(4, 4);
  for (int i = 0; i < 4; ++i) t.col(i) << 1, 0, 2 + i, 2 + (i + 1) % 4;
  Mesh<Simplex<3>> mesh(1, x, t);
  for (int e = 0; e < 4; ++e) REQUIRE(signed_volume(mesh, e) > 0);
  std::vector<std::pair<std::vector<int>, int>> facets;
  for (int i = 0; i < 4; ++i)
    for (int pole : {0, 1}) facets.push_back({{pole, 2 + i, 2 + (i + 1) % 4}, tag(i, pole)});
  add_boundary_facets(mesh, facets);
  return mesh;
}
// A linear tetrahedron mesh of the tetrahedra `tets` (each turned to
// positive volume), whose faces that one tetrahedron alone has are boundary
// facets, each on a surface of its own (tags 1, 2, ...).
Mesh<Simplex<3>> tetrahedra_with_boundary(const Eigen::Matrix3Xd& x, std::vector<std::array<int, 4>> tets) {
  Eigen::MatrixXi t(4, tets.size());
  for (std::size_t e = 0; e < tets.size(); ++e) {
    Eigen::Matrix3d j;
    for (int k = 0; k < 3; ++k) j.col(k) = x.col(tets[e][k + 1]) - x.col(tets[e][0]);
    if (j.determinant() < 0) std::swap(tets[e][0], tets[e][1]);
    for (int k = 0; k < 4; ++k) t(k, e) = tets[e][k];
  }
  Mesh<Simplex<3>> mesh(1, x, t);
  std::map<std::vector<int>, int> face_count;
  for (const auto& tet : tets)
    for (int skip = 0; skip < 4; ++skip) {
      std::vector<int> f;
      for (int k = 0; k < 4; ++k)
        if (k != skip) f.push_back(tet[k]);
      std::sort(f.begin(), f.end());
      ++face_count[f];
    }
  std::vector<std::pair<std::vector<int>, int>> facets;
  for (const auto& [f, count] : face_count)
    if (count == 1) facets.push_back({f, int(facets.size()) + 1});
  add_boundary_facets(mesh, facets);
  return mesh;
}

double total_volume(const Mesh<Simplex<3>>& mesh) {
  double volume = 0;
  for (int e = 0; e < mesh.num_elements(); ++e) volume += signed_volume(mesh, e) / 6;
  return volume;
}

}  // namespace

TEST_CASE("split_flat_corners: a tetrahedron with two faces on one surface is split across its interior edge") {
  // An octahedron cut into four tetrahedra around its axis a-b; the two
  // faces (a, p0, p1) and (b, p0, p1) are on surface 1, each other face on
  // a surface of its own, so
  // the tetrahedron (a, b, p0, p1) has flat corners at p0 and p1: their
  // three edges are all on surface 1.
  auto mesh = octahedron(1.0, [](int i, int pole) { return i == 0 ? 1 : 10 + 2 * i + pole; });
  for (int i = 0; i < 6; ++i) mesh.node_class(i) = {NodeKind::on_entity, EntityId{2, 2}, 0, {}};

  const auto corners = find_flat_corners(mesh);
  REQUIRE(corners.size() == 2);
  for (const auto& c : corners) {
    CHECK(c.element == 0);
    CHECK(c.entity == 1);
    CHECK((mesh.vertex(0, c.vertex) == 2 || mesh.vertex(0, c.vertex) == 3));
  }
  const auto s = split_flat_corners(mesh);
  CHECK(s.corners == 2);
  CHECK(s.edges_split == 1);  // the axis a-b, shared by all four
  CHECK(s.centroid_splits == 0);
  REQUIRE(mesh.num_elements() == 8);
  REQUIRE(mesh.num_nodes() == 7);
  CHECK(mesh.node(6).norm() < 1e-15);  // the axis's midpoint
  CHECK(mesh.node_class(6).kind == NodeKind::free);
  CHECK(find_flat_corners(mesh).empty());
  double volume = 0;
  for (int e = 0; e < 8; ++e) {
    CHECK(signed_volume(mesh, e) > 0);  // orientation kept
    volume += signed_volume(mesh, e) / 6;
  }
  CHECK(volume == doctest::Approx(4.0 / 3.0));  // the octahedron's
  CHECK(mesh.boundary_facets().size() == 8);
  check_facet_owners(mesh);
}

TEST_CASE("split_flat_corners: triangles with two edges on one curve; a triangle with no interior edge") {
  // a-b-c on curve 1 (b nearly on the chord a-c), c-d-a on curve 2: both
  // triangles have a flat corner and share the interior edge a-c.
  Eigen::Matrix2Xd x(2, 4);
  x << 0, 1, 2, 1,  //
      0, 0.1, 0, -1;
  Eigen::MatrixXi t(3, 2);
  t.col(0) << 0, 2, 1;
  t.col(1) << 0, 3, 2;
  Mesh<Simplex<2>> mesh(1, x, t);
  for (int e = 0; e < 2; ++e) REQUIRE(signed_volume(mesh, e) > 0);
  add_boundary_facets(mesh, {{{0, 1}, 1}, {{1, 2}, 1}, {{2, 3}, 2}, {{3, 0}, 2}});
  CHECK(find_flat_corners(mesh).size() == 2);
  const auto s = split_flat_corners(mesh);
  CHECK(s.edges_split == 1);
  REQUIRE(mesh.num_elements() == 4);
  CHECK(find_flat_corners(mesh).empty());
  double area = 0;
  for (int e = 0; e < 4; ++e) {
    CHECK(signed_volume(mesh, e) > 0);
    area += signed_volume(mesh, e) / 2;
  }
  CHECK(area == doctest::Approx(0.1 + 1.0));
  check_facet_owners(mesh);

  // One triangle alone: every edge is a boundary edge, so the triangle is
  // split at its centroid.
  Mesh<Simplex<2>> lone(1, x.leftCols(3), t.leftCols(1));
  add_boundary_facets(lone, {{{0, 1}, 1}, {{1, 2}, 1}, {{2, 0}, 2}});
  const auto l = split_flat_corners(lone);
  CHECK(l.edges_split == 0);
  CHECK(l.centroid_splits == 1);
  REQUIRE(lone.num_elements() == 3);
  CHECK((lone.node(3) - Eigen::Vector2d(1, 0.1 / 3)).norm() < 1e-15);
  CHECK(find_flat_corners(lone).empty());
  area = 0;
  for (int e = 0; e < 3; ++e) {
    CHECK(signed_volume(lone, e) > 0);
    area += signed_volume(lone, e) / 2;
  }
  CHECK(area == doctest::Approx(0.1));
  check_facet_owners(lone);

  // Only linear meshes.
  auto quadratic = elevate(lone, 2);
  CHECK_THROWS_AS(split_flat_corners(quadratic), std::invalid_argument);
}

TEST_CASE("split_flat_corners: a tetrahedron with every edge on the boundary is split at its centroid") {
  // The unit tetrahedron alone, faces (0,1,2) and (0,1,3) on surface 1:
  // flat corners at vertices 0 and 1, and no interior edge.
  Eigen::Matrix3Xd x(3, 4);
  x << 0, 1, 0, 0,  //
      0, 0, 1, 0,   //
      0, 0, 0, 1;
  Eigen::MatrixXi t(4, 1);
  t << 0, 1, 2, 3;
  Mesh<Simplex<3>> mesh(1, x, t);
  add_boundary_facets(mesh, {{{0, 1, 2}, 1}, {{0, 1, 3}, 1}, {{0, 2, 3}, 2}, {{1, 2, 3}, 3}});
  CHECK(find_flat_corners(mesh).size() == 2);
  const auto s = split_flat_corners(mesh);
  CHECK(s.centroid_splits == 1);
  CHECK(s.edges_split == 0);
  REQUIRE(mesh.num_elements() == 4);
  CHECK((mesh.node(4) - Eigen::Vector3d::Constant(0.25)).norm() < 1e-15);
  CHECK(find_flat_corners(mesh).empty());
  double volume = 0;
  for (int e = 0; e < 4; ++e) {
    CHECK(signed_volume(mesh, e) > 0);
    volume += signed_volume(mesh, e) / 6;
  }
  CHECK(volume == doctest::Approx(1.0 / 6.0));
  check_facet_owners(mesh);
  std::set<int> owners;
  for (const auto& bf : mesh.boundary_facets()) owners.insert(bf.element);
  CHECK(owners.size() == 4);  // one facet per child
}

TEST_CASE("split_flat_corners: corners on several nearly coplanar patches are flat too") {
  // A flat octahedron (poles at z = +-0.1) around the axis a-b, every face
  // on a surface of its own: the faces around each equatorial vertex are
  // within 17 degrees of coplanar, as the patches of one smooth surface are.
  auto own_surface = [](int i, int pole) { return 1 + 2 * i + pole; };
  auto mesh = octahedron(0.1, own_surface);
  CHECK(find_flat_corners(mesh).size() == 8);  // both equatorial corners of each
  const auto s = split_flat_corners(mesh);
  CHECK(s.edges_split == 1);
  CHECK(mesh.num_elements() == 8);
  CHECK(find_flat_corners(mesh).empty());
  check_facet_owners(mesh);

  // The same with the poles at +-1: the faces meet at 70 degrees, a crease.
  CHECK(find_flat_corners(octahedron(1.0, own_surface)).empty());
}

TEST_CASE("split_flat_corners: corners on surfaces tangent to each other are flat, whatever their facets") {
  // The octahedron with poles at +-1, every face on a surface of its own:
  // its straight facets meet at 70 degrees around each equatorial vertex, a
  // crease by the facets alone (see above). If the surfaces are tangent to
  // each other there (a fillet's tangent seam, narrower than the elements),
  // the curved edges all end in one tangent plane and the corner is flat.
  auto own_surface = [](int i, int pole) { return 1 + 2 * i + pole; };
  const auto mesh = octahedron(1.0, own_surface);
  std::set<int> asked;
  const EntityNormal<3> tangent = [&](int, int node) -> std::optional<Eigen::Vector3d> {
    asked.insert(node);
    return Eigen::Vector3d(0, 0, node % 2 ? 1 : -1);  // one tangent plane, either orientation
  };
  const auto corners = find_flat_corners(mesh, tangent);
  CHECK(corners.size() == 8);  // both equatorial corners of each tetrahedron
  for (const auto& c : corners) CHECK(mesh.vertex(c.element, c.vertex) >= 2);
  CHECK(asked.count(2) + asked.count(3) + asked.count(4) + asked.count(5) == 4);  // asked at the corners' nodes

  // Normals 80 degrees apart (upper and lower surfaces): a crease again.
  const EntityNormal<3> crease = [](int tag, int) -> std::optional<Eigen::Vector3d> {
    const double t = (tag % 2 ? 40.0 : -40.0) * std::acos(-1.0) / 180.0;
    return Eigen::Vector3d(std::sin(t), 0, std::cos(t));
  };
  CHECK(find_flat_corners(mesh, crease).empty());
  // No normal at a singular point: the facets decide.
  const EntityNormal<3> none = [](int, int) -> std::optional<Eigen::Vector3d> { return std::nullopt; };
  CHECK(find_flat_corners(mesh, none).empty());

  auto split = mesh;
  const auto s = split_flat_corners(split, tangent);
  CHECK(s.corners == 8);
  CHECK(s.edges_split == 1);  // the axis
  CHECK(split.num_elements() == 8);
  CHECK(find_flat_corners(split, tangent).empty());
  check_facet_owners(split);
}

TEST_CASE("split_flat_corners: a straight corner (two boundary edges opposite in one tangent plane) is split") {
  // Where an edge spans a fillet narrower than the elements and the next
  // continues on the face beyond its seam, the two curved edges end
  // antiparallel at the seam node: a straight angle, det D phi = 0.
  // The mesh: a bipyramid around the interior edge b-c (ring a, r1, r2, r3)
  // and two tetrahedra (a, b, r1, s), (a, c, r1, s) outside its faces at
  // a-r1, which makes a-r1 interior. At a, the edges a-b and a-c are on the
  // boundary, a-r1 is interior: the tetrahedron (b, c, a, r1) has a straight
  // corner at a for the normal (0, 0, -1), which bisects the chords.
  Eigen::Matrix3Xd x(3, 7);
  x << 0, -1, 1, 0, 0, 0, 0,  // a b c r1 r2 r3 s
      0, 0, 0, 1, 0, -1, 1,   //
      1, 0, 0, 0, -1, 0, 1;
  const int node = 0, r1 = 3, s_apex = 6;
  auto mesh = tetrahedra_with_boundary(x, {{1, 2, 0, 3}, {1, 2, 3, 4}, {1, 2, 4, 5}, {1, 2, 5, 0},
                                           {0, 1, r1, s_apex}, {0, 2, r1, s_apex}});
  const std::size_t facets = mesh.boundary_facets().size();
  const auto on_boundary = detail::boundary_edge_facets(mesh);
  auto boundary = [&](int i, int j) { return on_boundary.count(detail::mesh_edge(i, j)) > 0; };
  REQUIRE(boundary(node, 1));
  REQUIRE(boundary(node, 2));
  REQUIRE(!boundary(node, r1));
  REQUIRE(!boundary(1, 2));
  const Eigen::Vector3d n(0, 0, -1);
  const EntityNormal<3> fillet = [&](int, int i) -> std::optional<Eigen::Vector3d> {
    if (i == node) return n;
    return std::nullopt;
  };
  CHECK(find_flat_corners(mesh).empty());
  const auto corners = find_flat_corners(mesh, fillet);
  REQUIRE(!corners.empty());
  int straight = 0;
  for (const auto& c : corners) {
    CHECK(mesh.vertex(c.element, c.vertex) == node);
    if (c.split_from < 0) {  // a flat corner: all three edges on the boundary
      for (int b = 0; b < 4; ++b)
        if (b != c.vertex) CHECK(boundary(node, mesh.vertex(c.element, b)));
      continue;
    }
    ++straight;
    const Eigen::Vector3d x = mesh.node(node);
    auto in_plane = [&](int local) {
      const Eigen::Vector3d d = mesh.node(mesh.vertex(c.element, local)) - x;
      return Eigen::Vector3d(d - d.dot(n) * n).normalized();
    };
    CHECK(in_plane(c.split_from).dot(in_plane(c.split_to)) < -0.86);
    CHECK(!boundary(mesh.vertex(c.element, c.split_from), mesh.vertex(c.element, c.split_to)));
  }
  CHECK(straight >= 1);
  const int before = mesh.num_elements();
  const auto s = split_flat_corners(mesh, fillet);
  CHECK(s.edges_split >= 1);
  CHECK(mesh.num_elements() > before);
  CHECK(find_flat_corners(mesh, fillet).empty());
  for (int e = 0; e < mesh.num_elements(); ++e) CHECK(signed_volume(mesh, e) > 0);
  CHECK(total_volume(mesh) == doctest::Approx(4.0 / 3.0 + 2.0 / 6.0));  // the octahedron, the two outer tetrahedra
  CHECK(mesh.boundary_facets().size() == facets);
  check_facet_owners(mesh);
}

TEST_CASE("split_flat_corners: a corner whose boundary edges turn the other way in the tangent plane is split") {
  // At a fuselage's tail tip, thinner than the elements, two boundary edges
  // from node a (under the tail, on the cylinder y^2 + z^2 = 1 with normal
  // (0, -1, 0) at a) go round to b and c on its top and bottom; b-c is a
  // boundary edge too (on a symmetry plane), face a-b-c is interior. The
  // tetrahedron (a, d1, b, c) is positive, but the chords a-b, a-c
  // projected onto the tangent plane turn the other way round about a-d1:
  // curved, its det D phi(a) < 0. Rings of three tetrahedra around a-d1 and
  // a-d2 make those edges interior; a's boundary fan is b, e1, c, e2.
  Eigen::Matrix3Xd x(3, 7);
  x << 0, -0.3, -0.3, -1, 0.6, -1.2, 1.2,  // a b c d1 d2 e1 e2
      -1, 0, 0, -0.3, -0.4, -1, -1,        //
      0, 1, -1, 0, 0, 0, 0;
  const int a = 0, b = 1, c = 2, d1 = 3, d2 = 4, e1 = 5, e2 = 6;
  auto mesh = tetrahedra_with_boundary(
      x, {{a, d1, b, c}, {a, d1, c, e1}, {a, d1, e1, b}, {a, d2, b, c}, {a, d2, c, e2}, {a, d2, e2, b}});
  const auto on_boundary = detail::boundary_edge_facets(mesh);
  auto boundary = [&](int i, int j) { return on_boundary.count(detail::mesh_edge(i, j)) > 0; };
  REQUIRE(boundary(a, b));
  REQUIRE(boundary(a, c));
  REQUIRE(boundary(b, c));
  REQUIRE(!boundary(a, d1));
  REQUIRE(!boundary(a, d2));
  REQUIRE(detail::interior_face(mesh.boundary_facets(), on_boundary, a, b, c));
  const Eigen::Vector3d n(0, -1, 0);
  const EntityNormal<3> cylinder = [&](int, int i) -> std::optional<Eigen::Vector3d> {
    if (i == a) return n;
    return std::nullopt;
  };
  CHECK(find_flat_corners(mesh).empty());
  const auto corners = find_flat_corners(mesh, cylinder);
  REQUIRE(corners.size() == 1);
  const auto& corner = corners.front();
  std::set<int> folded;
  for (int k = 0; k < 4; ++k) folded.insert(mesh.vertex(corner.element, k));
  CHECK(folded == std::set<int>{a, b, c, d1});
  CHECK(mesh.vertex(corner.element, corner.vertex) == a);
  CHECK(std::set<int>{mesh.vertex(corner.element, corner.split_from), mesh.vertex(corner.element, corner.split_to)} ==
        std::set<int>{b, c});
  // The tangents of the curved edges a-b, a-c at a (the cylinder's helices
  // through them) make det D phi(a) < 0 with a-d1 straight, as claimed.
  auto helix_tangent = [&](int end) {
    const double turn = std::atan2(x(2, end), -x(1, end));  // the angle round the axis from a
    return Eigen::Vector3d(x(0, end), 0, turn);
  };
  const Eigen::Vector3d ad1 = x.col(d1) - x.col(a);
  const double linear = (x.col(b) - x.col(a)).cross(Eigen::Vector3d(x.col(c) - x.col(a))).dot(ad1);
  CHECK(linear * helix_tangent(b).cross(helix_tangent(c)).dot(ad1) < 0);

  const double volume = total_volume(mesh);
  const std::size_t facets = mesh.boundary_facets().size();
  const auto s = split_flat_corners(mesh, cylinder);
  CHECK(s.faces_split == 1);
  CHECK(s.edges_split == 0);
  CHECK(s.centroid_splits == 0);
  CHECK(mesh.num_elements() == 6 + 4);  // both tetrahedra on a-b-c into three
  CHECK(mesh.num_nodes() == 8);
  CHECK(mesh.node(7).isApprox((x.col(a) + x.col(b) + x.col(c)) / 3));
  CHECK(mesh.node_classes()[7].kind == NodeKind::free);
  CHECK(find_flat_corners(mesh, cylinder).empty());
  for (int e = 0; e < mesh.num_elements(); ++e) CHECK(signed_volume(mesh, e) > 0);
  CHECK(total_volume(mesh) == doctest::Approx(volume));
  CHECK(mesh.boundary_facets().size() == facets);
  check_facet_owners(mesh);
}

TEST_CASE("split_flat_corners: a corner on entities with no common tangent plane is split where it folds") {
  // The star of a wing tip's leading-edge vertex v (hom curve on
  // wing_fuselage.step at p = 4: the fold left after the volume stage, in
  // its coordinates relative to v): the tip face (y = 0, normal y) meets the
  // wing at a right angle, and the wing's upper and lower faces meet
  // tangentially along the leading edge (normal x for both). Edge v-k lies
  // on the tip's airfoil curve (facets on the tip and the upper face), so
  // curved it leaves v along the curve's tangent, z = x x y; edge v-l lies
  // on the lower face, so it leaves v in the plane x = 0. The faces at v
  // have no common tangent plane, yet both edges end in the wing's, and
  // (v, d, l, k) with its third edge v-d interior folds at v once curved.
  Eigen::Matrix3Xd x(3, 8);
  x << 0, 5.95, 8.16, 7.16, 4.14, 0, 18.63, 28.12,  // v d l k upper seam tip tip_curve
      0, 10.54, 10.56, 0, 10.67, 14.26, 0, 0,       //
      0, 1.7, -4.3, 11.07, 8.77, 0, 5.59, -2.56;
  const int v = 0, d = 1, l = 2, k = 3, upper = 4, seam = 5, tip = 6, tip_curve = 7;
  auto mesh = tetrahedra_with_boundary(x, {{v, l, tip, tip_curve}, {v, k, l, tip}, {v, upper, d, k},
                                           {v, upper, d, seam}, {v, d, l, k}, {v, d, l, seam}});
  const int upper_face = 1, lower_face = 2, tip_face = 3;
  auto facet_is = [](const BoundaryFacet<Simplex<3>>& f, std::set<int> nodes) {
    return std::set<int>(f.vertices.begin(), f.vertices.end()) == nodes;
  };
  for (auto& f : mesh.boundary_facets()) {
    f.entity_tag += 10;  // the star's outer facets: entities of their own
    if (facet_is(f, {v, upper, k}) || facet_is(f, {v, upper, seam})) f.entity_tag = upper_face;
    if (facet_is(f, {v, l, tip_curve}) || facet_is(f, {v, l, seam})) f.entity_tag = lower_face;
    if (facet_is(f, {v, tip, tip_curve}) || facet_is(f, {v, k, tip})) f.entity_tag = tip_face;
  }
  const auto on_boundary = detail::boundary_edge_facets(mesh);
  REQUIRE(!on_boundary.count(detail::mesh_edge(v, d)));
  REQUIRE(detail::interior_face(mesh.boundary_facets(), on_boundary, v, l, k));
  auto normals = [&](bool tip_normal) {
    return EntityNormal<3>([=](int tag, int node) -> std::optional<Eigen::Vector3d> {
      if (node != v) return std::nullopt;
      if (tag == upper_face || tag == lower_face) return Eigen::Vector3d(-1, 0, 0);
      if (tag == tip_face && tip_normal) return Eigen::Vector3d(0, -1, 0);
      return std::nullopt;
    });
  };
  auto corners_at_v = [&](const Mesh<Simplex<3>>& m, const EntityNormal<3>& n) {
    std::vector<FlatCorner> out;
    for (const auto& c : find_flat_corners(m, n))
      if (m.vertex(c.element, c.vertex) == v) out.push_back(c);
    return out;
  };
  // The claim, from the curved directions: z along v-k, v-l's chord without
  // its x component; v-d straight.
  auto element_nodes = [&](const FlatCorner& c) {
    std::set<int> s;
    for (int i = 0; i < 4; ++i) s.insert(mesh.vertex(c.element, i));
    return s;
  };
  const Eigen::Vector3d along_k(0, 0, 1), along_l = Eigen::Vector3d(0, x(1, l), x(2, l)).normalized();
  const double linear = Eigen::Vector3d(x.col(l)).cross(Eigen::Vector3d(x.col(k))).dot(x.col(d));
  CHECK(linear * along_l.cross(along_k).dot(x.col(d)) < 0);

  const auto corners = corners_at_v(mesh, normals(true));
  REQUIRE(corners.size() == 1);  // the other tetrahedra at v keep their orientation
  CHECK(element_nodes(corners.front()) == std::set<int>{v, d, l, k});
  CHECK(std::set<int>{mesh.vertex(corners.front().element, corners.front().split_from),
                      mesh.vertex(corners.front().element, corners.front().split_to)} == std::set<int>{l, k});
  CHECK(corners_at_v(mesh, normals(false)).empty());  // no tip normal: the curve's tangent is unknown

  const double volume = total_volume(mesh);
  const std::size_t facets = mesh.boundary_facets().size();
  const auto s = split_flat_corners(mesh, normals(true));
  CHECK(s.faces_split == 1);  // l-k is on the star's outer facet (k, l, tip): face v-l-k is split
  CHECK(mesh.num_elements() == 6 + 4);
  CHECK(corners_at_v(mesh, normals(true)).empty());
  for (int e = 0; e < mesh.num_elements(); ++e) CHECK(signed_volume(mesh, e) > 0);
  CHECK(total_volume(mesh) == doctest::Approx(volume));
  CHECK(mesh.boundary_facets().size() == facets);
  check_facet_owners(mesh);
}
