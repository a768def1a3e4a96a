#pragma once
/// @file sum_factorization.hpp
/// Jacobians of many tetrahedra at the points of a collapsed Gauss–Jacobi
/// rule by sum factorization, and the transposed product, in O(p^4) per
/// element instead of the O(p^6) of the dense product with the tabulation.
///
/// The optimizer's blocked kernels compute, for R rows (one per element and
/// coordinate) of nodal values X (R x n), every row's reference gradient at
/// every quadrature point, JP = X * G (G = Tabulation::shape_gradients, n x
/// 3 nq), and pull point data back to the nodes, out = P * G^T. At p = 10 G is
/// 286 x 10125 and each product costs 17 Mflop per row triple.
///
/// Sum factorization (Sherwin & Karniadakis; Orszag for tensor bases) uses
/// the structure of the orthonormal Dubiner basis of orthonormal.hpp in the
/// collapsed coordinates (a, b, c) of the rule (gauss.hpp: x = (1+a)(1-b)(1-c)/8,
/// y = (1+b)(1-c)/4, z = (1+c)/2):
///
///   psi_ijk = F_i(a) G_ij(b) H_ijk(c),   F_i = P_i,
///   G_ij(b)  = ((1-b)/2)^i P_j^(2i+1,0)(b),
///   H_ijk(c) = 8 2^(2i+j) ((1-c)/2)^(i+j) P_k^(2i+2j+2,0)(c),
///
/// (orthonormal Jacobi P as in jacobi.hpp). With the modal coefficients
/// C = X V^{-T} (the Lagrange basis is N = V^{-T} psi, lagrange.hpp), the
/// derivatives of phi in (a, b, c) at the tensor points come from three
/// one-dimensional contractions, k, then j, then i, each a small dense product
/// batched over the R rows; the derivatives in xi follow by the chain rule with
/// the inverse of d xi / d(a, b, c), a fixed 3 x 3 matrix per point (the rule's
/// points are interior, where the collapse is regular). Per row triple at p = 10
/// with 15^3 points this is about 1.7 Mflop instead of 17.
///
/// The transposed product runs the same stages backwards. Both reproduce the
/// dense products to round-off (test/test_sum_factorization.cpp).

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>

#include "hom/basis/jacobi.hpp"
#include "hom/basis/orthonormal.hpp"
#include "hom/element/simplex.hpp"
#include "hom/quadrature/gauss.hpp"
#include "hom/quadrature/quadrature_rule.hpp"

namespace hom {

class TetrahedronSumFactorization {
 public:
  /// Scratch space of one thread (reused between calls).
  struct Workspace {
    Eigen::MatrixXd modal, A, Ad, B0, Bb, Bc, S0, Sb, Sc, Phi[3];
  };

  /// `inverse_vandermonde_t` = V^{-T} (n x n, rows: nodes in the layout
  /// order, columns: modes in OrthonormalBasis order); `points_per_direction`
  /// of the collapsed rule.
  TetrahedronSumFactorization(int p, const Eigen::MatrixXd& inverse_vandermonde_t, int points_per_direction)
      : p_(p), n_(points_per_direction) {
    using Basis = OrthonormalBasis<Simplex<3>>;
    const auto modes = Basis::modes(p);
    const int m = int(modes.size());
    build_pair_offsets();
    // Modes grouped by (i, j), k fastest: pair (i, j) owns modal columns
    // pair_offset .. pair_offset + p - i - j.
    std::vector<int> column_of_mode(m);
    for (int q = 0; q < m; ++q) column_of_mode[q] = grouped_index(modes[q][0], modes[q][1], modes[q][2]);
    modal_.resize(inverse_vandermonde_t.rows(), m);
    for (int q = 0; q < m; ++q) modal_.col(column_of_mode[q]) = inverse_vandermonde_t.col(q);
    tabulate_factors();
    tabulate_chain_rule();
  }

  int degree() const { return p_; }
  int points_per_direction() const { return n_; }
  int num_points() const { return n_ * n_ * n_; }

