#pragma once
/// @file structured.hpp
/// Linear structured meshes of a box, for tests, examples and benchmarks.
///
/// The box [lo, hi] is cut into n[0] x n[1] (x n[2]) cells; quadrilaterals and
/// hexahedra are the cells, triangles split each cell along its (0,0)-(1,1)
/// diagonal, tetrahedra split each cell into the 6 Kuhn tetrahedra around its
/// main diagonal (conforming, every cell cut the same way). Every element is
/// positively oriented.
///
/// The box is a model with entities of every dimension: the sub-entity with,
/// per axis, the state lo / hi / free gets dimension = number of free axes and
/// tag = 1 + its rank among the states of that dimension in lexicographic
/// order (axis 0 most significant, lo < hi < free). So in 2D the sides are the
/// curves x = lo (tag 1), x = hi (2), y = lo (3), y = hi (4); the domain is
/// entity (Dim, 1). Nodes are classified on the lowest-dimensional sub-entity
/// that contains them (corners fixed, sides on_entity without parameters,
/// interior free); boundary facets carry their side's tag.

#include <algorithm>
#include <array>
#include <map>
#include <stdexcept>
#include <vector>

#include <Eigen/Core>

#include "hom/mesh/mesh.hpp"

namespace hom {

namespace detail {

// Per axis: 0 lo, 1 hi, 2 free.
template <int Dim>
using BoxState = std::array<int, Dim>;

template <int Dim>
int box_entity_dim(const BoxState<Dim>& s) {
  int d = 0;
  for (int x : s) d += x == 2;
  return d;
}

template <int Dim>
int box_entity_tag(const BoxState<Dim>& s) {
  const int d = box_entity_dim<Dim>(s);
  int rank = 0;
  BoxState<Dim> t{};
  int total = 1;
  for (int a = 0; a < Dim; ++a) total *= 3;
  for (int code = 0; code < total; ++code) {
    int r = code;
    for (int a = Dim - 1; a >= 0; --a) {
      t[a] = r % 3;
      r /= 3;
    }
    if (box_entity_dim<Dim>(t) != d) continue;
    if (t == s) return rank + 1;
    ++rank;
  }
  return 0;
}

}  // namespace detail

/// Linear mesh of the box [lo, hi] with n[a] cells along axis a.
template <ElementFamily Family, NodeSet Nodes = WarpBlend>
Mesh<Family, Nodes> structured_mesh(const std::array<int, Family::dim>& n,
                                    const typename Family::Point& lo = Family::Point::Zero(),
                                    const typename Family::Point& hi = Family::Point::Ones()) {
  constexpr int D = Family::dim;
  using M = Mesh<Family, Nodes>;
  for (int a = 0; a < D; ++a)
    if (n[a] < 1) throw std::invalid_argument("hom::structured_mesh: need at least one cell per axis");
  std::array<int, D> stride{};
  int num_points = 1;
  for (int a = 0; a < D; ++a) {
    stride[a] = num_points;
    num_points *= n[a] + 1;
  }
  typename M::Coordinates X(D, num_points);
  std::vector<NodeClass> classes(num_points);
  for (int id = 0; id < num_points; ++id) {
    int r = id;
    detail::BoxState<D> state{};
    for (int a = 0; a < D; ++a) {
      const int i = r % (n[a] + 1);
      r /= n[a] + 1;
      X(a, id) = lo[a] + (hi[a] - lo[a]) * double(i) / n[a];
      state[a] = i == 0 ? 0 : (i == n[a] ? 1 : 2);
    }
    const int d = detail::box_entity_dim<D>(state);
    NodeClass c;
    c.entity = EntityId{d, detail::box_entity_tag<D>(state)};
    c.kind = d == D ? NodeKind::free : (d == 0 ? NodeKind::fixed : NodeKind::on_entity);
    classes[id] = c;
  }

  auto point = [&](const std::array<int, D>& cell, const std::array<int, D>& corner) {
    int id = 0;
    for (int a = 0; a < D; ++a) id += (cell[a] + corner[a]) * stride[a];
    return id;
  };
  std::vector<std::array<int, Family::num_vertices>> elems;
  int num_cells = 1;
  for (int a = 0; a < D; ++a) num_cells *= n[a];
  for (int c = 0; c < num_cells; ++c) {
    std::array<int, D> cell{};
    int r = c;
    for (int a = 0; a < D; ++a) {
      cell[a] = r % n[a];
      r /= n[a];
    }
    if constexpr (!Family::is_simplex) {
      std::array<int, Family::num_vertices> v{};
      for (int k = 0; k < Family::num_vertices; ++k) {
        const auto cc = Family::vertex_corner(k);
        std::array<int, D> corner{};
        for (int a = 0; a < D; ++a) corner[a] = cc[a];
        v[k] = point(cell, corner);
      }
      elems.push_back(v);
    } else if constexpr (D == 2) {
      elems.push_back({point(cell, {0, 0}), point(cell, {1, 0}), point(cell, {1, 1})});
      elems.push_back({point(cell, {0, 0}), point(cell, {1, 1}), point(cell, {0, 1})});
    } else {
      // Kuhn split: one tetrahedron per axis permutation, walking from the
      // cell's lowest corner to its highest one axis at a time.
      std::array<int, 3> perm{0, 1, 2};
      do {
        std::array<int, 3> corner{0, 0, 0};
        std::array<int, 4> v{};
        v[0] = point(cell, corner);
        for (int k = 0; k < 3; ++k) {
          corner[perm[k]] = 1;
          v[k + 1] = point(cell, corner);
        }
        elems.push_back(v);
      } while (std::next_permutation(perm.begin(), perm.end()));
    }
  }
  typename M::Connectivity conn(Family::num_vertices, elems.size());
  for (std::size_t e = 0; e < elems.size(); ++e) {
    auto v = elems[e];
    if constexpr (Family::is_simplex) {
      Eigen::Matrix<double, D, D> J;
      for (int k = 0; k < D; ++k) J.col(k) = X.col(v[k + 1]) - X.col(v[0]);
      if (J.determinant() < 0) std::swap(v[1], v[2]);
    }
    for (int k = 0; k < Family::num_vertices; ++k) conn(k, e) = v[k];
  }
  M mesh(1, std::move(X), std::move(conn));
  mesh.node_classes() = std::move(classes);

  // Model entities with their boundaries.
  int total = 1;
  for (int a = 0; a < D; ++a) total *= 3;
  for (int code = 0; code < total; ++code) {
    detail::BoxState<D> s{};
    int r = code;
    for (int a = D - 1; a >= 0; --a) {
      s[a] = r % 3;
      r /= 3;
    }
    Entity en;
    en.id = EntityId{detail::box_entity_dim<D>(s), detail::box_entity_tag<D>(s)};
    for (int a = 0; a < D; ++a)
      if (s[a] == 2)
        for (int side = 0; side < 2; ++side) {
          auto t = s;
          t[a] = side;
          en.boundary.push_back((side == 0 ? -1 : 1) * detail::box_entity_tag<D>(t));
        }
    mesh.entities().push_back(en);
  }

  // Boundary facets: a facet lies on side (a, lo/hi) when all its vertices do.
  for (int e = 0; e < mesh.num_elements(); ++e)
    for (int f = 0; f < num_facets<Family>; ++f) {
      const auto lv = facet_vertices<Family>(f);
      for (int a = 0; a < D; ++a)
        for (int side = 0; side < 2; ++side) {
          const double wall = side == 0 ? lo[a] : hi[a];
          bool on = true;
          for (int l : lv) on = on && mesh.node(mesh.vertex(e, l))[a] == wall;
          if (!on) continue;
          detail::BoxState<D> s{};
          s.fill(2);
          s[a] = side;
          BoundaryFacet<Family> bf;
          bf.element = e;
          bf.local_facet = f;
          bf.entity_tag = detail::box_entity_tag<D>(s);
          for (int k = 0; k < facet_num_vertices<Family>; ++k) bf.vertices[k] = mesh.vertex(e, lv[k]);
          mesh.boundary_facets().push_back(bf);
        }
    }
  return mesh;
}

}  // namespace hom
