#pragma once
/// @file lebesgue.hpp
/// Estimate of the Lebesgue constant of a nodal basis,
///
///   Lambda = max_{x in E^M} sum_j |N_j(x)|,
///
/// the factor by which interpolation at the nodes can exceed the best
/// approximation error (||f - I f|| <= (1 + Lambda) inf_q ||f - q||). It is
/// why the thesis uses warp & blend / Gauss-Lobatto nodes instead of
/// equispaced ones (appendix A: "a node distribution that provides a
/// quasi-optimal Lebesgue constant").
///
/// The maximum is taken over a sample: the equispaced lattice of degree m
/// (which contains the vertices and points on every edge and face, where the
/// Lebesgue function peaks) plus uniformly random points in the element. The
/// result is a lower bound of Lambda that converges as the sample grows;
/// m = 3p (at least 12, at most 60, and at most `max_lattice_points` points)
/// gives 2-3 significant digits.

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include <Eigen/Core>

#include "hom/basis/lagrange.hpp"
#include "hom/element/family.hpp"
#include "hom/nodes/node_set.hpp"

namespace hom {

struct LebesgueOptions {
  int sample_degree = 0;             ///< lattice degree m; 0 picks clamp(3p, 12, 60)
  int max_lattice_points = 20000;    ///< the automatic m is lowered until the lattice fits
  int random_points = 2000;          ///< extra uniformly random points in the element
  std::uint64_t seed = 0x5eed1e6e;   ///< for the random points (the estimate is reproducible)
};

namespace detail {

/// Number of lattice points of degree m on family F.
template <ElementFamily F>
long long lattice_count(int m) {
  long long n = 1;
  if constexpr (F::is_simplex) {
    for (int d = 1; d <= F::dim; ++d) n = n * (m + d) / d;  // binom(m + dim, dim)
  } else {
    for (int d = 0; d < F::dim; ++d) n *= m + 1;
  }
  return n;
}

/// Equispaced lattice of degree m (m >= 1) plus `extra` random points.
template <ElementFamily F>
std::vector<typename F::Point> lebesgue_sample(int m, int extra, std::uint64_t seed) {
  constexpr int D = F::dim;
  std::vector<typename F::Point> x;
  x.reserve(lattice_count<F>(m) + extra);
  Lattice<D> l{};
  long long total = 1;
  for (int d = 0; d < D; ++d) total *= m + 1;
  for (long long id = 0; id < total; ++id) {
    long long r = id;
    for (int d = 0; d < D; ++d) {
      l[d] = static_cast<int>(r % (m + 1));
      r /= m + 1;
    }
    if (F::in_lattice(l, m)) x.push_back(F::equispaced_point(l, m));
  }
  std::mt19937_64 gen(seed);
  std::uniform_real_distribution<double> unif(0.0, 1.0);
  while (extra > 0) {
    typename F::Point y;
    for (int d = 0; d < D; ++d) y[d] = unif(gen);
    if constexpr (F::is_simplex) {
      if (y.sum() > 1.0) continue;  // rejection from the unit cube
    } else {
      y = 2.0 * y.array() - 1.0;
    }
    x.push_back(y);
    --extra;
  }
  return x;
}

}  // namespace detail

/// Lebesgue constant estimate of a constructed basis.
template <ElementFamily F, NodeSet N>
double lebesgue_constant(const LagrangeBasis<F, N>& basis, const LebesgueOptions& options = {}) {
  const int p = basis.degree();
  int m = options.sample_degree;
  if (m <= 0) {
    m = std::clamp(3 * p, 12, 60);
    while (m > p && detail::lattice_count<F>(m) > options.max_lattice_points) --m;
  }
  const auto sample = detail::lebesgue_sample<F>(m, options.random_points, options.seed);
  // Chunks bound the memory of the values matrix (chunk x n_p).
  constexpr std::size_t chunk = 2048;
  double lambda = 0.0;
  std::vector<typename F::Point> part;
  for (std::size_t begin = 0; begin < sample.size(); begin += chunk) {
    const std::size_t end = std::min(sample.size(), begin + chunk);
    part.assign(sample.begin() + begin, sample.begin() + end);
    lambda = std::max(lambda, basis.values(part).cwiseAbs().rowwise().sum().maxCoeff());
  }
  return lambda;
}

/// Lebesgue constant estimate of the degree-p Lagrange basis at node set N on F.
template <ElementFamily F, NodeSet N>
double lebesgue_constant(int p, const LebesgueOptions& options = {}) {
  return lebesgue_constant(lagrange_basis<F, N>(p), options);
}

}  // namespace hom