  /// Multiply-adds per row of one product (either direction), for choosing
  /// between this and the dense product (n * 3 nq per row).
  double cost_per_row() const {
    const double n = n_, m = double(modal_.cols()), np = p_ + 1.0;
    const double pairs = (p_ + 1.0) * (p_ + 2.0) / 2.0;
    return modal_.rows() * m + 2.0 * m * n + 3.0 * pairs * n * n + 3.0 * n * n * np * n + 9.0 * n * n * n;
  }

  /// JP = X * G: X is R x n (rows: any functions in nodal form), JP is
  /// R x 3 nq with column 3 q + c = d/d xi_c at point q (the rule's order:
  /// a fastest, c slowest).
  void gradients(const Eigen::MatrixXd& X, Eigen::MatrixXd& JP, Workspace& w) const {
    const Eigen::Index R = X.rows();
    const int n = n_, np = p_ + 1;
    w.modal.noalias() = X * modal_;
    w.S0.resize(R * n * n, np);
    w.Sb.resize(R * n * n, np);
    w.Sc.resize(R * n * n, np);
    for (int i = 0; i <= p_; ++i) {
      const int nj = p_ - i + 1;
      w.A.resize(R * n, nj);
      w.Ad.resize(R * n, nj);
      // Stage 1 (contract k): A_ij(rho, r) = sum_k C_ijk H_ijk(c_r), and with H'.
      for (int j = 0; j < nj; ++j) {
        const int pr = pair_index(i, j);
        const auto C = w.modal.middleCols(pair_offset_[pr], p_ - i - j + 1);
        Eigen::Map<Eigen::MatrixXd>(w.A.col(j).data(), R, n).noalias() = C * H_[pr];
        Eigen::Map<Eigen::MatrixXd>(w.Ad.col(j).data(), R, n).noalias() = C * dH_[pr];
      }
      // Stage 2 (contract j): B_i(rho, r, q) = sum_j A_ij(rho, r) G_ij(b_q).
      Eigen::Map<Eigen::MatrixXd>(w.S0.col(i).data(), R * n, n).noalias() = w.A * G_[i];
      Eigen::Map<Eigen::MatrixXd>(w.Sb.col(i).data(), R * n, n).noalias() = w.A * dG_[i];
      Eigen::Map<Eigen::MatrixXd>(w.Sc.col(i).data(), R * n, n).noalias() = w.Ad * G_[i];
    }
    // Stage 3 (contract i): d phi / da, db, dc at (rho, r, q, p).
    w.Phi[0].noalias() = w.S0 * dF_;
    w.Phi[1].noalias() = w.Sb * F_;
    w.Phi[2].noalias() = w.Sc * F_;
    // Chain rule to d/d xi, reordering the points to the rule's order.
    JP.resize(R, 3 * num_points());
    for_each_point(R, [&](int pt, int a, Eigen::Index off, const Eigen::Matrix3d& M) {
          const auto da = w.Phi[0].col(a).segment(off, R);
          const auto db = w.Phi[1].col(a).segment(off, R);
          const auto dc = w.Phi[2].col(a).segment(off, R);
          for (int c = 0; c < 3; ++c) JP.col(3 * pt + c) = M(0, c) * da + M(1, c) * db + M(2, c) * dc;
    });
  }

