#pragma once
/// @file warp_blend.hpp
/// Warburton's warp & blend nodes: the quasi-optimal distribution the thesis
/// uses on every element (appendix A, appendix E; T. Warburton, "An explicit
/// construction of interpolation nodes on the simplex", J. Eng. Math. 56, 2006;
/// Hesthaven & Warburton, "Nodal Discontinuous Galerkin Methods", 2008,
/// sections 6.1 and 10.1).
///
/// Construction on a simplex, from the equispaced barycentric coordinates
/// lambda_v = w_v / p of each lattice node (w_v the integer vertex weights):
///
///   1. Edge warp. On [-1, 1], let r^e_m = -1 + 2m/p and r^G_m the GLL points.
///      The warp function is the equispaced interpolant of the displacements
///      divided by the edge bubble,
///        w(r) = sum_{m=1}^{p-1} (r^G_m - r^e_m) / (1 - (r^e_m)^2)
///               * prod_{j=1..p-1, j != m} (r - r^e_j) / (r^e_m - r^e_j),
///      so that (1 - r^2) w(r^e_m) = r^G_m - r^e_m.
///   2. Triangle (or a tetrahedron's face with vertices a, b, c): moving along
///      each edge (a, b) by
///        g_ab = 4 lambda_a lambda_b w(lambda_b - lambda_a) (1 + (alpha lambda_c)^2)
///      in the edge's [-1, 1] coordinate, i.e. lambda_b += g_ab / 2,
///      lambda_a -= g_ab / 2. On the edge itself (lambda_c = 0,
///      lambda_a + lambda_b = 1) this is exactly the GLL displacement.
///   3. Tetrahedron: the warp of each face f (opposite vertex o) is blended in
///      with B_f = (1 + (alpha lambda_o)^2) lambda_a lambda_b lambda_c
///        / ((lambda_a + lambda_o/2)(lambda_b + lambda_o/2)(lambda_c + lambda_o/2)),
///      which is 1 on f and 0 on the other faces.
///
/// Working with barycentric increments is the book's construction on the
/// equilateral simplex (shifts along unit edge vectors of an edge-2 simplex)
/// written affinely, so the result maps to hom's unit simplex by
/// x_d = lambda_{d+1}. Nodes whose lattice index lies on a vertex or an edge
/// are set directly (vertex; GLL point on the edge, each endpoint's coordinate
/// computed from its own weight) so that they sit exactly on their entity and
/// an edge's nodes are the same numbers seen from both ends. Face nodes of a
/// tetrahedron stay on their face (the shift never involves the opposite
/// vertex). alpha is the blending parameter optimised per degree for the
/// Lebesgue constant (tables below, published in the references); beyond the
/// tables the book's defaults are used: 5/3 (triangle) and 1 (tetrahedron).
/// Note that a tetrahedron's face nodes use the tetrahedral alpha, so they are
/// not the triangle's warp & blend nodes (as in the book; matters only when
/// converting between a tetrahedron's face and a surface triangle, which hom
/// always does by evaluating the map, never by copying nodes).
///
/// On cubes, warp & blend with the GLL warp reduces to the tensor GLL nodes
/// (every 1D line of the lattice is warped to GLL points), so WarpBlend is
/// GaussLobatto there; the thesis uses that tensor set on quadrilaterals
/// (appendix F).

#include <array>
#include <cmath>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "hom/element/family.hpp"
#include "hom/element/node_layout.hpp"
#include "hom/nodes/gauss_lobatto.hpp"
#include "hom/nodes/node_set.hpp"

namespace hom {

/// Optimised warp & blend parameter alpha for the triangle (Warburton 2006,
/// table 1; Hesthaven & Warburton, Nodes2D), 5/3 beyond p = 15.
inline double warp_blend_alpha_triangle(int p) {
  static constexpr double table[15] = {0.0000, 0.0000, 1.4152, 0.1001, 0.2751, 0.9800, 1.0999, 1.2832,
                                       1.3648, 1.4773, 1.4959, 1.5743, 1.5770, 1.6223, 1.6258};
  return p >= 1 && p <= 15 ? table[p - 1] : 5.0 / 3.0;
}

/// Optimised warp & blend parameter alpha for the tetrahedron (Warburton 2006,
/// table 2; Hesthaven & Warburton, Nodes3D), 1 beyond p = 15.
inline double warp_blend_alpha_tetrahedron(int p) {
  static constexpr double table[15] = {0.0,    0.0,    0.0,    0.1002, 1.1332, 1.5608,  1.3413, 1.2577,
                                       1.1603, 1.10153, 0.6080, 0.4523, 0.8856, 0.8717, 0.9655};
  return p >= 1 && p <= 15 ? table[p - 1] : 1.0;
}

namespace detail {

/// The 1D warp function w(r) of step 1 above, odd in r.
class EdgeWarp {
 public:
  explicit EdgeWarp(int p) : p_(p), req_(p + 1), coef_(p + 1) {
    const Eigen::VectorXd r = gauss_lobatto_points(p);
    for (int m = 0; m <= p; ++m) req_[m] = -1.0 + 2.0 * m / p;
    for (int m = 0; m <= p; ++m) req_[m] = 0.5 * (req_[m] - req_[p - m]);  // exactly odd
    coef_.setZero();
    for (int m = 1; m < p; ++m) {
      double den = 1.0 - req_[m] * req_[m];
      for (int j = 1; j < p; ++j)
        if (j != m) den *= req_[m] - req_[j];
      coef_[m] = (r[m] - req_[m]) / den;
    }
  }

