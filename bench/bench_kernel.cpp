// How close the optimizer's element kernels come to the machine's peak
// double-precision rate.
//
//   bench_kernel [--benchmark_filter=...] [--benchmark_format=json|--benchmark_out=F.json --benchmark_out_format=json]
//
// Results (2026-11-22; `build-h4/bench/bench_kernel --benchmark_out=... --benchmark_out_format=json`;
// default release build -O3 -march=x86-64-v3, g++ 12.2, Eigen 3.4; Intel Xeon KVM guest with AVX-512,
// 2 cores). MEASURED ON A LOADED 2-CORE MACHINE (load average 6-7: other agents compiling), where
// this process got about 40% of a core: wall-clock rates are 2.5x below what the code does, so the
// numbers quoted here are per CPU second (GFLOPs_per_cpu_s, peak_fraction_cpu), and the 2-thread
// rows show no speed-up because the second core was never free; they say nothing about scaling.
// Peak (fma_peak, 1 thread): 33 GFLOP/s with AVX2+FMA (16 flop/cycle at about 2.1 GHz); 512-bit FMAs
// through a target attribute reach 69 GFLOP/s, so the theoretical 2x of AVX-512 is real on this CPU
// (two 512-bit FMA ports) and a -Dnative=true build could double the ceiling. Per CPU second,
// 1 thread, fraction of the 33 GFLOP/s AVX2 peak:
//   tet p = 2 / 5 / 10:  value_gradient  4.7 / 6.7 / 14.7 GFLOP/s (14% / 20% / 45%), i.e. 313k / 6.1k / 415
//                                        elements per CPU second (loaded wall clock: 125k / 2.4k / 165 elements/s);
//                        value           4.1 / 6.7 / 15.6 (12% / 20% / 47%);
//                        Hessian-vector  4.0 / 7.2 / 15.1 (12% / 22% / 46%);
//                        the dense products alone (one block, Eigen GEMM) 13 / 15 / 19 (40% / 47% / 57%);
//   tri p = 5 / 10:      value_gradient  6.0 / 10.3 (18% / 31%), Hessian-vector 6.8 / 9.8, dense alone 21 / 25.
// CPU time per quadrature point, tet p = 2 / 5 / 10: value_gradient 0.12 / 0.33 / 0.72 us; building the
// projected Hessian operator (hessian_operator_setup) 3.8 / 5.1 / 5.8 us, i.e. 8x-33x a gradient,
// dominated by the per-point work (measure Hessian, SVD-based PSD projection), not by dense products.
// At p = 10 the dense products are 98% of the modelled flops and the kernels run at 78-83% of the
// rate Eigen's GEMM reaches on the same shapes; at p = 2 the per-point measure work and the
// gathers dominate.
//
// Re-measured 2026-11-23 on an IDLE 2-core AMD EPYC guest (load 0.01; README, "the element kernels
// against the machine's peak"): AVX2 peak 49 GFLOP/s (512-bit via target attribute 102); tet
// value_gradient p = 2 / 5 / 10: 9.6 / 9.6 / 13.1 GFLOP/s (19% / 19% / 26%), Hessian-vector
// 12.4 / 11.6 / 16.8, dense products alone 35.5 / 49.0 / 46.1.
//
// 2026-12-01, an idle 2-core AMD EPYC guest without AVX-512 (FMA peak 18.7-21.4 GFLOP/s from run
// to run), after the value and value_gradient point loops went to four points at a time
// (detail/point_lanes.hpp, ShapeMeasure::value_gradient_lanes): tet value_gradient
// p = 2 / 5 / 10: 5.5 / 5.4 / 5.3 GFLOP/s against an 18.7 peak (29% / 29% / 28%; the medians of
// three repetitions 29% / 28% / 29%), where the per-point code measured 3.9 / 4.1 / 5.4 against
// 19.7 (20% / 21% / 27%) that morning; value 17.8 / 14.2 / 9.1 M points/s (was 14.0 / 11.8 / 9.1).
//
// Two groups of benchmarks:
//   1. fma_peak: the peak double-precision rate of this build's widest SIMD ISA
//      (AVX-512F, AVX2+FMA, SSE2, or scalar, from the compiler's __AVX512F__ /
//      __AVX2__ / __FMA__ macros; the label says which): independent chains
//      of packed FMAs, enough of them to cover the FMA latency on every FMA
//      port, so the loop is bound by FMA throughput alone. threads:1 and
//      threads:all (OpenMP). Counters: GFLOPs (measured, compiled ISA, per
//      second of wall time), GFLOPs_per_cpu_s (per CPU second of the process)
//      and, when the build is narrower than 512 bits,
//      GFLOPs_avx512_theoretical = GFLOPs x 512 / width: what the same FMA
//      throughput would give with 512-bit vectors (theoretical: some cores
//      issue 512-bit FMAs on fewer ports). fma_peak_avx512_runtime runs the
//      512-bit kernel through a target attribute when the CPU has AVX-512F
//      but the build does not use it: the AVX-512 peak actually measured,
//      which hom's code in a -march=x86-64-v3 build cannot reach.
//   2. value, value_gradient, hessian_operator_setup (problem.hessian_operator,
//      HessianForm::projected), hessian_vector_product (op.apply on the
//      operator built once), dense_products (the two products of one
//      evaluation block alone, Eigen only, 1 thread): OptimizationProblem's
//      evaluations (problem.hpp) on a structured mesh of tetrahedra
//      (p = 2, 5, 10) or triangles (p = 5, 10) elevated to p, its free
//      (interior) nodes moved by a small random valid perturbation, shape
//      measure, DefaultExactness quadrature, straight-sided ideal, 1 and 2
//      threads (problem.set_threads). Counters: elements_per_s and
//      points_per_s (quadrature points, per second of wall time),
//      cpu_us_per_point (process CPU time), GFLOPs (wall) and GFLOPs_per_cpu_s
//      from the FLOP model below, dense_flop_share (the dense products' part
//      of the model), peak_fraction = GFLOPs / (threads x 1-thread peak) and
//      peak_fraction_cpu = GFLOPs_per_cpu_s / 1-thread peak per CPU second,
//      the peaks being those of the compiled ISA measured at start-up (best of
//      5 runs, also in the JSON context as hom_peak_*). On a loaded machine
//      use the _cpu_ counters; with 2 threads they include OpenMP's spinning
//      at barriers, which makes them pessimistic for small elements.
//
// FLOP model (a multiply, an add, a divide and a cube root count 1 each, an
// FMA 2; n = nodes per element, nq = quadrature points, D = Dim):
//   - the two dense products per element, JP = X G ((D x n) (n x D nq)) and
//     grad = P G^T ((D x D nq) (D nq x n)), 2 D n D nq flops each:
//     dense = 2 * 2 * D * n * D * nq;
//   - value_gradient, per quadrature point (ShapeMeasure::value_gradient with
//     sigma_0; measure_point_flops_value_gradient itemizes it):
//     J = JP_q A 45, cof J 27, det 5, reg^(-2/3) and its derivative 6,
//     ||J||^2 / 3 18, (2/3) J 9, gradient 28, residual and f 6,
//     P_q = (c r) g A^T 55: 199 flops in 3D (67 in 2D);
//   - value: one dense product (2 D n D nq) and per point J 45, det 14,
//     ||J||^2 17, cube root and scaling 4, residual and f 5: 85 flops in 3D
//     (29 in 2D);
//   - hessian_vector_product (op.apply): the two dense products
//     (dJ = V G, out = S G^T) and per point M_q vec(dJ_q), D^2 (2 D^2 - 1)
//     flops (153 in 3D, 28 in 2D);
//   - hessian_operator_setup (measure Hessian, its PSD projection, traces):
//     no FLOP model, only elements/s, points/s and CPU time per point.
// Gathering nodes into blocks and summing element contributions per node
// move memory and are not counted.
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <map>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <time.h>

