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
/// `project_hessian` (HessianForm::projected) replaces each quadrature point's
/// Dim^2 x Dim^2 block by its positive semi-definite part (eigenvalues clamped
/// at 0) before the pull back, so the element Hessian is positive
/// semi-definite: the modification for indefinite Hessians used by the Newton
/// solvers. HessianForm::gauss_newton keeps only the g g^T term. The point
/// data (ElementHessianData) also applies the element Hessian to a direction
/// without forming it (apply_element_hessian), for matrix-free Newton-CG.

#include <cmath>
#include <limits>
#include <vector>

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
  // Most blocks of a valid configuration are positive definite already; a
  // Cholesky factorization (a fraction of the eigensolver's cost) detects them.
  if (Eigen::LLT<Eigen::Matrix<double, N, N>>(M).info() == Eigen::Success) return M;
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

/// Which second-order model of f_e a Newton-type solver uses. With
/// g = d eta / dJ_P and H_eta the measure's Hessian pulled back to J_P, the
/// exact second derivative of f_e at quadrature point q in J_P coordinates is
///     M_q = c_q [ g g^T + (eta - 1) H_eta ],
/// and the element Hessian is sum_q G_q M_q G_q^T (nodes x coordinates, see
/// element_objective_hessian). The forms:
enum class HessianForm {
  exact,         ///< M_q as above (indefinite in general): derivative checks
  projected,     ///< M_q replaced by its positive semi-definite part (eigenvalues clamped at 0)
  gauss_newton,  ///< c_q g g^T: the Gauss-Newton model of the least squares eq 4.10 (PSD, rank one per point)
};

/// Second-order data of f_e at its quadrature points: enough to apply the
/// element Hessian to a direction, or to assemble it, without storing it.
///   - gauss_newton: `u[q]` = sqrt(c_q) vec(d eta / d J_P), M_q = u u^T (Dim^2 numbers per point);
///   - exact, projected: `M[q]` (Dim^4 numbers per point).
template <int Dim>
struct ElementHessianData {
  using FlatVector = Eigen::Matrix<double, Dim * Dim, 1>;
  using FlatMatrix = Eigen::Matrix<double, Dim * Dim, Dim * Dim>;
  HessianForm form = HessianForm::exact;
  std::vector<FlatVector> u;
  std::vector<FlatMatrix> M;

  /// M_q in every form.
  FlatMatrix point_matrix(int q) const { return form == HessianForm::gauss_newton ? FlatMatrix(u[q] * u[q].transpose()) : M[q]; }
};

namespace detail {

/// K with vec(J_P A) = K vec(J_P), K = A^T (x) I: K(a + D b, c + D d) = A(d, b) delta_ac.
template <int D>
Eigen::Matrix<double, D * D, D * D> right_product_matrix(const Eigen::Matrix<double, D, D>& A) {
  Eigen::Matrix<double, D * D, D * D> K = Eigen::Matrix<double, D * D, D * D>::Zero();
  for (int b = 0; b < D; ++b)
    for (int d = 0; d < D; ++d)
      for (int a = 0; a < D; ++a) K(a + D * b, a + D * d) = A(d, b);
  return K;
}

}  // namespace detail

