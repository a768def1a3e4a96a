#pragma once
/// @file determinant.hpp
/// Determinant of a small fixed-size matrix with its first and second
/// derivatives, for the chain rule of the Jacobian-based measures.
///
///   d det(J) / dJ = cof(J)                      (cofactor matrix, = det(J) J^{-T} when invertible)
///   d^2 det(J) / dJ_ij dJ_kl                   (constant in 2D, linear in J in 3D)
///
/// Nothing here inverts J, so every formula holds for singular and inverted J.
/// Matrices are flattened column-major: entry (i, j) has index i + Dim * j
/// (Eigen's default storage, so Eigen::Map over .data() is the flattening).

#include <Eigen/Core>

#include "hom/detail/point_lanes.hpp"

namespace hom::detail {

template <int Dim>
using SquareMatrix = Eigen::Matrix<double, Dim, Dim>;

template <int Dim>
using FlatHessian = Eigen::Matrix<double, Dim * Dim, Dim * Dim>;

/// Flattened index of entry (i, j).
template <int Dim>
constexpr int flat_index(int i, int j) {
  return i + Dim * j;
}

/// cof(J) = d det(J) / dJ.
template <int Dim>
SquareMatrix<Dim> cofactor(const SquareMatrix<Dim>& J) {
  static_assert(Dim == 2 || Dim == 3, "hom::detail::cofactor: only 2x2 and 3x3 Jacobians");
  SquareMatrix<Dim> C;
  if constexpr (Dim == 2) {
    C << J(1, 1), -J(1, 0),
        -J(0, 1), J(0, 0);
  } else {
    // det J = r0 . (r1 x r2) with r_i the rows, so row i of cof J is the cross
    // product of the two other rows in cyclic order: r1 x r2, r2 x r0, r0 x r1.
    for (int i = 0; i < 3; ++i) {
      const int a = (i + 1) % 3, b = (i + 2) % 3;
      C(i, 0) = J(a, 1) * J(b, 2) - J(a, 2) * J(b, 1);
      C(i, 1) = J(a, 2) * J(b, 0) - J(a, 0) * J(b, 2);
      C(i, 2) = J(a, 0) * J(b, 1) - J(a, 1) * J(b, 0);
    }
  }
  return C;
}

/// cof(J) in W lanes (point_lanes.hpp: J and C are Dim^2 x W, row i + Dim j
/// entry (i, j)), the same products as cofactor().
template <int Dim, int W>
void cofactor_lanes(const double (&J)[Dim * Dim][W], double (&C)[Dim * Dim][W]) {
  static_assert(Dim == 2 || Dim == 3, "hom::detail::cofactor_lanes: only 2x2 and 3x3 Jacobians");
  auto at = [](int i, int j) { return i + Dim * j; };
  HOM_LANES
  for (int l = 0; l < W; ++l) {
    if constexpr (Dim == 2) {
      C[at(0, 0)][l] = J[at(1, 1)][l];
      C[at(0, 1)][l] = -J[at(1, 0)][l];
      C[at(1, 0)][l] = -J[at(0, 1)][l];
      C[at(1, 1)][l] = J[at(0, 0)][l];
    } else {
      for (int i = 0; i < 3; ++i) {
        const int a = (i + 1) % 3, b = (i + 2) % 3;
        C[at(i, 0)][l] = J[at(a, 1)][l] * J[at(b, 2)][l] - J[at(a, 2)][l] * J[at(b, 1)][l];
        C[at(i, 1)][l] = J[at(a, 2)][l] * J[at(b, 0)][l] - J[at(a, 0)][l] * J[at(b, 2)][l];
        C[at(i, 2)][l] = J[at(a, 0)][l] * J[at(b, 1)][l] - J[at(a, 1)][l] * J[at(b, 0)][l];
      }
    }
  }
}

/// det(J) in W lanes (J as in cofactor_lanes), the operations of determinant().
template <int Dim, int W>
void determinant_lanes(const double (&J)[Dim * Dim][W], double (&det)[W]) {
  static_assert(Dim == 2 || Dim == 3, "hom::detail::determinant_lanes: only 2x2 and 3x3 Jacobians");
  auto at = [](int i, int j) { return i + Dim * j; };
  HOM_LANES
  for (int l = 0; l < W; ++l) {
    if constexpr (Dim == 2) {
      det[l] = J[at(0, 0)][l] * J[at(1, 1)][l] - J[at(0, 1)][l] * J[at(1, 0)][l];
    } else {
      det[l] = J[at(0, 0)][l] * (J[at(1, 1)][l] * J[at(2, 2)][l] - J[at(1, 2)][l] * J[at(2, 1)][l]) +
               J[at(0, 1)][l] * (J[at(1, 2)][l] * J[at(2, 0)][l] - J[at(1, 0)][l] * J[at(2, 2)][l]) +
               J[at(0, 2)][l] * (J[at(1, 0)][l] * J[at(2, 1)][l] - J[at(1, 1)][l] * J[at(2, 0)][l]);
    }
  }
}

/// det(J) from its cofactors (Laplace expansion along row 0), so that the
/// determinant and its gradient are exactly consistent.
template <int Dim>
double determinant_from_cofactor(const SquareMatrix<Dim>& J, const SquareMatrix<Dim>& C) {
  return J.row(0).dot(C.row(0));
}

/// det(J) written out (no Eigen/LU dependency; same operations as the cofactor expansion).
template <int Dim>
double determinant(const SquareMatrix<Dim>& J) {
  static_assert(Dim == 2 || Dim == 3, "hom::detail::determinant: only 2x2 and 3x3 Jacobians");
  if constexpr (Dim == 2) {
    return J(0, 0) * J(1, 1) - J(0, 1) * J(1, 0);
  } else {
    return J(0, 0) * (J(1, 1) * J(2, 2) - J(1, 2) * J(2, 1)) +
           J(0, 1) * (J(1, 2) * J(2, 0) - J(1, 0) * J(2, 2)) +
           J(0, 2) * (J(1, 0) * J(2, 1) - J(1, 1) * J(2, 0));
  }
}

/// Levi-Civita symbol on {0, 1, 2}.
constexpr int levi_civita(int i, int j, int k) {
  return (i - j) * (j - k) * (k - i) / 2;
}

/// hess += scale * d^2 det(J) / dJ^2 (column-major flattening).
///   2D: d^2 det / dJ00 dJ11 = 1, d^2 det / dJ01 dJ10 = -1, others 0;
///   3D: d^2 det / dJ_ij dJ_kl = eps_{ika} eps_{jlb} J_ab  (a, b the remaining indices).
template <int Dim>
void add_determinant_hessian(const SquareMatrix<Dim>& J, double scale, FlatHessian<Dim>& hess) {
  static_assert(Dim == 2 || Dim == 3, "hom::detail::add_determinant_hessian: only 2x2 and 3x3 Jacobians");
  if constexpr (Dim == 2) {
    const int i00 = flat_index<2>(0, 0), i11 = flat_index<2>(1, 1);
    const int i01 = flat_index<2>(0, 1), i10 = flat_index<2>(1, 0);
    hess(i00, i11) += scale;
    hess(i11, i00) += scale;
    hess(i01, i10) -= scale;
    hess(i10, i01) -= scale;
  } else {
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i)
        for (int l = 0; l < 3; ++l)
          for (int k = 0; k < 3; ++k) {
            if (i == k || j == l) continue;
            const int a = 3 - i - k, b = 3 - j - l;
            hess(flat_index<3>(i, j), flat_index<3>(k, l)) +=
                scale * levi_civita(i, k, a) * levi_civita(j, l, b) * J(a, b);
          }
  }
}

}  // namespace hom::detail