#include <Eigen/Core>
#include <benchmark/benchmark.h>

#if defined(_OPENMP)
#include <omp.h>
#endif
#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

#include "hom/mesh/elevate.hpp"
#include "hom/mesh/structured.hpp"
#include "hom/optimize/mesh_problem.hpp"

namespace {

using Tet = hom::Simplex<3>;
using Tri = hom::Simplex<2>;

// ---------------------------------------------------------------------------
// 1. Peak FMA throughput
// ---------------------------------------------------------------------------
// Each chain is acc = acc * m + a, m slightly below 1: the values converge to
// a / (1 - m) = 0.1 and never reach denormals or overflow, and no compiler can
// collapse the recurrence. Chains = latency (4 cycles) x FMA ports (2) x 1.5,
// kept under the register count (16 ymm, 32 zmm) so nothing spills.

constexpr double chain_multiplier = 0.999999;
constexpr double chain_addend = 1e-7;

#if defined(__AVX512F__)
constexpr const char* compiled_isa = "AVX-512F (512-bit FMA)";
constexpr int compiled_width = 8;
constexpr int compiled_chains = 24;
#elif defined(__AVX2__) && defined(__FMA__)
constexpr const char* compiled_isa = "AVX2+FMA (256-bit FMA)";
constexpr int compiled_width = 4;
constexpr int compiled_chains = 12;
#elif defined(__SSE2__)
constexpr const char* compiled_isa = "SSE2 (128-bit multiply + add, no FMA)";
constexpr int compiled_width = 2;
constexpr int compiled_chains = 12;
#else
constexpr const char* compiled_isa = "scalar (multiply + add)";
constexpr int compiled_width = 1;
constexpr int compiled_chains = 8;
#endif

// Sums through memory rather than _mm512_reduce_add_pd, which trips GCC 12's
// -Wuninitialized inside its own header.
#if defined(__AVX512F__)
double horizontal_sum(__m512d s) {
  alignas(64) double out[8];
  _mm512_store_pd(out, s);
  double t = 0.0;
  for (double x : out) t += x;
  return t;
}
#endif

/// `iters` steps of every chain; returns the sum of the chains (keeps them live).
double fma_kernel_compiled(long iters) {
#if defined(__AVX512F__)
  __m512d acc[compiled_chains];
  const __m512d m = _mm512_set1_pd(chain_multiplier), a = _mm512_set1_pd(chain_addend);
#pragma GCC unroll 32
  for (int k = 0; k < compiled_chains; ++k) acc[k] = _mm512_set1_pd(1.0 + 1e-3 * k);
  for (long i = 0; i < iters; ++i) {
#pragma GCC unroll 32
    for (int k = 0; k < compiled_chains; ++k) acc[k] = _mm512_fmadd_pd(acc[k], m, a);
  }
  __m512d s = acc[0];
  for (int k = 1; k < compiled_chains; ++k) s = _mm512_add_pd(s, acc[k]);
  return horizontal_sum(s);
#elif defined(__AVX2__) && defined(__FMA__)
  __m256d acc[compiled_chains];
  const __m256d m = _mm256_set1_pd(chain_multiplier), a = _mm256_set1_pd(chain_addend);
#pragma GCC unroll 32
  for (int k = 0; k < compiled_chains; ++k) acc[k] = _mm256_set1_pd(1.0 + 1e-3 * k);
  for (long i = 0; i < iters; ++i) {
#pragma GCC unroll 32
    for (int k = 0; k < compiled_chains; ++k) acc[k] = _mm256_fmadd_pd(acc[k], m, a);
  }
  __m256d s = acc[0];
  for (int k = 1; k < compiled_chains; ++k) s = _mm256_add_pd(s, acc[k]);
  alignas(32) double out[4];
  _mm256_store_pd(out, s);
  return out[0] + out[1] + out[2] + out[3];
#elif defined(__SSE2__)
  __m128d acc[compiled_chains];
  const __m128d m = _mm_set1_pd(chain_multiplier), a = _mm_set1_pd(chain_addend);
#pragma GCC unroll 32
  for (int k = 0; k < compiled_chains; ++k) acc[k] = _mm_set1_pd(1.0 + 1e-3 * k);
  for (long i = 0; i < iters; ++i) {
#pragma GCC unroll 32
    for (int k = 0; k < compiled_chains; ++k) acc[k] = _mm_add_pd(_mm_mul_pd(acc[k], m), a);
  }
  __m128d s = acc[0];
  for (int k = 1; k < compiled_chains; ++k) s = _mm_add_pd(s, acc[k]);
  alignas(16) double out[2];
  _mm_store_pd(out, s);
  return out[0] + out[1];
#else
  double acc[compiled_chains];
  for (int k = 0; k < compiled_chains; ++k) acc[k] = 1.0 + 1e-3 * k;
  for (long i = 0; i < iters; ++i)
    for (int k = 0; k < compiled_chains; ++k) acc[k] = acc[k] * chain_multiplier + chain_addend;
  double s = 0.0;
  for (double x : acc) s += x;
  return s;
#endif
}

constexpr double compiled_flops_per_iter = 2.0 * compiled_width * compiled_chains;

// The 512-bit kernel for builds narrower than AVX-512 on CPUs that have it
// (GCC/Clang on x86-64 only): compiled for avx512f through a target attribute,
// called only after __builtin_cpu_supports("avx512f").
#if !defined(__AVX512F__) && defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define HOM_BENCH_RUNTIME_AVX512 1
constexpr int avx512_chains = 24;
constexpr double avx512_flops_per_iter = 2.0 * 8 * avx512_chains;

__attribute__((target("avx512f"))) double horizontal_sum(__m512d s) {
  alignas(64) double out[8];
  _mm512_store_pd(out, s);
  double t = 0.0;
  for (double x : out) t += x;
  return t;
}

__attribute__((target("avx512f"))) double fma_kernel_avx512(long iters) {
  __m512d acc[avx512_chains];
  const __m512d m = _mm512_set1_pd(chain_multiplier), a = _mm512_set1_pd(chain_addend);
#pragma GCC unroll 32
  for (int k = 0; k < avx512_chains; ++k) acc[k] = _mm512_set1_pd(1.0 + 1e-3 * k);
  for (long i = 0; i < iters; ++i) {
#pragma GCC unroll 32
    for (int k = 0; k < avx512_chains; ++k) acc[k] = _mm512_fmadd_pd(acc[k], m, a);
  }
  __m512d s = acc[0];
  for (int k = 1; k < avx512_chains; ++k) s = _mm512_add_pd(s, acc[k]);
  return horizontal_sum(s);
}

bool cpu_has_avx512() {
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx512f");
}
#endif

int max_threads() {
#if defined(_OPENMP)
  return omp_get_max_threads();
#else
  return 1;
#endif
}

/// Runs kernel(iters) on `threads` threads at once; returns the sum of the results.
double run_on_threads(double (*kernel)(long), long iters, int threads) {
  double s = 0.0;
#if defined(_OPENMP)
#pragma omp parallel num_threads(threads) reduction(+ : s)
  s += kernel(iters);
#else
  (void)threads;
  s = kernel(iters);
#endif
  return s;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// CPU seconds used by the whole process (all threads) so far. On a loaded
/// machine the wall clock counts the time other processes hold the cores; a
/// rate per CPU second is what a core delivers while it runs this code.
double process_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

/// Wall and process-CPU time of a section.
struct Stopwatch {
  std::chrono::steady_clock::time_point wall0 = std::chrono::steady_clock::now();
  double cpu0 = process_cpu_seconds();
  double wall() const { return seconds_since(wall0); }
  double cpu() const { return process_cpu_seconds() - cpu0; }
};

struct Peak {
  double wall = 0.0;  ///< GFLOP/s per second of wall time
  double cpu = 0.0;   ///< GFLOP/s per CPU second
};

/// Best of 5 single-thread runs of about 30 ms each.
Peak measure_peak(double (*kernel)(long), double flops_per_iter) {
  const long iters = 1L << 20;
  Peak best;
  for (int r = 0; r < 5; ++r) {
    const Stopwatch t;
    benchmark::DoNotOptimize(kernel(iters));
    const double cpu = t.cpu(), wall = t.wall();
    best.wall = std::max(best.wall, flops_per_iter * iters / wall / 1e9);
    best.cpu = std::max(best.cpu, flops_per_iter * iters / cpu / 1e9);
  }
  return best;
}

// Measured at start-up (main): the denominators of peak_fraction(_cpu).
Peak peak_1thread;

void fma_benchmark(benchmark::State& state, double (*kernel)(long), double flops_per_iter, int width) {
  const int threads = static_cast<int>(state.range(0));
  const long iters = 1L << 20;
  const Stopwatch t;
  for (auto _ : state) benchmark::DoNotOptimize(run_on_threads(kernel, iters, threads));
  const double wall = t.wall(), cpu = t.cpu();
  const double flops = flops_per_iter * iters * threads * double(state.iterations());
  const double gflops = flops / wall / 1e9;
  state.counters["threads"] = threads;
  state.counters["simd_width"] = width;
  state.counters["chains"] = flops_per_iter / (2.0 * width);
  state.counters["GFLOPs"] = gflops;
  state.counters["GFLOPs_per_cpu_s"] = flops / cpu / 1e9;
  if (width < 8) state.counters["GFLOPs_avx512_theoretical"] = gflops * 8.0 / width;
}

void fma_peak(benchmark::State& state) {
  state.SetLabel(compiled_isa);
  fma_benchmark(state, fma_kernel_compiled, compiled_flops_per_iter, compiled_width);
}

// ---------------------------------------------------------------------------
// 2. The optimizer's element kernels
// ---------------------------------------------------------------------------

/// Per-quadrature-point flops of the measure work in value_gradient (the
/// itemized count of the file comment; ShapeMeasure, sigma_0, valid element).
constexpr double measure_point_flops_value_gradient(int D) {
  const int D2 = D * D;
  const double jacobian = D2 * (2 * D - 1);                 // J = JP_q A
  const double cofactor = D == 3 ? 27 : 0;                  // 3 products + 1 subtraction per entry (2D: signs only)
  const double det = 2 * D - 1;                             // row 0 of J . row 0 of cof J
  const double power = D == 3 ? 6 : 4;                      // reg^(-2/D): cube root, square, reciprocal, derivative
  const double phi = 2 * D2;                                // ||J||^2 / D
  const double grad_phi = D2;                               // (2 / D) J
  const double gradient = 3 * D2 + 1;                       // g grad_phi + (phi g') cof
  const double residual = 6;                                // eta, eta - 1, f += c r^2 / 2
  const double pull = 1 + D2 + D2 * (2 * D - 1);            // (c r) g A^T
  return jacobian + cofactor + det + power + phi + grad_phi + gradient + residual + pull;
}

/// value(): J, det (written out), ||J||^2, reg^(2/D) and the quotient, f.
constexpr double measure_point_flops_value(int D) {
  const int D2 = D * D;
  const double jacobian = D2 * (2 * D - 1);
  const double det = D == 3 ? 14 : 3;
  const double norm = 2 * D2 - 1;
  const double power = D == 3 ? 4 : 2;  // cube root, square, D * (.), division
  const double residual = 5;
  return jacobian + det + norm + power + residual;
}

/// op.apply: M_q (D^2 x D^2) times vec(dJ_q).
constexpr double hvp_point_flops(int D) { return D * D * (2.0 * D * D - 1); }

static_assert(measure_point_flops_value_gradient(3) == 199 && measure_point_flops_value_gradient(2) == 67);
static_assert(measure_point_flops_value(3) == 85 && measure_point_flops_value(2) == 29);

/// Cells per axis of the structured mesh: enough elements for several
/// evaluation blocks per thread (problem.hpp evaluates 16..128 elements per
/// block) and tens of milliseconds per evaluation.
template <class Family>
int cells_per_axis(int p) {
  if constexpr (Family::dim == 3)
    return p <= 2 ? 10 : (p <= 5 ? 6 : 4);
  else
    return p <= 5 ? 40 : 24;
}

template <class Family>
struct Case {
  using Problem = hom::OptimizationProblem<Family, hom::ShapeMeasure>;
  using Coordinates = typename Problem::Coordinates;

  explicit Case(int p) {
    constexpr int D = Family::dim;
    const int cells = cells_per_axis<Family>(p);
    std::array<int, D> n;
    n.fill(cells);
    auto mesh = hom::elevate(hom::structured_mesh<Family>(n), p);
    // Interior nodes moved by a small random amount so that the residuals
    // eta - 1 are non-zero (nothing trivially zero) while every element stays
    // valid: up to 5% of the nominal node spacing h / p per coordinate, halved
    // until the mesh is valid (at p = 10 the derivatives of the Lagrange basis
    // amplify nodal noise strongly near the clustered warp & blend nodes).
    const auto straight = mesh.nodes();
    std::mt19937 rng(12345);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    amplitude = 0.05 / (cells * p);
    for (int attempt = 0;; ++attempt, amplitude *= 0.5) {
      if (attempt == 12) throw std::runtime_error("bench_kernel: no valid perturbation of the mesh found");
      mesh.nodes() = straight;
      for (int i = 0; i < mesh.num_nodes(); ++i)
        if (mesh.node_class(i).kind == hom::NodeKind::free)
          for (int a = 0; a < D; ++a) mesh.nodes()(a, i) += amplitude * u(rng);
      problem = std::make_unique<Problem>(
          hom::make_problem<hom::ShapeMeasure, hom::DefaultExactness>(mesh, mesh.straight_sided_ideal()));
      X = problem->coordinates();
      if (problem->status(X).inverted == 0) break;
    }
    relative_amplitude = amplitude * cells * p;
    v = Eigen::VectorXd::NullaryExpr(problem->num_dofs(), [&] { return u(rng); });
    nodes = problem->nodes_per_element();
    points = problem->tabulation().num_points();
    elements = problem->num_elements();
  }

  std::unique_ptr<Problem> problem;
  Coordinates X;
  Eigen::VectorXd v;
  int nodes = 0, points = 0, elements = 0;
  double amplitude = 0.0;           ///< largest nodal displacement per coordinate
  double relative_amplitude = 0.0;  ///< the same in units of h / p
};

/// One problem per (family, p), built on first use (p = 10 takes seconds).
template <class Family>
Case<Family>& get_case(int p) {
  static std::map<int, std::unique_ptr<Case<Family>>> cache;
  auto& slot = cache[p];
  if (!slot) slot = std::make_unique<Case<Family>>(p);
  return *slot;
}

enum class Kernel { value, value_gradient, hessian_operator_setup, hessian_vector_product, dense_products };

/// Flops of one of the two products JP = X G, grad = P G^T for one element:
/// dense, or by sum factorization (tetrahedra, quality/sum_factorization.hpp).
template <class Problem>
double product_flops(const Problem& problem, int n, int nq) {
  constexpr int D = Problem::dim;
  if (problem.use_sum_factorization()) return 2.0 * D * problem.tabulation().sum_factorization->cost_per_row();
  return 2.0 * D * n * D * nq;
}

/// The products' part of flops_per_element.
inline double product_flops_per_element(Kernel k, double product) {
  return k == Kernel::value ? product : (k == Kernel::hessian_operator_setup ? 0.0 : 2 * product);
}

template <class Family>
double flops_per_element(Kernel k, double product, int nq) {
  constexpr int D = Family::dim;
  switch (k) {
    case Kernel::value: return product + nq * measure_point_flops_value(D);
    case Kernel::value_gradient: return 2 * product + nq * measure_point_flops_value_gradient(D);
    case Kernel::hessian_vector_product: return 2 * product + nq * hvp_point_flops(D);
    case Kernel::hessian_operator_setup: return 0.0;  // not modelled
    case Kernel::dense_products: return 2 * product;
  }
  return 0.0;
}

template <class Family>
void run_kernel(benchmark::State& state, Kernel kernel, bool sum_factorization = true) {
  const int p = static_cast<int>(state.range(0));
  const int threads = static_cast<int>(state.range(1));
  Case<Family>* c = nullptr;
  try {
    c = &get_case<Family>(p);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  auto& problem = *c->problem;
  problem.set_threads(threads);
  problem.set_sum_factorization(sum_factorization && kernel != Kernel::dense_products);
  Eigen::VectorXd g, out;
  typename Case<Family>::Problem::HessianOperator op;
  // dense_products: the two products of one evaluation block alone, with the
  // block size problem.hpp uses (65536 / n elements, clamped to 16..128), so
  // that the GEMM rate Eigen reaches on these shapes can be set beside the
  // kernels' rates. Timed per block, counted as `block` elements.
  const int block = std::clamp(65536 / c->nodes, 16, 128);
  const Eigen::MatrixXd& G = problem.tabulation().shape_gradients;
  Eigen::MatrixXd Xb, JP, P, Out;
  if (kernel == Kernel::dense_products) {
    Xb = Eigen::MatrixXd::Random(Family::dim * block, c->nodes);
    P = Eigen::MatrixXd::Random(Family::dim * block, G.cols());
  }
  const hom::detail::SerialEigenScope serial_eigen;
  if (kernel == Kernel::hessian_vector_product) problem.hessian_operator(c->X, hom::HessianForm::projected, g, op);

  const Stopwatch t;
  for (auto _ : state) {
    switch (kernel) {
      case Kernel::value: benchmark::DoNotOptimize(problem.value(c->X)); break;
      case Kernel::value_gradient:
        benchmark::DoNotOptimize(problem.value_gradient(c->X, g));
        benchmark::DoNotOptimize(g.data());
        break;
      case Kernel::hessian_operator_setup:
        benchmark::DoNotOptimize(problem.hessian_operator(c->X, hom::HessianForm::projected, g, op));
        break;
      case Kernel::hessian_vector_product:
        op.apply(c->v, out);
        benchmark::DoNotOptimize(out.data());
        break;
      case Kernel::dense_products:
        JP.noalias() = Xb * G;
        Out.noalias() = P * G.transpose();
        benchmark::DoNotOptimize(JP.data());
        benchmark::DoNotOptimize(Out.data());
        break;
    }
    benchmark::ClobberMemory();
  }
  const double wall = t.wall(), cpu = t.cpu();
  const double calls = double(state.iterations());
  const int elements = kernel == Kernel::dense_products ? block : c->elements;
  const double product = product_flops(problem, c->nodes, c->points);
  const double flops = flops_per_element<Family>(kernel, product, c->points) * elements;
  state.counters["p"] = p;
  state.counters["threads"] = threads;
  state.counters["elements"] = elements;
  state.counters["nodes_per_element"] = c->nodes;
  state.counters["points_per_element"] = c->points;
  state.counters["perturbation_h_over_p"] = c->relative_amplitude;
  state.counters["elements_per_s"] = elements * calls / wall;
  state.counters["points_per_s"] = double(elements) * c->points * calls / wall;
  state.counters["cpu_us_per_point"] = 1e6 * cpu / (double(elements) * c->points * calls);
  if (flops > 0.0) {
    const double gflops = flops * calls / wall / 1e9;
    const double gflops_cpu = flops * calls / cpu / 1e9;
    state.counters["GFLOPs"] = gflops;
    state.counters["GFLOPs_per_cpu_s"] = gflops_cpu;
    state.counters["flops_per_element"] = flops / elements;
    state.counters["product_flop_share"] = product_flops_per_element(kernel, product) * elements / flops;
    state.counters["sum_factorized"] = problem.use_sum_factorization() ? 1 : 0;
    if (peak_1thread.wall > 0.0) state.counters["peak_fraction"] = gflops / (threads * peak_1thread.wall);
    if (peak_1thread.cpu > 0.0) state.counters["peak_fraction_cpu"] = gflops_cpu / peak_1thread.cpu;
  }
}

template <class Family>
void value(benchmark::State& state) {
  run_kernel<Family>(state, Kernel::value);
}
template <class Family>
void value_gradient(benchmark::State& state) {
  run_kernel<Family>(state, Kernel::value_gradient);
}
template <class Family>
void hessian_operator_setup(benchmark::State& state) {
  run_kernel<Family>(state, Kernel::hessian_operator_setup);
}
template <class Family>
void hessian_vector_product(benchmark::State& state) {
  run_kernel<Family>(state, Kernel::hessian_vector_product);
}
/// The same two kernels with the dense products where sum factorization applies.
template <class Family>
void value_gradient_dense(benchmark::State& state) {
  run_kernel<Family>(state, Kernel::value_gradient, false);
}
template <class Family>
void hessian_vector_product_dense(benchmark::State& state) {
  run_kernel<Family>(state, Kernel::hessian_vector_product, false);
}
template <class Family>
void dense_products(benchmark::State& state) {
  run_kernel<Family>(state, Kernel::dense_products);
}

}  // namespace

namespace {

/// value_gradient<Tet>/p:10/threads:2 and so on, for 1 and 2 threads.
template <class Family>
void register_kernels(const std::string& family, const std::vector<std::int64_t>& degrees) {
  auto add = [&](const std::string& name, void (*fn)(benchmark::State&), std::vector<std::int64_t> threads = {1, 2}) {
    benchmark::RegisterBenchmark((name + "<" + family + ">").c_str(), fn)
        ->ArgsProduct({degrees, threads})
        ->ArgNames({"p", "threads"})
        ->UseRealTime()
        ->MeasureProcessCPUTime()
        ->Unit(benchmark::kMillisecond);
  };
  add("value_gradient", value_gradient<Family>);
  add("value", value<Family>);
  add("hessian_vector_product", hessian_vector_product<Family>);
  add("hessian_operator_setup", hessian_operator_setup<Family>);
  add("dense_products", dense_products<Family>, {1});
  if constexpr (Family::is_simplex && Family::dim == 3) {
    add("value_gradient_dense", value_gradient_dense<Family>);
    add("hessian_vector_product_dense", hessian_vector_product_dense<Family>);
  }
}

}  // namespace

int main(int argc, char** argv) {
  // The banner goes to stderr so that stdout stays valid JSON with --benchmark_format=json.
  std::fprintf(stderr, "bench_kernel: compiler %s %s, C++ %ld, %s%s\n",
#if defined(__clang__)
              "clang",
#else
              "gcc",
#endif
              __VERSION__, static_cast<long>(__cplusplus),
#ifdef __OPTIMIZE__
              "optimized",
#else
              "NOT optimized",
#endif
#ifdef NDEBUG
              ", NDEBUG"
#else
              ", assertions on"
#endif
  );
  std::fprintf(stderr, "Eigen %d.%d.%d, SIMD in use: %s, packet size (doubles): %d\n", EIGEN_WORLD_VERSION, EIGEN_MAJOR_VERSION,
              EIGEN_MINOR_VERSION, Eigen::SimdInstructionSetsInUse(),
              static_cast<int>(Eigen::internal::packet_traits<double>::size));

  const int all = max_threads();
  benchmark::RegisterBenchmark("fma_peak", fma_peak)->ArgName("threads")->Arg(1)->Arg(all)->UseRealTime()->MeasureProcessCPUTime();
  bool runtime_avx512 = false;
#ifdef HOM_BENCH_RUNTIME_AVX512
  runtime_avx512 = cpu_has_avx512();
  if (runtime_avx512)
    benchmark::RegisterBenchmark("fma_peak_avx512_runtime",
                                 [](benchmark::State& s) {
                                   s.SetLabel("AVX-512F via target attribute (not used by hom's code in this build)");
                                   fma_benchmark(s, fma_kernel_avx512, avx512_flops_per_iter, 8);
                                 })
        ->ArgName("threads")
        ->Arg(1)
        ->Arg(all)
        ->UseRealTime()
        ->MeasureProcessCPUTime();
#endif
  register_kernels<Tet>("Tet", {2, 5, 10});
  register_kernels<Tri>("Tri", {5, 10});

  peak_1thread = measure_peak(fma_kernel_compiled, compiled_flops_per_iter);
  std::fprintf(stderr, "FMA peak (%s), measured at start-up, best of 5, 1 thread: %.1f GFLOP/s (wall), %.1f GFLOP/s per CPU second; "
              "%.1f GFLOP/s per CPU second would be the theoretical 512-bit peak at the same FMA throughput\n",
              compiled_isa, peak_1thread.wall, peak_1thread.cpu, peak_1thread.cpu * 8.0 / compiled_width);
  benchmark::AddCustomContext("hom_isa", compiled_isa);
  benchmark::AddCustomContext("hom_simd_width_doubles", std::to_string(compiled_width));
  benchmark::AddCustomContext("hom_peak_gflops_1thread", std::to_string(peak_1thread.wall));
  benchmark::AddCustomContext("hom_peak_gflops_per_cpu_s_1thread", std::to_string(peak_1thread.cpu));
  benchmark::AddCustomContext("hom_peak_gflops_per_cpu_s_avx512_theoretical_1thread",
                              std::to_string(peak_1thread.cpu * 8.0 / compiled_width));
  benchmark::AddCustomContext("hom_cpu_has_avx512f_runtime", runtime_avx512 ? "yes" : "no (or not checked)");
  benchmark::AddCustomContext("hom_openmp_max_threads", std::to_string(all));
  benchmark::AddCustomContext("hom_eigen_simd", Eigen::SimdInstructionSetsInUse());

  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
