// Reference-element kernels: tabulating the Lagrange shape functions and their
// gradients at the quadrature points (done once per family, node set, degree
// and rule, then shared by every element), and building a LagrangeBasis.
//
//   bench_reference [--benchmark_filter=...]
#include <cstdio>
#include <string>

#include <Eigen/Core>
#include <benchmark/benchmark.h>

#include "hom/basis/lagrange.hpp"
#include "hom/basis/orthonormal.hpp"
#include "hom/nodes/gauss_lobatto.hpp"
#include "hom/nodes/warp_blend.hpp"
#include "hom/quadrature/quadrature_policy.hpp"

namespace {

using Tet = hom::Simplex<3>;
using Hex = hom::Cube<3>;

template <hom::ElementFamily F, hom::NodeSet N>
void lagrange_values(benchmark::State& state) {
  const int p = static_cast<int>(state.range(0));
  const auto& basis = hom::lagrange_basis<F, N>(p);
  const auto& rule = hom::quadrature_for<F, hom::DefaultExactness>(p);
  for (auto _ : state) benchmark::DoNotOptimize(basis.values(rule.points));
  state.counters["n_p"] = basis.size();
  state.counters["points"] = rule.size();
  state.SetItemsProcessed(state.iterations() * rule.size());
}

template <hom::ElementFamily F, hom::NodeSet N>
void lagrange_gradients(benchmark::State& state) {
  const int p = static_cast<int>(state.range(0));
  const auto& basis = hom::lagrange_basis<F, N>(p);
  const auto& rule = hom::quadrature_for<F, hom::DefaultExactness>(p);
  for (auto _ : state) benchmark::DoNotOptimize(basis.gradients(rule.points));
  state.counters["n_p"] = basis.size();
  state.counters["points"] = rule.size();
  state.SetItemsProcessed(state.iterations() * rule.size());
}

// The modal basis alone at one point (the inner kernel of both above on simplices).
template <hom::ElementFamily F>
void orthonormal_gradient(benchmark::State& state) {
  using B = hom::OrthonormalBasis<F>;
  const int p = static_cast<int>(state.range(0));
  typename F::Point x = F::Point::Constant(0.2);
  Eigen::VectorXd v(B::size(p));
  typename B::Gradient g(B::size(p), F::dim);
  for (auto _ : state) {
    B::evaluate_with_gradient(p, x, v, g);
    benchmark::DoNotOptimize(g.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations());
}

template <hom::ElementFamily F, hom::NodeSet N>
void lagrange_construction(benchmark::State& state) {
  const int p = static_cast<int>(state.range(0));
  for (auto _ : state) {
    hom::LagrangeBasis<F, N> basis(p);
    benchmark::DoNotOptimize(basis.nodes().data());
  }
}

}  // namespace

BENCHMARK(lagrange_values<Tet, hom::WarpBlend>)->DenseRange(1, 10)->Unit(benchmark::kMicrosecond);
BENCHMARK(lagrange_gradients<Tet, hom::WarpBlend>)->DenseRange(1, 10)->Unit(benchmark::kMicrosecond);
BENCHMARK(orthonormal_gradient<Tet>)->DenseRange(1, 10);
BENCHMARK(lagrange_construction<Tet, hom::WarpBlend>)->DenseRange(1, 10)->Unit(benchmark::kMicrosecond);
// Hexahedra take the tensor-product path (O(n_p) per point instead of O(n_p^2)).
BENCHMARK(lagrange_gradients<Hex, hom::GaussLobatto>)->DenseRange(1, 10)->Unit(benchmark::kMicrosecond);

int main(int argc, char** argv) {
  std::printf("bench_reference: compiler %s %s, C++ %ld\n",
#if defined(__clang__)
              "clang",
#else
              "gcc",
#endif
              __VERSION__, static_cast<long>(__cplusplus));
  std::printf("flags:%s%s%s%s%s\n",
#ifdef __OPTIMIZE__
              " optimized",
#else
              " NOT optimized",
#endif
#ifdef NDEBUG
              " NDEBUG",
#else
              " assertions-on",
#endif
#ifdef __AVX2__
              " -mavx2",
#else
              "",
#endif
#ifdef __FMA__
              " -mfma",
#else
              "",
#endif
#ifdef __AVX512F__
              " -mavx512f"
#else
              ""
#endif
  );
  std::printf("Eigen %d.%d.%d, SIMD in use: %s; EIGEN_VECTORIZE:%s%s%s%s%s\n", EIGEN_WORLD_VERSION, EIGEN_MAJOR_VERSION,
              EIGEN_MINOR_VERSION, Eigen::SimdInstructionSetsInUse(),
#ifdef EIGEN_VECTORIZE_SSE4_2
              " SSE4_2",
#else
              "",
#endif
#ifdef EIGEN_VECTORIZE_AVX
              " AVX",
#else
              "",
#endif
#ifdef EIGEN_VECTORIZE_AVX2
              " AVX2",
#else
              "",
#endif
#ifdef EIGEN_VECTORIZE_FMA
              " FMA",
#else
              "",
#endif
#ifdef EIGEN_VECTORIZE_AVX512
              " AVX512"
#else
              ""
#endif
  );
  std::printf("packet size (doubles): %d\n", static_cast<int>(Eigen::internal::packet_traits<double>::size));
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