  /// w(r); evaluated at |r| and signed so that w(-r) == -w(r) exactly.
  double operator()(double r) const {
    const double a = std::abs(r);
    double w = 0.0;
    for (int m = 1; m < p_; ++m) {
      double t = coef_[m];
      for (int j = 1; j < p_; ++j)
        if (j != m) t *= a - req_[j];
      w += t;
    }
    return r < 0 ? -w : w;
  }

 private:
  int p_;
  Eigen::VectorXd req_, coef_;
};

/// Barycentric shift (step 2) of one triangle (vertices a, b, c of the
/// simplex's barycentric vector lam) added to shift.
template <int N>
void add_face_warp(const EdgeWarp& warp, double alpha, const std::array<double, N>& lam, int a, int b, int c,
                   double scale, std::array<double, N>& shift) {
  const int v[3] = {a, b, c};
  for (int e = 0; e < 3; ++e) {
    const int i = v[e], j = v[(e + 1) % 3], k = v[(e + 2) % 3];
    const double ak = alpha * lam[k];
    const double g = 4.0 * lam[i] * lam[j] * warp(lam[j] - lam[i]) * (1.0 + ak * ak);
    shift[j] += 0.5 * scale * g;
    shift[i] -= 0.5 * scale * g;
  }
}

template <int Dim>
std::vector<typename Simplex<Dim>::Point> warp_blend_simplex(int p, double alpha) {
  using F = Simplex<Dim>;
  constexpr int nv = Dim + 1;
  const auto& layout = node_layout<F>(p);
  const Eigen::VectorXd gll = gauss_lobatto_points(p);
  const EdgeWarp warp(p);
  std::vector<typename F::Point> x(layout.size());
  for (int n = 0; n < layout.size(); ++n) {
    const auto w = F::vertex_weights(layout.lattice(n), p);
    int nonzero = 0;
    for (int wi : w) nonzero += wi != 0;
    std::array<double, nv> lam{};
    if (nonzero <= 2) {
      // Vertex or edge: the GLL point of the edge, lambda_v = (1 + r_{w_v}) / 2
      // (r_p = 1 gives a vertex); r_{p-k} == -r_k makes both ends agree.
      for (int v = 0; v < nv; ++v) lam[v] = w[v] == 0 ? 0.0 : 0.5 * (1.0 + gll[w[v]]);
    } else {
      for (int v = 0; v < nv; ++v) lam[v] = double(w[v]) / p;
      std::array<double, nv> shift{};
      if constexpr (Dim == 2) {
        add_face_warp<nv>(warp, alpha, lam, 0, 1, 2, 1.0, shift);
      } else {
        for (int o = 0; o < nv; ++o) {
          int f[3], m = 0;
          for (int v = 0; v < nv; ++v)
            if (v != o) f[m++] = v;
          const double prod = lam[f[0]] * lam[f[1]] * lam[f[2]];
          if (prod == 0.0) continue;  // node on another face: B_f = 0
          const double h = 0.5 * lam[o];
          const double ao = alpha * lam[o];
          const double blend =
              (1.0 + ao * ao) * prod / ((lam[f[0]] + h) * (lam[f[1]] + h) * (lam[f[2]] + h));
          add_face_warp<nv>(warp, alpha, lam, f[0], f[1], f[2], blend, shift);
        }
      }
      for (int v = 0; v < nv; ++v) lam[v] += shift[v];
    }
    for (int d = 0; d < Dim; ++d) x[n][d] = lam[d + 1];
  }
  return x;
}

}  // namespace detail

struct WarpBlend {
  static constexpr std::string_view name = "warp_blend";

  template <ElementFamily F>
  static constexpr bool supports = true;

  template <ElementFamily F>
  static std::vector<typename F::Point> points(int p) {
    if constexpr (F::is_simplex) {
      if (p == 1) return node_layout<F>(p).equispaced_points();
      const double alpha = F::dim == 2 ? warp_blend_alpha_triangle(p) : warp_blend_alpha_tetrahedron(p);
      return detail::warp_blend_simplex<F::dim>(p, alpha);
    } else {
      return detail::tensor_points<F>(p, gauss_lobatto_points(p));
    }
  }

  /// Simplex nodes with a chosen blending parameter (alpha = 0: no
  /// optimisation; the tables above give the published optimum).
  template <ElementFamily F>
  static std::vector<typename F::Point> points(int p, double alpha) {
    static_assert(F::is_simplex, "hom::WarpBlend::points(p, alpha): alpha only exists on simplices");
    if (p == 1) return node_layout<F>(p).equispaced_points();
    return detail::warp_blend_simplex<F::dim>(p, alpha);
  }
};

static_assert(NodeSet<WarpBlend>);

}  // namespace hom
