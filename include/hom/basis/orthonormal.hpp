#pragma once
/// @file orthonormal.hpp
/// L2-orthonormal polynomial bases of degree p on hom's reference elements:
/// the modal basis behind the Vandermonde matrices and the Lagrange shape
/// functions of appendix A (eq A.1).
///
/// Simplex<Dim> (reference: the unit simplex, vertices 0, e1, e2[, e3]):
/// the Dubiner / Koornwinder basis of the complete space P_p,
///
///   triangle:    psi_ij  = 2 sqrt(2) 2^i         Q_i^(0,0)(U1, T1) P_j^(2i+1,0)(2y - 1)
///   tetrahedron: psi_ijk = 8         2^(2i + j)  Q_i^(0,0)(U1, T1) Q_j^(2i+1,0)(U2, T2)
///                                                 P_k^(2i+2j+2,0)(2z - 1)
///
/// with T1 = 1 - y (- z), U1 = 2x - T1, T2 = 1 - z, U2 = 2y - T2, P_n the
/// orthonormal Jacobi polynomials and Q_n(u, t) = t^n P_n(u / t) their scaled
/// form (jacobi.hpp). This is the usual collapsed-coordinate construction
/// (Hesthaven & Warburton, "Nodal Discontinuous Galerkin Methods", eqs 6.6 and
/// 10.4, on the biunit simplex) mapped to the unit simplex: the collapsed
/// coordinates are a = U1 / T1, b = U2 / T2 (or 2y - 1 in 2D) and the factors
/// (1 - b)^i, (1 - c)^(i+j) are absorbed into the scaled polynomials, so no
/// division by T1 or T2 ever happens. Values and gradients are therefore exact
/// everywhere, the collapsed (top) vertices included, with no special cases.
/// The factor 2 (triangle) or 2 sqrt(2) (tetrahedron) rescales the biunit
/// orthonormal basis to the unit simplex's measure.
///
/// Cube<Dim> (reference [-1, 1]^Dim): tensor products of orthonormal Legendre
/// polynomials, psi_ijk = P_i(x) P_j(y) P_k(z), all indices 0..p (the space Q_p).
///
/// Mode order (fixed, shared by every user of the basis):
///   - simplices: by total degree n = i + j (+ k); within one degree, the last
///     index is the slowest: triangle (n, j) -> n(n+1)/2 + j with i = n - j;
///     tetrahedron (n, k, j) with i = n - j - k. So the first size(q) modes
///     span P_q for every q <= p (hierarchical).
///   - cubes: lexicographic, first index fastest: i + (p+1) j + (p+1)^2 k.
/// `modes(p)` returns the multi-index of every mode in this order.

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "hom/basis/jacobi.hpp"
#include "hom/element/family.hpp"

namespace hom {

template <ElementFamily Family>
struct OrthonormalBasis {
  static constexpr int dim = Family::dim;
  using Point = typename Family::Point;
  using Gradient = Eigen::Matrix<double, Eigen::Dynamic, dim>;

  /// Largest degree accepted (the scratch buffers live on the stack; far beyond
  /// where a Vandermonde-based Lagrange basis is useful anyway).
  static constexpr int max_degree = 48;

  /// Number of modes: dim P_p or dim Q_p, equal to Family::num_nodes(p).
  static int size(int p) { return Family::num_nodes(p); }

  /// Multi-index of each mode, in basis order.
  static std::vector<std::array<int, dim>> modes(int p) {
    std::vector<std::array<int, dim>> m;
    m.reserve(size(p));
    if constexpr (Family::is_simplex) {
      for (int n = 0; n <= p; ++n) {
        if constexpr (dim == 2) {
          for (int j = 0; j <= n; ++j) m.push_back({n - j, j});
        } else {
          for (int k = 0; k <= n; ++k)
            for (int j = 0; j <= n - k; ++j) m.push_back({n - j - k, j, k});
        }
      }
    } else {
      std::array<int, dim> idx{};
      for (int id = 0; id < size(p); ++id) {
        int r = id;
        for (int d = 0; d < dim; ++d) {
          idx[d] = r % (p + 1);
          r /= p + 1;
        }
        m.push_back(idx);
      }
    }
    return m;
  }

  /// Polynomial degree of each mode: total degree (simplex) or max index (cube).
  static std::vector<int> mode_degrees(int p) {
    std::vector<int> deg;
    for (const auto& m : modes(p)) {
      int d = 0;
      for (int c : m) d = Family::is_simplex ? d + c : std::max(d, c);
      deg.push_back(d);
    }
    return deg;
  }