/// f_e, its gradient (Dim x n) and the second-order data of `form` at every
/// quadrature point. The measure's Hessian is not evaluated for Gauss-Newton.
template <ElementFamily Family, class Measure, DeterminantRegularization Reg>
double element_hessian_data(const Tabulation<Family>& tab,
                            const Eigen::Ref<const Eigen::Matrix<double, Family::dim, Eigen::Dynamic>>& X,
                            const IdealAtPoints<Family::dim>& ideal, const Measure& measure, const Reg& reg,
                            HessianForm form, ElementGradient<Family::dim>& grad, ElementHessianData<Family::dim>& data) {
  constexpr int D = Family::dim;
  constexpr int D2 = D * D;
  using Mat = Eigen::Matrix<double, D, D>;
  using Mat2 = Eigen::Matrix<double, D2, D2>;
  const int nq = tab.num_points();
  const Eigen::Matrix<double, D, Eigen::Dynamic> JP = X * tab.shape_gradients;
  Eigen::Matrix<double, D, Eigen::Dynamic> P(D, D * nq);
  data.form = form;
  if (form == HessianForm::gauss_newton) {
    data.u.resize(nq);
    data.M.clear();
  } else {
    data.M.resize(nq);
    data.u.clear();
  }
  double f = 0.0;
  for (int q = 0; q < nq; ++q) {
    const Mat& A = ideal.inverse_jacobian[q];
    const double c = ideal.weight[q];
    const Mat J = JP.template middleCols<D>(q * D) * A;
    Mat g;
    Mat2 h;
    const double eta = form == HessianForm::gauss_newton ? measure.value_gradient(J, reg, g)
                                                         : measure.value_gradient_hessian(J, reg, g, h);
    const double r = eta - 1.0;
    f += 0.5 * c * r * r;
    const Mat gp = g * A.transpose();  // d eta / d J_P
    P.template middleCols<D>(q * D) = (c * r) * gp;
    const Eigen::Map<const Eigen::Matrix<double, D2, 1>> gv(gp.data());
    if (form == HessianForm::gauss_newton) {
      data.u[q] = std::sqrt(c) * gv;
    } else {
      const Mat2 K = detail::right_product_matrix<D>(A);
      Mat2 Mq = c * (gv * gv.transpose() + r * (K.transpose() * h * K));
      if (form == HessianForm::projected) Mq = detail::psd_part<D2>(Mq);
      data.M[q] = Mq;
    }
  }
  grad.noalias() = P * tab.shape_gradients.transpose();
  return f;
}

/// out = H_e V: the element Hessian (of data's form) applied to the direction V
/// (Dim x n, same layout as X), without forming H_e:
///     dJ_q = V G_q,   S_q = unvec(M_q vec(dJ_q)),   out = sum_q S_q G_q^T.
template <ElementFamily Family>
void apply_element_hessian(const Tabulation<Family>& tab, const ElementHessianData<Family::dim>& data,
                           const Eigen::Ref<const Eigen::Matrix<double, Family::dim, Eigen::Dynamic>>& V,
                           Eigen::Matrix<double, Family::dim, Eigen::Dynamic>& out) {
  constexpr int D = Family::dim;
  constexpr int D2 = D * D;
  const int nq = tab.num_points();
  Eigen::Matrix<double, D, Eigen::Dynamic> S = V * tab.shape_gradients;  // dJ_q, then S_q in place
  for (int q = 0; q < nq; ++q) {
    Eigen::Map<Eigen::Matrix<double, D2, 1>> s(S.data() + q * D2);
    if (data.form == HessianForm::gauss_newton)
      s = data.u[q] * data.u[q].dot(s);
    else
      s = (data.M[q] * s).eval();
  }
  out.noalias() = S * tab.shape_gradients.transpose();
}

/// The Dim x Dim diagonal blocks of H_e, one per node: column block i of the
/// result (Dim x (Dim n)) is d^2 f_e / dx_i^2 (for a nodal block-Jacobi preconditioner).
template <ElementFamily Family>
void element_hessian_diagonal_blocks(const Tabulation<Family>& tab, const ElementHessianData<Family::dim>& data,
                                     Eigen::Matrix<double, Family::dim, Eigen::Dynamic>& blocks) {
  constexpr int D = Family::dim;
  using Mat = Eigen::Matrix<double, D, D>;
  using Vec = Eigen::Matrix<double, D, 1>;
  const int nq = tab.num_points();
  const int n = tab.num_nodes();
  blocks.setZero(D, D * n);
  for (int q = 0; q < nq; ++q) {
    const auto Gq = tab.shape_gradients.template middleCols<D>(q * D);  // n x D
    if (data.form == HessianForm::gauss_newton) {
      // H_ii += v v^T with v = U_q G_q(i,:)^T, U_q = unvec(u_q).
      const Eigen::Map<const Mat> U(data.u[q].data());
      const Eigen::Matrix<double, D, Eigen::Dynamic> W = U * Gq.transpose();
      for (int i = 0; i < n; ++i) blocks.template middleCols<D>(i * D).noalias() += W.col(i) * W.col(i).transpose();
    } else {
      const auto& Mq = data.M[q];
      for (int i = 0; i < n; ++i) {
        const Vec gi = Gq.row(i).transpose();
        Mat Bi;
        for (int a = 0; a < D; ++a)
          for (int c = 0; c < D; ++c) {
            double s = 0.0;
            for (int b = 0; b < D; ++b)
              for (int d = 0; d < D; ++d) s += gi[b] * Mq(a + D * b, c + D * d) * gi[d];
            Bi(a, c) = s;
          }
        blocks.template middleCols<D>(i * D) += Bi;
      }
    }
  }
}

