#pragma once
/// @file element_objective.hpp
/// One element's contribution to the objective of eq 4.10,
///
///     f_e(X) = 1/2 || M_delta phi_E - 1 ||^2_{E^I}
///            = 1/2 sum_q c_q (eta(J_q) - 1)^2,      c_q = w_q |det D phi_I(xi_q)|,
///
/// with J_q = D phi_E(xi_q) = X G_q A_q, A_q = (D phi_I(xi_q))^{-1} (eq A.2), and
/// its gradient and Hessian with respect to the element's node coordinates X
/// (Dim x n). The Jacobian is linear in X, so everything follows from the
/// measure's derivatives in J by the chain rule:
///
///     d eta / dX      = (d eta/dJ) A^T G_q^T
///     d^2 f / dX dX   = sum_q c_q [ g g^T + (eta - 1) H_eta ]  pulled back through J = X G_q A_q.
///
/// Coordinates are flattened node-major: entry (a, i) of X (coordinate a of
/// node i) has index a + Dim * i, the storage order of a column-major X.
///
/// `project_hessian` replaces each quadrature point's Dim^2 x Dim^2 block by
/// its positive semi-definite part (eigenvalues clamped at 0) before the pull
/// back, so the element Hessian is positive semi-definite: the modification
/// for indefinite Hessians used by the Newton solvers.

#include <cmath>
#include <limits>

#include <Eigen/Dense>

#include "hom/measure/distortion_measure.hpp"
#include "hom/measure/regularization.hpp"
#include "hom/quality/ideal.hpp"
#include "hom/quality/tabulation.hpp"

namespace hom {

template <int Dim>
using ElementGradient = Eigen::Matrix<double, Dim, Eigen::Dynamic>;

/// Ideal data of one element at the quadrature points.
template <int Dim>
struct IdealAtPoints {
  std::vector<Eigen::Matrix<double, Dim, Dim>> inverse_jacobian;  ///< A_q = (D phi_I(xi_q))^{-1}
  std::vector<double> weight;                                     ///< c_q = w_q |det D phi_I(xi_q)|
};

template <ElementFamily Family>
IdealAtPoints<Family::dim> ideal_at_points(const Tabulation<Family>& tab, const IdealVertices<Family>& ideal) {
  IdealAtPoints<Family::dim> r;
  const int nq = tab.num_points();
  r.inverse_jacobian.resize(nq);
  r.weight.resize(nq);
  for (int q = 0; q < nq; ++q) {
    const Eigen::Matrix<double, Family::dim, Family::dim> Ji = ideal * tab.vertex_gradients[q];
    r.inverse_jacobian[q] = Ji.inverse();
    r.weight[q] = tab.rule.weights[q] * std::abs(Ji.determinant());
  }
  return r;
}

namespace detail {

// Positive semi-definite part of a small symmetric matrix.
template <int N>
Eigen::Matrix<double, N, N> psd_part(const Eigen::Matrix<double, N, N>& M) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> es(M);
  const Eigen::Matrix<double, N, 1> lambda = es.eigenvalues().cwiseMax(0.0);
  return es.eigenvectors() * lambda.asDiagonal() * es.eigenvectors().transpose();
}

}  // namespace detail

/// f_e; +inf if some eta is infinite (an invalid element under sigma_0).
template <ElementFamily Family, class Measure, DeterminantRegularization Reg>
double element_objective(const Tabulation<Family>& tab, const Eigen::Ref<const Eigen::Matrix<double, Family::dim, Eigen::Dynamic>>& X,
                         const IdealAtPoints<Family::dim>& ideal, const Measure& measure, const Reg& reg) {
  constexpr int D = Family::dim;
  using Mat = Eigen::Matrix<double, D, D>;
  const Eigen::Matrix<double, D, Eigen::Dynamic> JP = X * tab.shape_gradients;
  double f = 0.0;
  for (int q = 0; q < tab.num_points(); ++q) {
    const double eta = measure.value(Mat(JP.template middleCols<D>(q * D) * ideal.inverse_jacobian[q]), reg);
    f += 0.5 * ideal.weight[q] * (eta - 1.0) * (eta - 1.0);
  }
  return f;
}