  /// out[j] = psi_j(x), j = 0..size(p)-1.
  static void evaluate(int p, const Point& x, Eigen::Ref<Eigen::VectorXd> out) {
    check(p, out.size());
    compute<false>(p, x, out.data(), nullptr);
  }

  /// out(j, k) = d psi_j / d x_k.
  static void gradient(int p, const Point& x, Eigen::Ref<Gradient> out) {
    check(p, out.rows());
    Scratch values(size(p));
    compute<true>(p, x, values.data(), &out);
  }

  /// Values and gradients together (one pass).
  static void evaluate_with_gradient(int p, const Point& x, Eigen::Ref<Eigen::VectorXd> values,
                                     Eigen::Ref<Gradient> grad) {
    check(p, values.size());
    check(p, grad.rows());
    compute<true>(p, x, values.data(), &grad);
  }

 private:
  using Vec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, max_degree + 1, 1>;
  using Scratch = Eigen::VectorXd;

  static void check(int p, Eigen::Index rows) {
    if (p < 0 || p > max_degree)
      throw std::invalid_argument("hom::OrthonormalBasis: degree " + std::to_string(p) + " outside [0, " +
                                  std::to_string(max_degree) + "]");
    if (rows != size(p))
      throw std::invalid_argument("hom::OrthonormalBasis: output has " + std::to_string(rows) + " rows, need " +
                                  std::to_string(size(p)));
  }

  template <bool WithGradient>
  static void compute(int p, const Point& x, double* val, Eigen::Ref<Gradient>* grad) {
    if constexpr (!Family::is_simplex)
      compute_cube<WithGradient>(p, x, val, grad);
    else if constexpr (dim == 2)
      compute_triangle<WithGradient>(p, x, val, grad);
    else
      compute_tetrahedron<WithGradient>(p, x, val, grad);
  }

  template <bool WithGradient>
  static void compute_cube(int p, const Point& x, double* val, Eigen::Ref<Gradient>* grad) {
    std::array<Vec, dim> f, df;
    for (int d = 0; d < dim; ++d) {
      f[d].setZero(p + 1);
      df[d].setZero(p + 1);
      if constexpr (WithGradient)
        jacobi_normalized(p, 0.0, 0.0, x[d], f[d], df[d]);
      else
        jacobi_normalized(p, 0.0, 0.0, x[d], f[d]);
    }
    const int n1 = p + 1;
    const int nk = dim == 3 ? n1 : 1;
    int id = 0;
    for (int k = 0; k < nk; ++k) {
      const double fk = dim == 3 ? f[dim - 1][k] : 1.0;
      for (int j = 0; j < n1; ++j) {
        const double fjk = f[1][j] * fk;
        for (int i = 0; i < n1; ++i, ++id) {
          val[id] = f[0][i] * fjk;
          if constexpr (WithGradient) {
            auto& g = *grad;
            g(id, 0) = df[0][i] * fjk;
            g(id, 1) = f[0][i] * df[1][j] * fk;
            if constexpr (dim == 3) g(id, 2) = f[0][i] * f[1][j] * df[2][k];
          }
        }
      }
    }
  }

  template <bool WithGradient>
  static void compute_triangle(int p, const Point& x, double* val, Eigen::Ref<Gradient>* grad) {
    const double t1 = 1.0 - x[1];
    const double u1 = 2.0 * x[0] - t1;
    const double b = 2.0 * x[1] - 1.0;
    // Zero-initialised: the recurrences fill them, but the compiler cannot see it.
    Vec qa = Vec::Zero(p + 1), qa_u = Vec::Zero(p + 1), qa_t = Vec::Zero(p + 1), pb = Vec::Zero(p + 1),
        pb_d = Vec::Zero(p + 1);
    if constexpr (WithGradient)
      scaled_jacobi_normalized(p, 0.0, 0.0, u1, t1, qa, qa_u, qa_t);
    else
      scaled_jacobi_normalized(p, 0.0, 0.0, u1, t1, qa);
    const double c0 = 2.0 * std::sqrt(2.0);
    for (int i = 0; i <= p; ++i) {
      const int nj = p - i;
      auto b_i = pb.head(nj + 1);
      auto bd_i = pb_d.head(nj + 1);
      if constexpr (WithGradient)
        jacobi_normalized(nj, 2.0 * i + 1.0, 0.0, b, b_i, bd_i);
      else
        jacobi_normalized(nj, 2.0 * i + 1.0, 0.0, b, b_i);
      const double ci = std::ldexp(c0, i);
      for (int j = 0; j <= nj; ++j) {
        const int n = i + j;
        const int id = n * (n + 1) / 2 + j;
        val[id] = ci * qa[i] * pb[j];
        if constexpr (WithGradient) {
          // d/dx: U1_x = 2; d/dy: U1_y = 1, T1_y = -1, b_y = 2.
          auto& g = *grad;
          g(id, 0) = ci * 2.0 * qa_u[i] * pb[j];
          g(id, 1) = ci * ((qa_u[i] - qa_t[i]) * pb[j] + 2.0 * qa[i] * pb_d[j]);
        }
      }
    }
  }

