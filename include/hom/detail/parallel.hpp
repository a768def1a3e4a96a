#pragma once
/// @file parallel.hpp
/// OpenMP glue for the optimizer's loops. Headers stay usable without
/// -fopenmp: the pragmas vanish (no -Wunknown-pragmas) and everything runs
/// on one thread.
///
/// Determinism: every parallel loop in hom writes disjoint outputs (one slot
/// per element or per node) and every sum is taken afterwards in a fixed
/// order, so results do not depend on the number of threads. Eigen's own
/// GEMM parallelisation (enabled by -fopenmp) would choose its blocking by
/// thread count; `SerialEigenScope` switches it off while hom computes.

#include <algorithm>

#include <Eigen/Core>

#if defined(_OPENMP)
#include <omp.h>
#define HOM_PRAGMA(x) _Pragma(#x)
#else
#define HOM_PRAGMA(x)
#endif

/// `HOM_PARALLEL_FOR(threads) for (...)`: a statically scheduled parallel loop
/// with the given number of threads (>= 1).
#define HOM_PARALLEL_FOR(threads) HOM_PRAGMA(omp parallel for schedule(static) num_threads(threads))
/// The same with dynamic scheduling, for loops whose iterations differ in cost.
#define HOM_PARALLEL_FOR_DYNAMIC(threads) HOM_PRAGMA(omp parallel for schedule(dynamic, 16) num_threads(threads))
/// One iteration at a time, for a few expensive iterations (blocks of elements).
#define HOM_PARALLEL_FOR_EACH(threads) HOM_PRAGMA(omp parallel for schedule(dynamic, 1) num_threads(threads))

namespace hom::detail {

/// threads <= 0: OpenMP's default (OMP_NUM_THREADS or the number of cores).
inline int resolve_threads(int threads) {
  if (threads > 0) return threads;
#if defined(_OPENMP)
  return omp_get_max_threads();
#else
  return 1;
#endif
}

/// Threads worth starting for `items` independent work items of which one
/// thread should get at least `grain`: between 1 and `threads`. Small problems
/// run on one thread: waking OpenMP's team costs more than they do, and on a
/// loaded machine its spinning threads slowed an 8-dof solve a thousandfold.
inline int useful_threads(int threads, long long items, long long grain) {
  const long long n = grain > 0 ? items / grain : items;
  return int(std::max<long long>(1, std::min<long long>(threads, n)));
}

/// Eigen single-threaded for the lifetime of the scope (restored after).
class SerialEigenScope {
 public:
  SerialEigenScope() : saved_(Eigen::nbThreads()) { Eigen::setNbThreads(1); }
  ~SerialEigenScope() { Eigen::setNbThreads(saved_); }
  SerialEigenScope(const SerialEigenScope&) = delete;
  SerialEigenScope& operator=(const SerialEigenScope&) = delete;

 private:
  int saved_;
};

}  // namespace hom::detail
