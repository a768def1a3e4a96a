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
/// Dim^2 x Dim^2 block, in J coordinates, by its positive semi-definite part
/// (eigenvalues clamped at 0) before the pull back, so the element Hessian is positive
/// semi-definite: the modification for indefinite Hessians used by the Newton
/// solvers. HessianForm::gauss_newton keeps only the g g^T term. The point
/// data (ElementHessianData) also applies the element Hessian to a direction
/// without forming it (apply_element_hessian), for matrix-free Newton-CG.

#include <algorithm>
#include <array>
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

/// Ideal data of one element at the quadrature points: A_q = (D phi_I(xi_q))^{-1}
/// and c_q = w_q |det D phi_I(xi_q)| (eq 4.11's integral over E^I mapped to the
/// reference element). An affine ideal (every straight-sided simplex, and
/// parallelograms) has one A for all points, stored once: one per point
/// would cost Dim^2 doubles per quadrature point, 388 MB at p = 10 on table
/// 4.1's mesh against 43 MB for the weights.
template <int Dim>
struct IdealAtPoints {
  using Matrix = Eigen::Matrix<double, Dim, Dim>;
  std::vector<Matrix> inverse_jacobians;  ///< one per point, or one for all when affine
  std::vector<double> weights;            ///< c_q, one per point

  bool affine() const { return inverse_jacobians.size() == 1; }
  int num_points() const { return int(weights.size()); }
  const Matrix& inverse_jacobian(int q) const { return inverse_jacobians[affine() ? 0 : q]; }
  double weight(int q) const { return weights[q]; }
};

template <ElementFamily Family>
IdealAtPoints<Family::dim> ideal_at_points(const Tabulation<Family>& tab, const IdealVertices<Family>& ideal) {
  IdealAtPoints<Family::dim> r;
  const int nq = tab.num_points();
  r.inverse_jacobians.resize(nq);
  r.weights.resize(nq);
  for (int q = 0; q < nq; ++q) {
    const Eigen::Matrix<double, Family::dim, Family::dim> Ji = ideal * tab.vertex_gradients[q];
    r.inverse_jacobians[q] = Ji.inverse();
    r.weights[q] = tab.rule.weights[q] * std::abs(Ji.determinant());
  }
  // Bitwise equal at every point (a simplex's vertex gradients are the same
  // numbers at every point): keep one.
  if (nq > 1 && std::all_of(r.inverse_jacobians.begin(), r.inverse_jacobians.end(),
                            [&](const auto& A) { return A == r.inverse_jacobians[0]; }))
    r.inverse_jacobians.resize(1);
  return r;
}