  template <bool WithGradient>
  static void compute_tetrahedron(int p, const Point& x, double* val, Eigen::Ref<Gradient>* grad) {
    const double t1 = 1.0 - x[1] - x[2];
    const double u1 = 2.0 * x[0] - t1;
    const double t2 = 1.0 - x[2];
    const double u2 = 2.0 * x[1] - t2;
    const double c = 2.0 * x[2] - 1.0;
    Vec qa = Vec::Zero(p + 1), qa_u = Vec::Zero(p + 1), qa_t = Vec::Zero(p + 1);
    if constexpr (WithGradient)
      scaled_jacobi_normalized(p, 0.0, 0.0, u1, t1, qa, qa_u, qa_t);
    else
      scaled_jacobi_normalized(p, 0.0, 0.0, u1, t1, qa);
    // The third factor depends on (i, j) only through m = i + j: tabulate it
    // once per m. Row m of pc holds P_k^(2m+2,0)(c), k = 0..p-m.
    using Table = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, max_degree + 1, max_degree + 1>;
    Table pc = Table::Zero(p + 1, p + 1), pc_d = Table::Zero(p + 1, p + 1);
    {
      Vec tmp = Vec::Zero(p + 1), tmp_d = Vec::Zero(p + 1);
      for (int m = 0; m <= p; ++m) {
        const int nk = p - m;
        auto v = tmp.head(nk + 1);
        auto vd = tmp_d.head(nk + 1);
        if constexpr (WithGradient)
          jacobi_normalized(nk, 2.0 * m + 2.0, 0.0, c, v, vd);
        else
          jacobi_normalized(nk, 2.0 * m + 2.0, 0.0, c, v);
        pc.row(m).head(nk + 1) = v.transpose();
        if constexpr (WithGradient) pc_d.row(m).head(nk + 1) = vd.transpose();
      }
    }
    Vec qb = Vec::Zero(p + 1), qb_u = Vec::Zero(p + 1), qb_t = Vec::Zero(p + 1);
    for (int i = 0; i <= p; ++i) {
      const int nj = p - i;
      auto b = qb.head(nj + 1);
      auto b_u = qb_u.head(nj + 1);
      auto b_t = qb_t.head(nj + 1);
      if constexpr (WithGradient)
        scaled_jacobi_normalized(nj, 2.0 * i + 1.0, 0.0, u2, t2, b, b_u, b_t);
      else
        scaled_jacobi_normalized(nj, 2.0 * i + 1.0, 0.0, u2, t2, b);
      for (int j = 0; j <= nj; ++j) {
        const int m = i + j;
        const double cij = std::ldexp(8.0, 2 * i + j);
        const double ab = cij * qa[i] * qb[j];
        for (int k = 0; k <= p - m; ++k) {
          const int n = m + k;
          const int id = n * (n + 1) * (n + 2) / 6 + k * (n + 1) - k * (k - 1) / 2 + j;
          val[id] = ab * pc(m, k);
          if constexpr (WithGradient) {
            // U1 = 2x + y + z - 1, T1 = 1 - y - z, U2 = 2y + z - 1, T2 = 1 - z, c = 2z - 1.
            auto& g = *grad;
            const double a_x = 2.0 * qa_u[i];
            const double a_yz = qa_u[i] - qa_t[i];
            const double b_y = 2.0 * qb_u[j];
            const double b_z = qb_u[j] - qb_t[j];
            g(id, 0) = cij * a_x * qb[j] * pc(m, k);
            g(id, 1) = cij * (a_yz * qb[j] + qa[i] * b_y) * pc(m, k);
            g(id, 2) = cij * ((a_yz * qb[j] + qa[i] * b_z) * pc(m, k) + qa[i] * qb[j] * 2.0 * pc_d(m, k));
          }
        }
      }
    }
  }
};

}  // namespace hom
