// Element objective of eq 4.10: value, gradient and Hessian in the node
// coordinates against finite differences, for every family (include/hom/optimize/).
#include <doctest/doctest.h>

#include <random>

#include <Eigen/Dense>

#include "hom/measure/oddy_measure.hpp"
#include "hom/measure/shape_measure.hpp"
#include "hom/nodes/warp_blend.hpp"
#include "hom/optimize/element_objective.hpp"
#include "hom/quadrature/quadrature_policy.hpp"

using namespace hom;

namespace {

template <class F>
Eigen::Matrix<double, F::dim, Eigen::Dynamic> perturbed_nodes(int p, double amplitude, std::mt19937& rng) {
  const auto pts = WarpBlend::points<F>(p);
  Eigen::Matrix<double, F::dim, Eigen::Dynamic> X(F::dim, pts.size());
  std::uniform_real_distribution<double> u(-amplitude, amplitude);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    X.col(i) = pts[i];
    for (int k = 0; k < F::dim; ++k) X(k, i) += u(rng);
  }
  return X;
}

template <class F, class Measure, class Reg>
void check_derivatives(int p, double amplitude, const Measure& measure, const Reg& reg, std::mt19937& rng) {
  constexpr int D = F::dim;
  const auto& tab = tabulation<F, WarpBlend>(p, quadrature_for<F, DefaultExactness>(p));
  const auto ideal = ideal_at_points<F>(tab, regular_ideal_vertices<F>());
  auto X = perturbed_nodes<F>(p, amplitude, rng);
  ElementGradient<D> grad;
  Eigen::MatrixXd hess;
  const double f0 = element_objective<F>(tab, X, ideal, measure, reg);
  const double f1 = element_objective_gradient<F>(tab, X, ideal, measure, reg, grad);
  ElementGradient<D> grad2;
  const double f2 = element_objective_hessian<F>(tab, X, ideal, measure, reg, grad2, hess, false);
  CHECK(f1 == doctest::Approx(f0).epsilon(1e-13));
  CHECK(f2 == doctest::Approx(f0).epsilon(1e-13));
  CHECK((grad - grad2).norm() <= 1e-12 * (1 + grad.norm()));
  const int n = int(X.cols());
  const double h = 1e-6;
  double gscale = grad.cwiseAbs().maxCoeff() + 1e-8;
  double hscale = hess.cwiseAbs().maxCoeff() + 1e-8;
  for (int i = 0; i < n; ++i)
    for (int a = 0; a < D; ++a) {
      auto Xp = X, Xm = X;
      Xp(a, i) += h;
      Xm(a, i) -= h;
      const double fd = (element_objective<F>(tab, Xp, ideal, measure, reg) - element_objective<F>(tab, Xm, ideal, measure, reg)) / (2 * h);
      CHECK(std::abs(fd - grad(a, i)) <= 1e-6 * gscale);
      ElementGradient<D> gp, gm;
      element_objective_gradient<F>(tab, Xp, ideal, measure, reg, gp);
      element_objective_gradient<F>(tab, Xm, ideal, measure, reg, gm);
      const ElementGradient<D> column = (gp - gm) / (2 * h);
      for (int j = 0; j < n; ++j)
        for (int c = 0; c < D; ++c) CHECK(std::abs(column(c, j) - hess(c + D * j, a + D * i)) <= 1e-5 * hscale);
    }
  CHECK((hess - hess.transpose()).norm() <= 1e-12 * hess.norm());
}

}  // namespace

TEST_CASE_TEMPLATE("element objective: gradient and Hessian agree with finite differences", F, Simplex<2>, Simplex<3>, Cube<2>, Cube<3>) {
  std::mt19937 rng(3);
  const int pmax = F::dim == 3 ? 2 : 3;
  for (int p = 1; p <= pmax; ++p) {
    // Valid, slightly perturbed elements with the unregularized (clamped) measure.
    check_derivatives<F>(p, 0.02, ShapeMeasure{}, ClampedDeterminant{}, rng);
    check_derivatives<F>(p, 0.02, OddyMeasure{}, ClampedDeterminant{}, rng);
    // Strongly perturbed, possibly inverted elements with sigma_delta.
    check_derivatives<F>(p, 0.4, ShapeMeasure{}, element_regularization(), rng);
    check_derivatives<F>(p, 0.4, OddyMeasure{}, RegularizedDeterminant{0.1}, rng);
  }
}

