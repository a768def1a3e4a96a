#pragma once
/// @file gauss_lobatto.hpp
/// Tensor Gauss-Lobatto-Legendre (GLL) nodes on cubes: lattice index l sits at
/// (r_{l_0}, ..., r_{l_{Dim-1}}), r_0 < ... < r_p the p + 1 GLL points on
/// [-1, 1] (the endpoints and the roots of P_p'). Their Lebesgue constant
/// grows only like log(p)^Dim; the thesis uses them on quadrilaterals
/// (appendix F) and for the edge distribution of every element.
///
/// Simplices have no tensor structure: use WarpBlend there (its edges carry
/// the same GLL distribution).

#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "hom/element/family.hpp"
#include "hom/element/node_layout.hpp"
#include "hom/nodes/node_set.hpp"
#include "hom/quadrature/gauss_jacobi.hpp"

namespace hom {

/// The p + 1 GLL points on [-1, 1], ascending, exactly mirror-symmetric
/// (r[p - k] == -r[k] bit for bit, r[p/2] == 0 for even p), so an edge node
/// seen from either end is the same number. p >= 1.
inline Eigen::VectorXd gauss_lobatto_points(int p) {
  Eigen::VectorXd r = gauss_lobatto_legendre(p + 1).points;
  for (int k = 0; k <= p / 2; ++k) {
    const double s = 0.5 * (r[p - k] - r[k]);
    r[k] = -s;
    r[p - k] = s;
  }
  if (p % 2 == 0) r[p / 2] = 0.0;
  r[0] = -1.0;
  r[p] = 1.0;
  return r;
}

namespace detail {

/// Tensor nodes on a cube from 1D points r (p + 1 of them), in layout order.
template <ElementFamily F>
std::vector<typename F::Point> tensor_points(int p, const Eigen::VectorXd& r) {
  const auto& layout = node_layout<F>(p);
  std::vector<typename F::Point> x(layout.size());
  for (int i = 0; i < layout.size(); ++i)
    for (int d = 0; d < F::dim; ++d) x[i][d] = r[layout.lattice(i)[d]];
  return x;
}

}  // namespace detail

struct GaussLobatto {
  static constexpr std::string_view name = "gauss_lobatto";

  template <ElementFamily F>
  static constexpr bool supports = !F::is_simplex;

  template <ElementFamily F>
  static std::vector<typename F::Point> points(int p) {
    static_assert(!F::is_simplex,
                  "hom::GaussLobatto is a tensor-product node set for Cube<Dim> only; "
                  "use hom::WarpBlend on simplices (same GLL distribution on the edges)");
    return detail::tensor_points<F>(p, gauss_lobatto_points(p));
  }
};

static_assert(NodeSet<GaussLobatto>);

}  // namespace hom
