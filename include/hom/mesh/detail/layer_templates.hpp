#pragma once
/// @file layer_templates.hpp
/// Internals of boundary_layer.hpp: the split of one extruded wall facet into
/// simplices (thesis section 6.3.3.1, figures 6.7 and 6.8), written in terms
/// of "sites" and "interfaces".
///
/// A wall facet's local sites are its vertices and the midpoints of its edges:
///   3D: 0 a, 1 b, 2 c, 3 m_ab, 4 m_bc, 5 m_ca   (triangle split 1-to-4)
///   2D: 0 a, 1 b, 2 m                            (segment split 1-to-2)
/// with the facet ordered so that the extrusion direction (into the domain)
/// is +z of the reference prism: (b - a) x (c - a) points into the domain in
/// 3D, the domain lies left of a -> b in 2D. Interface k (0 = wall) carries
/// one node per site; the top interface of the transition carries only the
/// vertex sites (the original, unsplit facet).
///
/// Every simplex a template emits is listed as (site, interface) pairs and
/// oriented positively in the reference prism (site reference point, z =
/// interface), which is the orientation of the physical extrusion.

#include <algorithm>
#include <array>
#include <functional>
#include <stdexcept>
#include <utility>
#include <vector>

#include <Eigen/Dense>

namespace hom::detail {

/// A node of the extruded facet: local site and interface.
struct LayerNode {
  int site = 0;
  int interface = 0;
};

template <int Dim>
using LayerSimplex = std::array<LayerNode, Dim + 1>;

template <int Dim>
inline constexpr int layer_num_sites = Dim == 3 ? 6 : 3;

/// Reference coordinates of a local site in the wall facet (Dim - 1 values).
template <int Dim>
Eigen::Matrix<double, Dim - 1, 1> layer_site_reference(int site) {
  if constexpr (Dim == 3) {
    static const double xy[6][2] = {{0, 0}, {1, 0}, {0, 1}, {0.5, 0}, {0.5, 0.5}, {0, 0.5}};
    return {xy[site][0], xy[site][1]};
  } else {
    static const double x[3] = {0, 1, 0.5};
    Eigen::Matrix<double, 1, 1> r;
    r << x[site];
    return r;
  }
}

/// Reorders s so it is positively oriented in the reference prism.
template <int Dim>
LayerSimplex<Dim> orient_in_reference(LayerSimplex<Dim> s) {
  auto point = [](const LayerNode& n) {
    Eigen::Matrix<double, Dim, 1> x;
    x.template head<Dim - 1>() = layer_site_reference<Dim>(n.site);
    x[Dim - 1] = n.interface;
    return x;
  };
  Eigen::Matrix<double, Dim, Dim> J;
  for (int k = 0; k < Dim; ++k) J.col(k) = point(s[k + 1]) - point(s[0]);
  const double det = J.determinant();
  if (std::abs(det) < 1e-12) throw std::logic_error("hom::insert_boundary_layer: degenerate template simplex");
  if (det < 0) std::swap(s[1], s[2]);
  return s;
}

/// The stacked template (figure 6.7) between interfaces k and k + 1: in 3D 4
/// sub-prisms x 3 tetrahedra = 12, in 2D 2 sub-quadrilaterals x 2 triangles
/// = 4. `global(node)` is the node's mesh-wide id: every quadrilateral face
/// is cut along the diagonal through its smallest global id, a rule both
/// prisms sharing the face apply identically, so neighbouring facets stay
/// conformal. In 3D each sub-prism is then split around its smallest vertex,
/// which always admits a 3-tetrahedron split consistent with its three quad
/// diagonals (two of them run from that vertex).
template <int Dim>
std::vector<LayerSimplex<Dim>> stacked_template(int k, const std::function<int(LayerNode)>& global) {
  std::vector<LayerSimplex<Dim>> out;
  if constexpr (Dim == 2) {
    const int quads[2][2] = {{0, 2}, {2, 1}};
    for (const auto& q : quads) {
      const std::array<LayerNode, 4> c{LayerNode{q[0], k}, LayerNode{q[1], k}, LayerNode{q[1], k + 1},
                                       LayerNode{q[0], k + 1}};
      int m = 0;
      for (int i = 1; i < 4; ++i)
        if (global(c[i]) < global(c[m])) m = i;
      // Diagonal from corner m to corner m + 2.
      out.push_back(orient_in_reference<2>({c[m], c[(m + 1) % 4], c[(m + 2) % 4]}));
      out.push_back(orient_in_reference<2>({c[m], c[(m + 2) % 4], c[(m + 3) % 4]}));
    }
  } else {
    const int prisms[4][3] = {{0, 3, 5}, {3, 1, 4}, {5, 4, 2}, {3, 4, 5}};
    for (const auto& tri : prisms) {
      // Prism corners: 0-2 bottom, 3-5 top, i + 3 above i.
      std::array<LayerNode, 6> c{};
      for (int i = 0; i < 3; ++i) {
        c[i] = {tri[i], k};
        c[i + 3] = {tri[i], k + 1};
      }
      int m = 0;
      for (int i = 1; i < 6; ++i)
        if (global(c[i]) < global(c[m])) m = i;
      // Relabel so the smallest vertex is corner 0 (swap bottom and top if it
      // is on top, rotate the triangle); orientation is restored at the end.
      std::array<LayerNode, 6> r{};
      const int shift = m % 3;
      const bool flip = m >= 3;
      for (int i = 0; i < 3; ++i) {
        r[i] = c[(i + shift) % 3 + (flip ? 3 : 0)];
        r[i + 3] = c[(i + shift) % 3 + (flip ? 0 : 3)];
      }
      // Quads (0,1,4,3) and (0,2,5,3) are cut from corner 0; quad (1,2,5,4)
      // along 1-5 or 2-4, by its smallest id.
      out.push_back(orient_in_reference<3>({r[0], r[3], r[4], r[5]}));
      const int g1 = global(r[1]), g2 = global(r[2]), g4 = global(r[4]), g5 = global(r[5]);
      if (std::min(g1, g5) < std::min(g2, g4)) {
        out.push_back(orient_in_reference<3>({r[0], r[1], r[2], r[5]}));
        out.push_back(orient_in_reference<3>({r[0], r[1], r[5], r[4]}));
      } else {
        out.push_back(orient_in_reference<3>({r[0], r[1], r[2], r[4]}));
        out.push_back(orient_in_reference<3>({r[0], r[2], r[5], r[4]}));
      }
    }
  }
  return out;
}

/// The transition template (figure 6.8) between the split interface k and the
/// unsplit top interface k + 1: in 3D the 3 corner tetrahedra (a, m_ab, m_ca,
/// a') and the octahedron (m_ab, m_bc, m_ca, a', b', c') cut into 4
/// tetrahedra around one of its three diagonals, `diagonal` = 0, 1, 2 for
/// m_ab-c', m_bc-a', m_ca-b' (internal to the facet's stack, so any choice is
/// conformal); in 2D the 3 triangles (a, m, a'), (m, b, b'), (m, b', a').
template <int Dim>
std::vector<LayerSimplex<Dim>> transition_template(int k, int diagonal = 0) {
  std::vector<LayerSimplex<Dim>> out;
  const int t = k + 1;
  if constexpr (Dim == 2) {
    out.push_back(orient_in_reference<2>({LayerNode{0, k}, LayerNode{2, k}, LayerNode{0, t}}));
    out.push_back(orient_in_reference<2>({LayerNode{2, k}, LayerNode{1, k}, LayerNode{1, t}}));
    out.push_back(orient_in_reference<2>({LayerNode{2, k}, LayerNode{1, t}, LayerNode{0, t}}));
  } else {
    const int corner_mids[3][2] = {{3, 5}, {4, 3}, {5, 4}};  // (m_ab, m_ca), (m_bc, m_ab), (m_ca, m_bc)
    for (int v = 0; v < 3; ++v)
      out.push_back(orient_in_reference<3>(
          {LayerNode{v, k}, LayerNode{corner_mids[v][0], k}, LayerNode{corner_mids[v][1], k}, LayerNode{v, t}}));
    // Diagonal d joins midpoint 3 + d to the top vertex opposite it,
    // (d + 2) % 3; its equator is the cycle m_prev, v_d', v_{d+1}', m_next.
    const int d = diagonal;
    const LayerNode m{3 + d, k}, top{(d + 2) % 3, t};
    const std::array<LayerNode, 4> equator{LayerNode{3 + (d + 2) % 3, k}, LayerNode{d, t}, LayerNode{(d + 1) % 3, t},
                                           LayerNode{3 + (d + 1) % 3, k}};
    for (int i = 0; i < 4; ++i) out.push_back(orient_in_reference<3>({m, top, equator[i], equator[(i + 1) % 4]}));
  }
  return out;
}

}  // namespace hom::detail
