#pragma once
/// @file simplex.hpp
/// The simplex family: triangle (Dim = 2) and tetrahedron (Dim = 3).
///
/// Reference element (the master element E^M of appendix A): the unit simplex
/// with vertices v0 = 0 and v_i = e_i.
///
///        v2                      v3
///        | \                     | \ .
///        |   \                   |  v2
///        |     \                 | /  \ .
///        v0 --- v1               v0 --- v1
///
/// Nodes of a degree-p element sit on the integer lattice
/// { l in N^Dim : l_1 + ... + l_Dim <= p }; the equispaced node of lattice
/// index l is l / p. Its integer barycentric weights are
/// b_0 = p - sum(l), b_i = l_{i-1}; they sum to p and say which vertex,
/// edge or face the node lies on (the vertices whose weight is non-zero).

#include <array>
#include <string_view>

#include <Eigen/Core>

#include "hom/element/lattice.hpp"

namespace hom {

template <int Dim>
struct Simplex {
  static_assert(Dim == 2 || Dim == 3, "hom::Simplex<Dim>: only triangles (2) and tetrahedra (3) exist");

  static constexpr int dim = Dim;
  static constexpr bool is_simplex = true;
  static constexpr int num_vertices = Dim + 1;
  static constexpr std::string_view name = Dim == 2 ? "triangle" : "tetrahedron";
  using Point = Eigen::Matrix<double, Dim, 1>;

  /// n_p of appendix A: (p+1)(p+2)/2 for triangles, (p+1)(p+2)(p+3)/6 for tetrahedra.
  static constexpr int num_nodes(int p) {
    return Dim == 2 ? (p + 1) * (p + 2) / 2 : (p + 1) * (p + 2) * (p + 3) / 6;
  }

  /// Measure of the reference element: 1/2 or 1/6.
  static constexpr double reference_volume() { return Dim == 2 ? 0.5 : 1.0 / 6.0; }

  /// Edges as ordered vertex pairs; an edge's nodes run from its first vertex to its second.
  static constexpr auto edges() {
    if constexpr (Dim == 2)
      return std::array<std::array<int, 2>, 3>{{{0, 1}, {1, 2}, {0, 2}}};
    else
      return std::array<std::array<int, 2>, 6>{{{0, 1}, {1, 2}, {0, 2}, {0, 3}, {1, 3}, {2, 3}}};
  }

  /// Faces (3D only) as ordered vertex triples, each oriented with its normal
  /// pointing out of the element (right-hand rule). A face's interior nodes are
  /// ordered by their face-local lattice index (see NodeLayout).
  static constexpr auto faces() {
    static_assert(Dim == 3, "hom::Simplex<2>::faces(): a triangle has no faces; use edges()");
    return std::array<std::array<int, 3>, 4>{{{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}};
  }

  static Point vertex(int i) {
    Point v = Point::Zero();
    if (i > 0) v[i - 1] = 1.0;
    return v;
  }

  /// Lattice index of vertex i for degree p.
  static Lattice<Dim> vertex_lattice(int i, int p) {
    Lattice<Dim> l{};
    if (i > 0) l[i - 1] = p;
    return l;
  }

  static bool in_lattice(const Lattice<Dim>& l, int p) {
    int s = 0;
    for (int c : l) {
      if (c < 0) return false;
      s += c;
    }
    return s <= p;
  }

  /// Integer weights of the vertices at lattice node l (they sum to p): the
  /// equispaced node is sum_i w_i v_i / p.
  static std::array<int, num_vertices> vertex_weights(const Lattice<Dim>& l, int p) {
    std::array<int, num_vertices> w{};
    w[0] = p;
    for (int i = 0; i < Dim; ++i) {
      w[i + 1] = l[i];
      w[0] -= l[i];
    }
    return w;
  }

  /// Equispaced reference coordinates of lattice node l.
  static Point equispaced_point(const Lattice<Dim>& l, int p) {
    Point x;
    for (int i = 0; i < Dim; ++i) x[i] = p == 0 ? 1.0 / (Dim + 1) : double(l[i]) / p;
    return x;
  }
};

using Triangle = Simplex<2>;
using Tetrahedron = Simplex<3>;

}  // namespace hom