/// The dense element Hessian ((Dim n) x (Dim n), node-major) from its point data:
///     H[(a,i),(c,j)] = sum_q sum_{b,d} G_q(i,b) M_q(a + D b, c + D d) G_q(j,d),
/// for each coordinate pair (a, c) one product G * blockdiag_q(M_q[a.,c.]) * G^T.
template <ElementFamily Family>
void assemble_element_hessian(const Tabulation<Family>& tab, const ElementHessianData<Family::dim>& data,
                              Eigen::MatrixXd& hess) {
  constexpr int D = Family::dim;
  using Mat = Eigen::Matrix<double, D, D>;
  const int nq = tab.num_points();
  const int n = tab.num_nodes();
  hess.setZero(D * n, D * n);
  Eigen::MatrixXd B(n, D * nq);
  Eigen::MatrixXd Hac(n, n);
  for (int a = 0; a < D; ++a)
    for (int c = a; c < D; ++c) {
      for (int q = 0; q < nq; ++q) {
        const auto Mq = data.point_matrix(q);
        Mat block;
        for (int b = 0; b < D; ++b)
          for (int d = 0; d < D; ++d) block(b, d) = Mq(a + D * b, c + D * d);
        B.template middleCols<D>(q * D).noalias() = tab.shape_gradients.template middleCols<D>(q * D) * block;
      }
      Hac.noalias() = B * tab.shape_gradients.transpose();
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          hess(a + D * i, c + D * j) = Hac(i, j);
          hess(c + D * j, a + D * i) = Hac(i, j);
        }
    }
}

/// f_e, its gradient and its Hessian ((Dim n) x (Dim n), node-major) in the given form.
template <ElementFamily Family, class Measure, DeterminantRegularization Reg>
double element_objective_hessian(const Tabulation<Family>& tab,
                                 const Eigen::Ref<const Eigen::Matrix<double, Family::dim, Eigen::Dynamic>>& X,
                                 const IdealAtPoints<Family::dim>& ideal, const Measure& measure, const Reg& reg,
                                 ElementGradient<Family::dim>& grad, Eigen::MatrixXd& hess, HessianForm form) {
  ElementHessianData<Family::dim> data;
  const double f = element_hessian_data<Family>(tab, X, ideal, measure, reg, form, grad, data);
  assemble_element_hessian<Family>(tab, data, hess);
  return f;
}

/// f_e, its gradient and its Hessian ((Dim n) x (Dim n), node-major);
/// `project_hessian` selects HessianForm::projected instead of exact.
template <ElementFamily Family, class Measure, DeterminantRegularization Reg>
double element_objective_hessian(const Tabulation<Family>& tab,
                                 const Eigen::Ref<const Eigen::Matrix<double, Family::dim, Eigen::Dynamic>>& X,
                                 const IdealAtPoints<Family::dim>& ideal, const Measure& measure, const Reg& reg,
                                 ElementGradient<Family::dim>& grad, Eigen::MatrixXd& hess, bool project_hessian) {
  return element_objective_hessian<Family>(tab, X, ideal, measure, reg, grad, hess,
                                           project_hessian ? HessianForm::projected : HessianForm::exact);
}

}  // namespace hom