  /// out = P * G^T: P is R x 3 nq in the layout of gradients(), out R x n.
  void gradients_transpose(const Eigen::MatrixXd& P, Eigen::MatrixXd& out, Workspace& w) const {
    const Eigen::Index R = P.rows();
    const int n = n_, np = p_ + 1;
    for (auto& phi : w.Phi) phi.resize(R * n * n, n);
    for_each_point(R, [&](int pt, int a, Eigen::Index off, const Eigen::Matrix3d& M) {
      const auto p0 = P.col(3 * pt), p1 = P.col(3 * pt + 1), p2 = P.col(3 * pt + 2);
      for (int d = 0; d < 3; ++d) w.Phi[d].col(a).segment(off, R) = M(d, 0) * p0 + M(d, 1) * p1 + M(d, 2) * p2;
    });
    w.S0.noalias() = w.Phi[0] * dF_.transpose();
    w.Sb.noalias() = w.Phi[1] * F_.transpose();
    w.Sc.noalias() = w.Phi[2] * F_.transpose();
    w.modal.resize(R, modal_.cols());
    for (int i = 0; i < np; ++i) {
      const int nj = p_ - i + 1;
      const auto S0 = Eigen::Map<const Eigen::MatrixXd>(w.S0.col(i).data(), R * n, n);
      const auto Sb = Eigen::Map<const Eigen::MatrixXd>(w.Sb.col(i).data(), R * n, n);
      const auto Sc = Eigen::Map<const Eigen::MatrixXd>(w.Sc.col(i).data(), R * n, n);
      w.A.noalias() = S0 * G_[i].transpose();
      w.A.noalias() += Sb * dG_[i].transpose();
      w.Ad.noalias() = Sc * G_[i].transpose();
      for (int j = 0; j < nj; ++j) {
        const int pr = pair_index(i, j);
        auto C = w.modal.middleCols(pair_offset_[pr], p_ - i - j + 1);
        C.noalias() = Eigen::Map<const Eigen::MatrixXd>(w.A.col(j).data(), R, n) * H_[pr].transpose();
        C.noalias() += Eigen::Map<const Eigen::MatrixXd>(w.Ad.col(j).data(), R, n) * dH_[pr].transpose();
      }
    }
    out.noalias() = w.modal * modal_.transpose();
  }

 private:
  // fn(pt, a, off, M) for every point: pt its index in the rule's order, a its
  // collapsed-a index, off the first row of its (r, q) block in the stage-3
  // layout (R rows per block), M = chain_[pt].
  template <class Fn>
  void for_each_point(Eigen::Index R, Fn&& fn) const {
    const int n = n_;
    for (int r = 0; r < n; ++r)
      for (int q = 0; q < n; ++q)
        for (int a = 0; a < n; ++a) {
          const int pt = a + n * q + n * n * r;
          fn(pt, a, R * (r + Eigen::Index(n) * q), chain_[pt]);
        }
  }

  // Index of the pair (i, j), i + j <= p, with j fastest.
  int pair_index(int i, int j) const { return i * (p_ + 1) - i * (i - 1) / 2 + j; }
  int grouped_index(int i, int j, int k) const { return pair_offset_[pair_index(i, j)] + k; }
  void build_pair_offsets() {
    int off = 0;
    for (int i = 0; i <= p_; ++i)
      for (int j = 0; j <= p_ - i; ++j) {
        pair_offset_.push_back(off);
        off += p_ - i - j + 1;
      }
  }

  void tabulate_factors() {
    const Rule1D ra = gauss_legendre(n_), rb = gauss_jacobi(n_, 1.0, 0.0), rc = gauss_jacobi(n_, 2.0, 0.0);
    const int np = p_ + 1;
    Eigen::VectorXd v(np), dv(np);
    F_.resize(np, n_);
    dF_.resize(np, n_);
    for (int s = 0; s < n_; ++s) {
      jacobi_normalized(p_, 0.0, 0.0, ra.points[s], v, dv);
      F_.col(s) = v;
      dF_.col(s) = dv;
    }
    for (int i = 0; i <= p_; ++i) {
      const int nj = p_ - i + 1;
      Eigen::MatrixXd g(nj, n_), dg(nj, n_);
      for (int s = 0; s < n_; ++s) {
        const double b = rb.points[s], t = 0.5 * (1.0 - b);
        jacobi_normalized(nj - 1, 2.0 * i + 1.0, 0.0, b, v.head(nj), dv.head(nj));
        const double ti = std::pow(t, i), dti = i > 0 ? -0.5 * i * std::pow(t, i - 1) : 0.0;
        g.col(s) = ti * v.head(nj);
        dg.col(s) = ti * dv.head(nj) + dti * v.head(nj);
      }
      G_.push_back(g);
      dG_.push_back(dg);
      for (int j = 0; j < nj; ++j) {
        const int nk = p_ - i - j + 1, e = i + j;
        const double scale = 8.0 * std::ldexp(1.0, 2 * i + j);
        Eigen::MatrixXd h(nk, n_), dh(nk, n_);
        for (int s = 0; s < n_; ++s) {
          const double c = rc.points[s], t = 0.5 * (1.0 - c);
          jacobi_normalized(nk - 1, 2.0 * e + 2.0, 0.0, c, v.head(nk), dv.head(nk));
          const double te = std::pow(t, e), dte = e > 0 ? -0.5 * e * std::pow(t, e - 1) : 0.0;
          h.col(s) = scale * te * v.head(nk);
          dh.col(s) = scale * (te * dv.head(nk) + dte * v.head(nk));
        }
        H_.push_back(h);
        dH_.push_back(dh);
      }
    }
  }

