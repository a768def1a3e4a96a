#pragma once
/// @file sub_elements.hpp
/// The linear sub-element split of a degree-p element (appendix C, figure C.1):
/// the nodes of the equispaced lattice span p^2 triangles, p^3 tetrahedra or
/// p^Dim cube cells. Used by p-continuation (untangle the linear sub-mesh
/// first) and to draw curved elements.
///
/// Triangles: at every lattice point a with a_1 + a_2 <= p - 1 an upright
/// triangle (a, a+e1, a+e2), and where a_1 + a_2 <= p - 2 an inverted one
/// (a+e1, a+e1+e2, a+e2): p(p+1)/2 + p(p-1)/2 = p^2.
///
/// Tetrahedra: the lattice cells are upright tetrahedra (sum a <= p-1),
/// octahedra (sum a <= p-2), each cut into four tetrahedra around the diagonal
/// (a+e1, a+e2+e3), and inverted tetrahedra (sum a <= p-3):
/// C(p+2,3) + 4 C(p+1,3) + C(p,3) = p^3.
///
/// Every sub-element is returned positively oriented (with respect to the
/// reference element's orientation), as local node numbers of NodeLayout.

#include <array>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "hom/element/node_layout.hpp"

namespace hom {

template <ElementFamily Family>
using SubElement = std::array<int, Family::num_vertices>;

namespace detail {

// Signed measure (up to a positive factor) of a linear sub-element whose
// vertices are lattice points, for orientation fixing.
template <ElementFamily Family>
double lattice_orientation(const NodeLayout<Family>& layout, const SubElement<Family>& s) {
  constexpr int D = Family::dim;
  const int p = layout.degree();
  auto x = [&](int k) { return Family::equispaced_point(layout.lattice(s[k]), p); };
  Eigen::Matrix<double, D, D> J;
  if constexpr (Family::is_simplex) {
    for (int k = 0; k < D; ++k) J.col(k) = x(k + 1) - x(0);
  } else {
    // Axis-aligned cube cell: edges from vertex 0 along the reference axes are
    // to vertices 1, 3 (and 4), as in Cube's numbering.
    J.col(0) = x(1) - x(0);
    J.col(1) = x(3) - x(0);
    if constexpr (D == 3) J.col(2) = x(4) - x(0);
  }
  return J.determinant();
}

}  // namespace detail

template <ElementFamily Family>
std::vector<SubElement<Family>> linear_sub_elements(int p) {
  constexpr int D = Family::dim;
  const auto& layout = node_layout<Family>(p);
  using L = Lattice<D>;
  auto id = [&](L l) { return layout.index_of(l); };
  auto shift = [](L a, int i0, int i1 = -1, int i2 = -1) {
    if (i0 >= 0) ++a[i0];
    if (i1 >= 0) ++a[i1];
    if (i2 >= 0) ++a[i2];
    return a;
  };
  std::vector<SubElement<Family>> out;
  out.reserve(D == 2 ? p * p : p * p * p);

  if constexpr (Family::is_simplex && D == 2) {
    for (int j = 0; j < p; ++j)
      for (int i = 0; i + j < p; ++i) {
        const L a{i, j};
        out.push_back({id(a), id(shift(a, 0)), id(shift(a, 1))});
        if (i + j <= p - 2) out.push_back({id(shift(a, 0)), id(shift(a, 0, 1)), id(shift(a, 1))});
      }
  } else if constexpr (Family::is_simplex && D == 3) {
    for (int k = 0; k < p; ++k)
      for (int j = 0; j + k < p; ++j)
        for (int i = 0; i + j + k < p; ++i) {
          const L a{i, j, k};
          const int s = i + j + k;
          out.push_back({id(a), id(shift(a, 0)), id(shift(a, 1)), id(shift(a, 2))});
          if (s <= p - 2) {
            // Octahedron with vertices a+e1, a+e2, a+e3, a+e1+e2, a+e1+e3,
            // a+e2+e3, cut around its diagonal (a+e1, a+e2+e3).
            const int d0 = id(shift(a, 0)), d1 = id(shift(a, 1, 2));
            const int ring[4] = {id(shift(a, 1)), id(shift(a, 0, 1)), id(shift(a, 0, 2)), id(shift(a, 2))};
            for (int r = 0; r < 4; ++r) out.push_back({d0, d1, ring[r], ring[(r + 1) % 4]});
          }
          if (s <= p - 3)
            out.push_back({id(shift(a, 0, 1)), id(shift(a, 0, 2)), id(shift(a, 1, 2)), id(shift(a, 0, 1, 2))});
        }
  } else {
    // Cube cells: the lattice cell at a, vertices in Cube's numbering.
    L a{};
    const int cells = D == 2 ? p * p : p * p * p;
    for (int c = 0; c < cells; ++c) {
      int r = c;
      for (int k = 0; k < D; ++k) {
        a[k] = r % p;
        r /= p;
      }
      SubElement<Family> cell;
      for (int v = 0; v < Family::num_vertices; ++v) {
        L l = a;
        const auto corner = Family::vertex_corner(v);
        for (int k = 0; k < D; ++k) l[k] += corner[k];
        cell[v] = id(l);
      }
      out.push_back(cell);
    }
  }

  if constexpr (Family::is_simplex) {
    for (auto& s : out)
      if (detail::lattice_orientation(layout, s) < 0) std::swap(s[0], s[1]);
  }
  return out;
}

}  // namespace hom