TEST_CASE_TEMPLATE("the ideal element is a minimum with zero objective", F, Simplex<2>, Simplex<3>, Cube<2>, Cube<3>) {
  for (int p = 1; p <= 4; ++p) {
    const auto& tab = tabulation<F, WarpBlend>(p, quadrature_for<F, DefaultExactness>(p));
    const auto pts = WarpBlend::points<F>(p);
    Eigen::Matrix<double, F::dim, Eigen::Dynamic> X(F::dim, pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) X.col(i) = pts[i];
    const IdealVertices<F> v = X.template leftCols<F::num_vertices>();
    const auto ideal = ideal_at_points<F>(tab, v);
    ElementGradient<F::dim> grad;
    Eigen::MatrixXd hess;
    const double f = element_objective_hessian<F>(tab, X, ideal, ShapeMeasure{}, ClampedDeterminant{}, grad, hess, false);
    CHECK(std::abs(f) < 1e-24);
    CHECK(grad.norm() < 1e-11);
    // At the ideal d eta / dJ = 0 (J = I minimizes eta) and eta - 1 = 0, so the
    // Hessian vanishes: the minimum of (eta - 1)^2 is degenerate (quartic), which
    // is why Newton converges only linearly in the last iterations.
    CHECK(hess.norm() < 1e-10);
  }
}

TEST_CASE_TEMPLATE("projected element Hessians are positive semi-definite", F, Simplex<2>, Simplex<3>, Cube<2>, Cube<3>) {
  std::mt19937 rng(9);
  for (int trial = 0; trial < 5; ++trial) {
    const int p = 2;
    const auto& tab = tabulation<F, WarpBlend>(p, quadrature_for<F, DefaultExactness>(p));
    const auto ideal = ideal_at_points<F>(tab, regular_ideal_vertices<F>());
    const auto X = perturbed_nodes<F>(p, 0.5, rng);
    ElementGradient<F::dim> grad;
    Eigen::MatrixXd raw, projected;
    element_objective_hessian<F>(tab, X, ideal, ShapeMeasure{}, element_regularization(), grad, raw, false);
    element_objective_hessian<F>(tab, X, ideal, ShapeMeasure{}, element_regularization(), grad, projected, true);
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(projected);
    CHECK(es.eigenvalues().minCoeff() > -1e-10 * es.eigenvalues().cwiseAbs().maxCoeff());
    // The projection only modifies second-order terms: the gradient is the same.
    ElementGradient<F::dim> grad2;
    element_objective_hessian<F>(tab, X, ideal, ShapeMeasure{}, element_regularization(), grad2, raw, false);
    CHECK((grad - grad2).norm() <= 1e-13 * (1 + grad.norm()));
  }
}

TEST_CASE_TEMPLATE("the isotropic projection is the positive semi-definite part, pulled back", M, ShapeMeasure, OddyMeasure) {
  // For an isotropic measure, the block-wise projection in the SVD basis of J
  // (detail::isotropic_psd_pullback) must equal K^T psd(M) K computed with a
  // full Dim^2 x Dim^2 eigensolver, for any J (valid or inverted) and ideal A.
  std::mt19937 rng(17);
  std::normal_distribution<double> normal;
  auto check = [&](auto dim_tag) {
    constexpr int D = decltype(dim_tag)::value;
    using Mat = Eigen::Matrix<double, D, D>;
    using Mat2 = Eigen::Matrix<double, D * D, D * D>;
    for (int trial = 0; trial < 20; ++trial) {
      Mat J, A;
      for (int i = 0; i < D; ++i)
        for (int j = 0; j < D; ++j) {
          J(i, j) = (i == j) + 0.6 * normal(rng);
          A(i, j) = (i == j) + 0.3 * normal(rng);
        }
      const RegularizedDeterminant reg{0.05};
      Mat g;
      Mat2 h;
      const double eta = M{}.value_gradient_hessian(J, reg, g, h);
      const Eigen::Map<const Eigen::Matrix<double, D * D, 1>> gv(g.data());
      const Mat2 Mj = 0.7 * (gv * gv.transpose() + (eta - 1.0) * h);
      const Mat2 K = detail::right_product_matrix<D>(A);
      const Mat2 reference = K.transpose() * detail::psd_part<D * D>(Mj) * K;
      const Mat2 fast = detail::isotropic_psd_pullback<D>(J, Mj, A);
      CHECK((fast - reference).norm() <= 1e-9 * (1.0 + reference.norm()));
    }
  };
  check(std::integral_constant<int, 2>{});
  check(std::integral_constant<int, 3>{});
}