/// f_e and its gradient (Dim x n, same layout as X).
template <ElementFamily Family, class Measure, DeterminantRegularization Reg>
double element_objective_gradient(const Tabulation<Family>& tab,
                                  const Eigen::Ref<const Eigen::Matrix<double, Family::dim, Eigen::Dynamic>>& X,
                                  const IdealAtPoints<Family::dim>& ideal, const Measure& measure, const Reg& reg,
                                  ElementGradient<Family::dim>& grad) {
  constexpr int D = Family::dim;
  using Mat = Eigen::Matrix<double, D, D>;
  const int nq = tab.num_points();
  const Eigen::Matrix<double, D, Eigen::Dynamic> JP = X * tab.shape_gradients;
  Eigen::Matrix<double, D, Eigen::Dynamic> P(D, D * nq);
  double f = 0.0;
  for (int q = 0; q < nq; ++q) {
    const Mat& A = ideal.inverse_jacobian[q];
    Mat g;
    const double eta = measure.value_gradient(Mat(JP.template middleCols<D>(q * D) * A), reg, g);
    const double r = eta - 1.0;
    f += 0.5 * ideal.weight[q] * r * r;
    P.template middleCols<D>(q * D) = (ideal.weight[q] * r) * g * A.transpose();
  }
  grad.noalias() = P * tab.shape_gradients.transpose();
  return f;
}

/// f_e, its gradient and its Hessian ((Dim n) x (Dim n), node-major).
template <ElementFamily Family, class Measure, DeterminantRegularization Reg>
double element_objective_hessian(const Tabulation<Family>& tab,
                                 const Eigen::Ref<const Eigen::Matrix<double, Family::dim, Eigen::Dynamic>>& X,
                                 const IdealAtPoints<Family::dim>& ideal, const Measure& measure, const Reg& reg,
                                 ElementGradient<Family::dim>& grad, Eigen::MatrixXd& hess, bool project_hessian) {
  constexpr int D = Family::dim;
  constexpr int D2 = D * D;
  using Mat = Eigen::Matrix<double, D, D>;
  using Mat2 = Eigen::Matrix<double, D2, D2>;
  const int nq = tab.num_points();
  const int n = tab.num_nodes();
  const Eigen::Matrix<double, D, Eigen::Dynamic> JP = X * tab.shape_gradients;
  Eigen::Matrix<double, D, Eigen::Dynamic> P(D, D * nq);
  // Per quadrature point, the Hessian in J_P = X G_q coordinates (vec column-major).
  std::vector<Mat2> M(nq);
  double f = 0.0;
  for (int q = 0; q < nq; ++q) {
    const Mat& A = ideal.inverse_jacobian[q];
    Mat g;
    Mat2 h;
    const double eta = measure.value_gradient_hessian(Mat(JP.template middleCols<D>(q * D) * A), reg, g, h);
    const double r = eta - 1.0;
    const double c = ideal.weight[q];
    f += 0.5 * c * r * r;
    const Mat gp = g * A.transpose();  // d eta / d J_P
    P.template middleCols<D>(q * D) = (c * r) * gp;
    // vec(J) = K vec(J_P), K = A^T (x) I:  K(a + D b, c + D d) = A(d, b) delta_ac.
    Mat2 K = Mat2::Zero();
    for (int b = 0; b < D; ++b)
      for (int d = 0; d < D; ++d)
        for (int a = 0; a < D; ++a) K(a + D * b, a + D * d) = A(d, b);
    const Eigen::Map<const Eigen::Matrix<double, D2, 1>> gv(gp.data());
    Mat2 Mq = c * (gv * gv.transpose() + r * (K.transpose() * h * K));
    if (project_hessian) Mq = detail::psd_part<D2>(Mq);
    M[q] = Mq;
  }
  grad.noalias() = P * tab.shape_gradients.transpose();

  // H[(a,i),(c,j)] = sum_q sum_{b,d} G_q(i,b) M_q(a + D b, c + D d) G_q(j,d):
  // for each coordinate pair (a, c), one product G * blockdiag_q(M_q[a.,c.]) * G^T.
  hess.setZero(D * n, D * n);
  Eigen::MatrixXd B(n, D * nq);
  Eigen::MatrixXd Hac(n, n);
  for (int a = 0; a < D; ++a)
    for (int c = a; c < D; ++c) {
      for (int q = 0; q < nq; ++q) {
        Mat block;
        for (int b = 0; b < D; ++b)
          for (int d = 0; d < D; ++d) block(b, d) = M[q](a + D * b, c + D * d);
        B.template middleCols<D>(q * D).noalias() = tab.shape_gradients.template middleCols<D>(q * D) * block;
      }
      Hac.noalias() = B * tab.shape_gradients.transpose();
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          hess(a + D * i, c + D * j) = Hac(i, j);
          hess(c + D * j, a + D * i) = Hac(i, j);
        }
    }
  return f;
}

}  // namespace hom