namespace detail {

// Positive semi-definite part of a small symmetric matrix.
template <int N>
Eigen::Matrix<double, N, N> psd_part(const Eigen::Matrix<double, N, N>& M) {
  // Most blocks of a valid configuration are positive definite already; a
  // Cholesky factorization (a fraction of the eigensolver's cost) detects them.
  if (Eigen::LLT<Eigen::Matrix<double, N, N>>(M).info() == Eigen::Success) return M;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> es;
  if constexpr (N <= 3)
    es.computeDirect(M);  // closed form; its accuracy is ample for clamping eigenvalues
  else
    es.compute(M);
  const Eigen::Matrix<double, N, 1> lambda = es.eigenvalues().cwiseMax(0.0);
  return es.eigenvectors() * lambda.asDiagonal() * es.eigenvectors().transpose();
}

// Kronecker product X (x) Y of D x D matrices in the column-major vec
// convention: vec(Y E X^T) = (X (x) Y) vec(E), entry (a + D b, c + D d) = X(b, d) Y(a, c).
template <int D>
Eigen::Matrix<double, D * D, D * D> kronecker(const Eigen::Matrix<double, D, D>& X, const Eigen::Matrix<double, D, D>& Y) {
  Eigen::Matrix<double, D * D, D * D> K;
  for (int d = 0; d < D; ++d)
    for (int b = 0; b < D; ++b) K.template block<D, D>(D * b, D * d) = X(b, d) * Y;
  return K;
}

// K^T M+ K, with M+ the positive semi-definite part of M, the second
// derivative with respect to J (flattened column-major) of a function of J
// that is isotropic, phi(R1 J R2) = phi(J) for rotations R1, R2 (every
// distortion measure, and c (eta - 1)^2 / 2 built from one), and
// K = A^T (x) I (vec(J_P A) = K vec(J_P)), the pull back to J_P.
//
// With J = U S V^T (SVD), such a Hessian is block diagonal in the basis
// Q = V (x) U, column i + D j = vec(u_i v_j^T) (Smith, De Goes & Kim 2019,
// "Analytic eigensystems for isotropic distortion energies"): one D x D block
// on the "stretch" directions E_ii and a 2 x 2 block on each pair (E_ij, E_ji).
// So M+ = Q P Q^T with P the blocks of B = Q^T M Q projected one by one, and
//     K^T M+ K = R^T P R,   R = Q^T K = (A V)^T (x) U^T,
// where P has at most D non-zeros per row: a few hundred flops instead of the
// dense 9 x 9 products and a 9 x 9 eigensolver. If M is not block diagonal in
// that basis (a measure that is not isotropic), the full eigensolver is used.
template <int D>
Eigen::Matrix<double, D * D, D * D> isotropic_psd_pullback(const Eigen::Matrix<double, D, D>& J,
                                                           const Eigen::Matrix<double, D * D, D * D>& M,
                                                           const Eigen::Matrix<double, D, D>& A) {
  constexpr int D2 = D * D;
  using Mat = Eigen::Matrix<double, D, D>;
  using Mat2 = Eigen::Matrix<double, D2, D2>;
  const Eigen::JacobiSVD<Mat> svd(J, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Mat& U = svd.matrixU();
  const Mat& V = svd.matrixV();
  const Mat2 Q = kronecker<D>(V, U);
  const Mat2 B = Q.transpose() * M * Q;
  // Block of each flattened index: 0 for the stretch block, 1 + pair number otherwise.
  std::array<int, D2> block{};
  for (int j = 0, pair = 1; j < D; ++j)
    for (int i = 0; i < j; ++i, ++pair) block[i + D * j] = block[j + D * i] = pair;
  double off = 0.0;
  for (int c = 0; c < D2; ++c)
    for (int r = 0; r < D2; ++r)
      if (block[r] != block[c]) off = std::max(off, std::abs(B(r, c)));
  const Mat2 K = kronecker<D>(A.transpose(), Mat::Identity());
  if (off > 1e-10 * B.cwiseAbs().maxCoeff()) return K.transpose() * psd_part<D2>(M) * K;
  const Mat2 R = kronecker<D>(Mat((A * V).transpose()), Mat(U.transpose()));
  Mat2 PR;  // P R, row by row from P's blocks
  Mat S;
  for (int i = 0; i < D; ++i)
    for (int k = 0; k < D; ++k) S(i, k) = B(i + D * i, k + D * k);
  S = psd_part<D>(S);
  for (int i = 0; i < D; ++i) {
    PR.row(i + D * i).setZero();
    for (int k = 0; k < D; ++k) PR.row(i + D * i) += S(i, k) * R.row(k + D * k);
  }
  for (int j = 0; j < D; ++j)
    for (int i = 0; i < j; ++i) {
      const int x = i + D * j, y = j + D * i;
      Eigen::Matrix2d T;
      T << B(x, x), B(x, y), B(y, x), B(y, y);
      T = psd_part<2>(T);
      const Eigen::Matrix<double, 1, D2> rx = R.row(x), ry = R.row(y);
      PR.row(x) = T(0, 0) * rx + T(0, 1) * ry;
      PR.row(y) = T(1, 0) * rx + T(1, 1) * ry;
    }
  return R.transpose() * PR;
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
    const double eta = measure.value(Mat(JP.template middleCols<D>(q * D) * ideal.inverse_jacobian(q)), reg);
    f += 0.5 * ideal.weight(q) * (eta - 1.0) * (eta - 1.0);
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
    const Mat& A = ideal.inverse_jacobian(q);
    Mat g;
    const double eta = measure.value_gradient(Mat(JP.template middleCols<D>(q * D) * A), reg, g);
    const double r = eta - 1.0;
    f += 0.5 * ideal.weight(q) * r * r;
    P.template middleCols<D>(q * D) = (ideal.weight(q) * r) * g * A.transpose();
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
  projected,     ///< M_q with its part in J = J_P A coordinates replaced by its positive semi-definite part
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

/// Relative shift under which a point's second-order matrix counts as positive
/// semi-definite without projecting it (point_second_order).
inline constexpr double psd_shift = 1e-3;

/// K with vec(J_P A) = K vec(J_P), K = A^T (x) I: K(a + D b, c + D d) = A(d, b) delta_ac.
template <int D>
Eigen::Matrix<double, D * D, D * D> right_product_matrix(const Eigen::Matrix<double, D, D>& A) {
  return kronecker<D>(A.transpose(), Eigen::Matrix<double, D, D>::Identity());
}

}  // namespace detail

/// What point_second_order returns: the residual eta - 1 and d eta / d J_P.
template <int Dim>
struct PointSecondOrder {
  double residual = 0.0;
  Eigen::Matrix<double, Dim, Dim> gradient;
};

/// One quadrature point's share of f_e's second-order model in J_P coordinates,
/// M_q of HessianForm `form`, written to `data`: sqrt(c) vec(d eta / d J_P)
/// (Dim^2 numbers) for Gauss-Newton, M_q column-major (Dim^4 numbers)
/// otherwise. J = J_P A is the point's Jacobian relative to the ideal, c its
/// weight c_q. The measure's Hessian is not evaluated for Gauss-Newton.
template <int D, class Measure, class Reg>
PointSecondOrder<D> point_second_order(const Measure& measure, const Reg& reg, const Eigen::Matrix<double, D, D>& J,
                                       const Eigen::Matrix<double, D, D>& A, double c, HessianForm form, double* data) {
  constexpr int D2 = D * D;
  using Mat = Eigen::Matrix<double, D, D>;
  using Mat2 = Eigen::Matrix<double, D2, D2>;
  Mat g;
  Mat2 h;
  const double eta = form == HessianForm::gauss_newton ? measure.value_gradient(J, reg, g) : measure.value_gradient_hessian(J, reg, g, h);
  PointSecondOrder<D> out;
  out.residual = eta - 1.0;
  out.gradient.noalias() = g * A.transpose();  // d eta / d J_P
  const Eigen::Map<const Eigen::Matrix<double, D2, 1>> gv(out.gradient.data());
  if (form == HessianForm::gauss_newton) {
    Eigen::Map<Eigen::Matrix<double, D2, 1>> u(data);
    u = std::sqrt(c) * gv;
    return out;
  }
  Eigen::Map<Mat2> M(data);
  if (form == HessianForm::projected) {
    // Projected in J coordinates, where the measure's isotropy gives the
    // eigenstructure, then pulled back (congruence keeps it PSD).
    const Eigen::Map<const Eigen::Matrix<double, D2, 1>> gj(g.data());
    Mat2 MJ = c * (gj * gj.transpose() + out.residual * h);
    // Most points of a mesh being smoothed are nearly ideal, where M is
    // positive semi-definite up to eigenvalues of size |J - R|^3 along the
    // measure's near-null directions (rotations, scaling). A Cholesky
    // factorization of M shifted by psd_shift * trace(M) / Dim^2 accepts
    // those for a few hundred flops; the shifted matrix (a Levenberg-Marquardt
    // term of relative size psd_shift) is used as is. Only the other points pay
    // for the SVD-based projection.
    const double shift = detail::psd_shift * MJ.trace() / D2;
    MJ.diagonal().array() += shift;
    if (shift > 0.0 && Eigen::LLT<Mat2>(MJ).info() == Eigen::Success) {
      const Mat2 K = detail::right_product_matrix<D>(A);
      M.noalias() = K.transpose() * MJ * K;
    } else {
      MJ.diagonal().array() -= shift;
      M = detail::isotropic_psd_pullback<D>(J, MJ, A);
    }
  } else {
    const Mat2 K = detail::right_product_matrix<D>(A);
    M.noalias() = c * (gv * gv.transpose() + out.residual * (K.transpose() * h * K));
  }
  return out;
}

/// f_e, its gradient (Dim x n) and the second-order data of `form` at every
/// quadrature point.
template <ElementFamily Family, class Measure, DeterminantRegularization Reg>
double element_hessian_data(const Tabulation<Family>& tab,
                            const Eigen::Ref<const Eigen::Matrix<double, Family::dim, Eigen::Dynamic>>& X,
                            const IdealAtPoints<Family::dim>& ideal, const Measure& measure, const Reg& reg,
                            HessianForm form, ElementGradient<Family::dim>& grad, ElementHessianData<Family::dim>& data) {
  constexpr int D = Family::dim;
  using Mat = Eigen::Matrix<double, D, D>;
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
    const Mat& A = ideal.inverse_jacobian(q);
    const double c = ideal.weight(q);
    double* out = form == HessianForm::gauss_newton ? data.u[q].data() : data.M[q].data();
    const auto pd = point_second_order<D>(measure, reg, Mat(JP.template middleCols<D>(q * D) * A), A, c, form, out);
    f += 0.5 * c * pd.residual * pd.residual;
    P.template middleCols<D>(q * D) = (c * pd.residual) * pd.gradient;
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

/// W (n x (Dim^2 nq)) with W(i, q Dim^2 + b + Dim d) = G_q(i, b) G_q(i, d): the
/// element-independent factor of the nodal diagonal blocks (tabulation only):
/// the block of node i is B_i(a, c) = sum_q sum_{b,d} W(i, q Dim^2 + b + Dim d) M_q(a + Dim b, c + Dim d).
template <ElementFamily Family>
Eigen::MatrixXd diagonal_block_basis(const Tabulation<Family>& tab) {
  constexpr int D = Family::dim;
  const int nq = tab.num_points();
  const int n = tab.num_nodes();
  Eigen::MatrixXd W(n, D * D * nq);
  for (int q = 0; q < nq; ++q)
    for (int d = 0; d < D; ++d)
      for (int b = 0; b < D; ++b)
        W.col(q * D * D + b + D * d) = tab.shape_gradients.col(q * D + b).cwiseProduct(tab.shape_gradients.col(q * D + d));
  return W;
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
