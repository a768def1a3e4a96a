#pragma once
/// @file point_lanes.hpp
/// Arithmetic on several quadrature points at once. The optimizer's
/// per-point work (a 3 x 3 Jacobian, its cofactors, a determinant, a power
/// of it and a gradient: about 200 flops a point in 3D) is the same
/// straight-line code at every point, so it runs on `point_lanes` points at
/// a time in structure-of-arrays form: a quantity x of the W points of a
/// batch is `double x[W]`, a matrix M is `double M[Dim * Dim][W]` (entry
/// (i, j) at row i + Dim j, column-major like Eigen), and every operation
/// is a loop over the lanes that the compiler turns into packed SIMD
/// instructions (W = 4 doubles fill an AVX2 register).
///
/// Done point by point, the same work ran at 1-2 flops per cycle: scalar
/// 3 x 3 products, a libm cube root (about 40 cycles) and three divisions
/// a point (bench_kernel, value_gradient<Tet> at p = 2: 19 % of the peak).

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#include "hom/detail/parallel.hpp"

/// Precedes a loop over the lanes of a batch: vectorize it.
#define HOM_LANES HOM_PRAGMA(omp simd)

namespace hom::detail {

/// Points per batch.
inline constexpr int point_lanes = 4;

/// y = s^(-1/3) in every lane, to a few ulps.
///
/// Newton's iteration for y^-3 = s, y <- y + (y / 3) (1 - s y^3)
/// (quadratic: relative error e -> about 2 e^2), started from the bit
/// estimate bits(y) = 0x553f09fc 00000000 - bits(s) / 3 on the high word
/// (the exponent field divided by -3, within 4 % for every positive normal
/// s), reaches full double precision in four steps: 4e-2, 3e-3, 2e-5,
/// 7e-10, 1e-18. Everything stays in 64-bit lanes (a division by 3 of a
/// 32-bit word is one widening multiply), so the loop is packed AVX2 code.
/// Lanes outside the positive normal range (zero, negative, subnormal,
/// infinite or NaN) are redone as 1 / std::cbrt(s) afterwards: +inf at 0,
/// the real root below 0.
template <int W>
void inverse_cube_root(const double (&s)[W], double (&y)[W]) {
  HOM_LANES
  for (int l = 0; l < W; ++l) {
    const std::uint32_t high = std::uint32_t(std::bit_cast<std::uint64_t>(s[l]) >> 32);
    const std::uint64_t third = (std::uint64_t(high) * 0xaaaaaaabull) >> 33;  // high / 3
    double v = std::bit_cast<double>((0x553f09fcull - third) << 32);
    for (int k = 0; k < 4; ++k) v += (v * (1.0 / 3.0)) * (1.0 - (s[l] * v) * (v * v));
    y[l] = v;
  }
  auto normal = [](double t) { return t >= std::numeric_limits<double>::min() && t <= std::numeric_limits<double>::max(); };
  bool all_normal = true;
  for (int l = 0; l < W; ++l) all_normal &= normal(s[l]);
  if (!all_normal)
    for (int l = 0; l < W; ++l)
      if (!normal(s[l])) y[l] = 1.0 / std::cbrt(s[l]);
}

}  // namespace hom::detail
