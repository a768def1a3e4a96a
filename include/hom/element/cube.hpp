#pragma once
/// @file cube.hpp
/// The tensor-product family: quadrilateral (Dim = 2) and hexahedron (Dim = 3).
///
/// Reference element: [-1, 1]^Dim, vertices numbered as Gmsh and VTK do
/// (bottom face counter-clockwise, then the top face above it):
///
///     v3 ----- v2            v7 ----- v6
///     |         |           /|       /|
///     |         |         v4 ----- v5 |
///     |         |          | v3 ----|-v2
///     v0 ----- v1          |/       |/
///                         v0 ----- v1
///
/// Nodes of a degree-p element sit on the lattice {0..p}^Dim; the equispaced
/// node of lattice index l is -1 + 2 l / p.

#include <array>
#include <string_view>

#include <Eigen/Core>

#include "hom/element/lattice.hpp"

namespace hom {

template <int Dim>
struct Cube {
  static_assert(Dim == 2 || Dim == 3, "hom::Cube<Dim>: only quadrilaterals (2) and hexahedra (3) exist");

  static constexpr int dim = Dim;
  static constexpr bool is_simplex = false;
  static constexpr int num_vertices = 1 << Dim;
  static constexpr std::string_view name = Dim == 2 ? "quadrilateral" : "hexahedron";
  using Point = Eigen::Matrix<double, Dim, 1>;

  /// n_p of appendix A: (p+1)^2 or (p+1)^3.
  static constexpr int num_nodes(int p) { return Dim == 2 ? (p + 1) * (p + 1) : (p + 1) * (p + 1) * (p + 1); }

  /// Measure of the reference element: 4 or 8.
  static constexpr double reference_volume() { return Dim == 2 ? 4.0 : 8.0; }

  /// Lattice corner (0 or 1 per axis) of vertex i.
  static constexpr std::array<int, Dim> vertex_corner(int i) {
    constexpr int quad[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    std::array<int, Dim> c{};
    c[0] = quad[i % 4][0];
    c[1] = quad[i % 4][1];
    if constexpr (Dim == 3) c[2] = i / 4;
    return c;
  }

  /// Edges as ordered vertex pairs; each runs along one reference axis in the
  /// positive direction, so its nodes run from its first vertex to its second.
  static constexpr auto edges() {
    if constexpr (Dim == 2)
      return std::array<std::array<int, 2>, 4>{{{0, 1}, {1, 2}, {3, 2}, {0, 3}}};
    else
      return std::array<std::array<int, 2>, 12>{{{0, 1},
                                                 {1, 2},
                                                 {3, 2},
                                                 {0, 3},
                                                 {4, 5},
                                                 {5, 6},
                                                 {7, 6},
                                                 {4, 7},
                                                 {0, 4},
                                                 {1, 5},
                                                 {2, 6},
                                                 {3, 7}}};
  }

  /// Faces (3D only) as vertex quadruples (f0, f1, f2, f3) in cyclic order with
  /// the normal pointing out of the element. The face-local axes are s along
  /// f0 -> f1 and t along f0 -> f3.
  static constexpr auto faces() {
    static_assert(Dim == 3, "hom::Cube<2>::faces(): a quadrilateral has no faces; use edges()");
    return std::array<std::array<int, 4>, 6>{
        {{0, 3, 2, 1}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {0, 4, 7, 3}, {4, 5, 6, 7}}};
  }

  static Point vertex(int i) {
    Point v;
    const auto c = vertex_corner(i);
    for (int a = 0; a < Dim; ++a) v[a] = c[a] ? 1.0 : -1.0;
    return v;
  }

  static Lattice<Dim> vertex_lattice(int i, int p) {
    Lattice<Dim> l{};
    const auto c = vertex_corner(i);
    for (int a = 0; a < Dim; ++a) l[a] = c[a] * p;
    return l;
  }

  static bool in_lattice(const Lattice<Dim>& l, int p) {
    for (int c : l)
      if (c < 0 || c > p) return false;
    return true;
  }

  /// Integer multilinear weights of the vertices at lattice node l (they sum
  /// to p^Dim): the equispaced node is sum_i w_i v_i / p^Dim.
  static std::array<int, num_vertices> vertex_weights(const Lattice<Dim>& l, int p) {
    std::array<int, num_vertices> w{};
    for (int i = 0; i < num_vertices; ++i) {
      const auto c = vertex_corner(i);
      int wi = 1;
      for (int a = 0; a < Dim; ++a) wi *= c[a] ? l[a] : p - l[a];
      w[i] = wi;
    }
    return w;
  }

  static Point equispaced_point(const Lattice<Dim>& l, int p) {
    Point x;
    for (int a = 0; a < Dim; ++a) x[a] = p == 0 ? 0.0 : -1.0 + 2.0 * l[a] / p;
    return x;
  }
};

using Quadrilateral = Cube<2>;
using Hexahedron = Cube<3>;

}  // namespace hom
