#pragma once
/// @file quadrature_rule.hpp
/// A quadrature rule on a reference element: points, positive weights, and the
/// polynomial degree it integrates exactly.
///
///   int_{E^M} f  ~=  sum_i weights[i] f(points[i])
///
/// What "degree" means depends on the family: total degree for simplices,
/// per-axis degree (Q_k, every exponent <= exactness) for cubes.

#include <string>
#include <vector>

#include <Eigen/Core>

namespace hom {

template <int Dim>
struct QuadratureRule {
  using Point = Eigen::Matrix<double, Dim, 1>;

  std::vector<Point> points;    ///< reference coordinates, size() entries
  std::vector<double> weights;  ///< size() entries, summing to the reference volume
  int exactness = 0;            ///< degree integrated exactly (may exceed the degree requested)
  std::string name;             ///< human-readable description, for reports

  int size() const { return static_cast<int>(weights.size()); }
};

}  // namespace hom
