#pragma once
/// @file gauss.hpp
/// Gauss rules of a requested exactness on every reference element.
///
/// Cubes ([-1, 1]^Dim): tensor products of the n-point Gauss–Legendre rule,
/// exact for every monomial whose exponents are all <= 2n - 1 (Q_{2n-1}).
///
/// Simplices (unit simplex, vertices 0, e1, e2, e3): collapsed-coordinate
/// (Duffy) products. The square/cube (u, v, w) in [-1, 1]^Dim maps onto the
/// simplex by
///
///   triangle:    x = (1+u)(1-v)/4,               y = (1+v)/2,
///                dx dy = (1-v)/8 du dv;
///   tetrahedron: x = (1+u)(1-v)(1-w)/8,  y = (1+v)(1-w)/4,  z = (1+w)/2,
///                dx dy dz = (1-v)(1-w)^2/64 du dv dw.
///
/// The Jacobian factors (1-v), (1-w)^2 are absorbed into Gauss–Jacobi rules
/// with alpha = 1 (in v) and alpha = 2 (in w), so every weight is positive and
/// no point lies on the boundary (Gauss points are interior to (-1, 1)). A
/// polynomial of total degree d in (x, y, z) has degree <= d in each of u, v,
/// w once the factors are absorbed, so n = ceil((d+1)/2) points per direction
/// give total-degree exactness 2n - 1.
///
/// @note These rules use n^Dim points; the symmetric simplex rules the thesis
/// cites (sec 3.1.3, Huerta et al.) use (q+1)(q+2)/2 (triangle) and
/// (q+1)(q+2)(q+3)/6 (tetrahedron) points for degree 2q+1 — about Dim! times
/// fewer. Collapsed rules exist for every degree with positive weights and
/// interior points, which fixed tables do not guarantee; that is why hom uses
/// them. See quadrature_policy.hpp for the degree each use asks for.

#include <stdexcept>
#include <string>

#include "hom/element/family.hpp"
#include "hom/quadrature/gauss_jacobi.hpp"
#include "hom/quadrature/quadrature_rule.hpp"

namespace hom {

/// Points per direction needed for a Gauss product rule of the given exactness.
inline int gauss_points_per_direction(int exactness) { return exactness / 2 + 1; }  // ceil((e+1)/2)

/// A positive-weight Gauss rule on Family's reference element integrating
/// polynomials of degree `exactness` exactly (total degree for simplices,
/// per-axis degree for cubes). The returned rule's `exactness` is the degree
/// actually reached, 2n - 1 >= the request.
template <ElementFamily Family>
QuadratureRule<Family::dim> gauss_rule(int exactness) {
  constexpr int dim = Family::dim;
  if (exactness < 0)
    throw std::invalid_argument("hom::gauss_rule: exactness must be >= 0, got " + std::to_string(exactness));
  const int n = gauss_points_per_direction(exactness);

  QuadratureRule<dim> rule;
  rule.exactness = 2 * n - 1;
  rule.points.reserve(dim == 2 ? n * n : n * n * n);
  rule.weights.reserve(dim == 2 ? n * n : n * n * n);
  using Point = typename QuadratureRule<dim>::Point;

  if constexpr (Family::is_simplex) {
    const Rule1D ru = gauss_legendre(n);
    const Rule1D rv = gauss_jacobi(n, 1.0, 0.0);
    if constexpr (dim == 2) {
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          const double u = ru.points[i], v = rv.points[j];
          rule.points.push_back(Point(0.25 * (1.0 + u) * (1.0 - v), 0.5 * (1.0 + v)));
          rule.weights.push_back(ru.weights[i] * rv.weights[j] / 8.0);
        }
    } else {
      const Rule1D rw = gauss_jacobi(n, 2.0, 0.0);
      for (int k = 0; k < n; ++k)
        for (int j = 0; j < n; ++j)
          for (int i = 0; i < n; ++i) {
            const double u = ru.points[i], v = rv.points[j], w = rw.points[k];
            rule.points.push_back(Point(0.125 * (1.0 + u) * (1.0 - v) * (1.0 - w),
                                        0.25 * (1.0 + v) * (1.0 - w), 0.5 * (1.0 + w)));
            rule.weights.push_back(ru.weights[i] * rv.weights[j] * rw.weights[k] / 64.0);
          }
    }
    rule.name = "collapsed Gauss-Jacobi " + std::string(Family::name) + " " + std::to_string(n) + "^" +
                std::to_string(dim) + " (degree " + std::to_string(rule.exactness) + ")";
  } else {
    const Rule1D r = gauss_legendre(n);
    if constexpr (dim == 2) {
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          rule.points.push_back(Point(r.points[i], r.points[j]));
          rule.weights.push_back(r.weights[i] * r.weights[j]);
        }
    } else {
      for (int k = 0; k < n; ++k)
        for (int j = 0; j < n; ++j)
          for (int i = 0; i < n; ++i) {
            rule.points.push_back(Point(r.points[i], r.points[j], r.points[k]));
            rule.weights.push_back(r.weights[i] * r.weights[j] * r.weights[k]);
          }
    }
    rule.name = "tensor Gauss-Legendre " + std::string(Family::name) + " " + std::to_string(n) + "^" +
                std::to_string(dim) + " (per-axis degree " + std::to_string(rule.exactness) + ")";
  }
  return rule;
}

}  // namespace hom