  // chain_[pt] = (d xi / d(a, b, c))^{-1}: d phi / d xi = (d phi / d(a,b,c)) * chain_.
  void tabulate_chain_rule() {
    const Rule1D ra = gauss_legendre(n_), rb = gauss_jacobi(n_, 1.0, 0.0), rc = gauss_jacobi(n_, 2.0, 0.0);
    chain_.resize(num_points());
    for (int r = 0; r < n_; ++r)
      for (int q = 0; q < n_; ++q)
        for (int s = 0; s < n_; ++s) {
          const double a = ra.points[s], b = rb.points[q], c = rc.points[r];
          Eigen::Matrix3d D;  // D(row = xi component, col = collapsed coordinate)
          D << (1 - b) * (1 - c) / 8, -(1 + a) * (1 - c) / 8, -(1 + a) * (1 - b) / 8,  //
              0, (1 - c) / 4, -(1 + b) / 4,                                          //
              0, 0, 0.5;
          chain_[s + n_ * q + n_ * n_ * r] = D.inverse();
        }
  }

  int p_, n_;
  std::vector<int> pair_offset_;  // first modal column of each pair (i, j)
  Eigen::MatrixXd modal_;  // n x m: V^{-T} with modes grouped by (i, j)
  Eigen::MatrixXd F_, dF_;                 // (p+1) x n
  std::vector<Eigen::MatrixXd> G_, dG_;   // per i: (p-i+1) x n
  std::vector<Eigen::MatrixXd> H_, dH_;   // per pair (i, j): (p-i-j+1) x n
  std::vector<Eigen::Matrix3d> chain_;
};

/// The sum factorization for a tetrahedral tabulation whose rule is hom's
/// collapsed Gauss–Jacobi rule (gauss_rule), or null where it does not apply
/// (other families or rules) or would not be cheaper than the dense product.
/// `inverse_vandermonde_t` = V^{-T} of the element's node set.
inline std::shared_ptr<const TetrahedronSumFactorization> make_tetrahedron_sum_factorization(
    int p, const Eigen::MatrixXd& inverse_vandermonde_t, const QuadratureRule<3>& rule) {
  const int nq = int(rule.points.size());
  const int n = int(std::lround(std::cbrt(double(nq))));
  if (n * n * n != nq || gauss_points_per_direction(rule.exactness) != n) return nullptr;
  const auto reference = gauss_rule<Simplex<3>>(rule.exactness);
  for (int q = 0; q < nq; ++q)
    if ((reference.points[q] - rule.points[q]).norm() > 1e-14) return nullptr;
  auto sf = std::make_shared<TetrahedronSumFactorization>(p, inverse_vandermonde_t, n);
  const double dense_cost = double(inverse_vandermonde_t.rows()) * 3.0 * nq;
  if (sf->cost_per_row() > 0.5 * dense_cost) return nullptr;
  return sf;
}

}  // namespace hom
