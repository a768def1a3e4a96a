// Tests of include/hom/measure/: regularization policies (eqs 3.4, 3.8, 4.12-4.14)
// and the shape / Oddy distortion measures (eqs 3.2, 3.3, 3.5, 3.6) with their
// analytic gradient and Hessian in J.

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>
#include <Eigen/QR>
#include <Eigen/SVD>

#include "hom/measure/distortion_measure.hpp"
#include "hom/measure/oddy_measure.hpp"
#include "hom/measure/regularization.hpp"
#include "hom/measure/shape_measure.hpp"

namespace {

using hom::AbsoluteDeterminant;
using hom::ClampedDeterminant;
using hom::OddyMeasure;
using hom::RegularizedDeterminant;
using hom::ShapeMeasure;

constexpr double inf = std::numeric_limits<double>::infinity();

template <int Dim>
using Mat = Eigen::Matrix<double, Dim, Dim>;
template <int Dim>
using Hess = Eigen::Matrix<double, Dim * Dim, Dim * Dim>;

/// One test case: a dimension and a measure.
template <int D, class M>
struct Case {
  static constexpr int dim = D;
  using Measure = M;
};

using Shape2 = Case<2, ShapeMeasure>;
using Shape3 = Case<3, ShapeMeasure>;
using Oddy2 = Case<2, OddyMeasure>;
using Oddy3 = Case<3, OddyMeasure>;

#define HOM_MEASURE_CASES Shape2, Shape3, Oddy2, Oddy3

using Rng = std::mt19937_64;

template <int Dim>
Mat<Dim> random_matrix(Rng& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Mat<Dim> A;
  for (int j = 0; j < Dim; ++j)
    for (int i = 0; i < Dim; ++i) A(i, j) = normal(rng);
  return A;
}

/// A random matrix whose determinant has the requested sign and |det| >= 0.05.
template <int Dim>
Mat<Dim> random_jacobian(Rng& rng, double sign) {
  for (;;) {
    Mat<Dim> A = random_matrix<Dim>(rng);
    const double det = A.determinant();
    if (std::abs(det) < 0.05) continue;
    if (det * sign < 0) A.col(0) *= -1.0;
    return A;
  }
}

template <int Dim>
Mat<Dim> random_rotation(Rng& rng) {
  Mat<Dim> Q = Eigen::HouseholderQR<Mat<Dim>>(random_matrix<Dim>(rng)).householderQ();
  if (Q.determinant() < 0) Q.col(0) *= -1.0;
  return Q;
}

double log_uniform(Rng& rng, double lo, double hi) {
  std::uniform_real_distribution<double> u(std::log(lo), std::log(hi));
  return std::exp(u(rng));
}

double rel_diff(double a, double b) { return std::abs(a - b) / std::max(std::abs(a), std::abs(b)); }

/// Plain, slow forms of the measures straight from the formulas, to test the fast ones.
template <int Dim>
double reference_shape(const Mat<Dim>& J, double s) {
  return J.squaredNorm() / (Dim * std::pow(s, 2.0 / Dim));
}
template <int Dim>
double reference_oddy(const Mat<Dim>& J, double s) {
  const double m = (J.transpose() * J).squaredNorm(), n = J.squaredNorm();
  return 1.0 + 2.0 * (m - n * n / Dim) / std::pow(s, 4.0 / Dim);
}

/// Central finite differences (fourth order) of the measure's value (-> gradient) and of its
/// analytic gradient (-> Hessian), flattened column-major.
template <int Dim, class Measure, class Reg>
void check_derivatives(const Measure& measure, const Mat<Dim>& J, const Reg& reg) {
  Mat<Dim> grad, grad2;
  Hess<Dim> hess;
  const double eta = measure.value(J, reg);
  REQUIRE(std::isfinite(eta));
  CHECK(measure.value_gradient(J, reg, grad) == doctest::Approx(eta).epsilon(1e-13));
  CHECK(measure.value_gradient_hessian(J, reg, grad2, hess) == doctest::Approx(eta).epsilon(1e-13));
  CHECK((grad - grad2).cwiseAbs().maxCoeff() <= 1e-14 * grad.cwiseAbs().maxCoeff());
  CHECK((hess - hess.transpose()).cwiseAbs().maxCoeff() <= 1e-12 * hess.cwiseAbs().maxCoeff());

  // Fourth-order central stencil (f(-2h) - 8 f(-h) + 8 f(h) - f(2h)) / 12h: its
  // truncation error is small enough to test at 1e-6 even near det = 0 with small delta.
  // The step follows the smallest singular value, the length scale on which eta varies near
  // a degenerate J (and sigma's scale stays far below delta for the near-singular J tested).
  const double h = 1e-3 * Eigen::JacobiSVD<Mat<Dim>>(J).singularValues()(Dim - 1);
  const double weights[4] = {1.0, -8.0, 8.0, -1.0};
  const double steps[4] = {-2.0, -1.0, 1.0, 2.0};
  Mat<Dim> fd_grad = Mat<Dim>::Zero();
  Hess<Dim> fd_hess = Hess<Dim>::Zero();
  for (int j = 0; j < Dim; ++j)
    for (int i = 0; i < Dim; ++i)
      for (int q = 0; q < 4; ++q) {
        Mat<Dim> Jq = J;
        Jq(i, j) += steps[q] * h;
        Mat<Dim> gq;
        fd_grad(i, j) += weights[q] * measure.value(Jq, reg) / (12 * h);
        measure.value_gradient(Jq, reg, gq);
        fd_hess.col(i + Dim * j) +=
            weights[q] / (12 * h) * Eigen::Map<const Eigen::Matrix<double, Dim * Dim, 1>>(gq.data());
      }
  // Relative to the largest entry, or where the derivative vanishes (the Oddy
  // measure at a conformal J) to the natural scale eta / |J|^k of a k-th derivative.
  const double size = J.cwiseAbs().maxCoeff();
  const double grad_scale = std::max(grad.cwiseAbs().maxCoeff(), 1e-3 * eta / size);
  const double hess_scale = std::max(hess.cwiseAbs().maxCoeff(), 1e-3 * eta / (size * size));
  const double grad_err = (fd_grad - grad).cwiseAbs().maxCoeff() / grad_scale;
  const double hess_err = (fd_hess - hess).cwiseAbs().maxCoeff() / hess_scale;
  CHECK(grad_err < 1e-6);
  CHECK(hess_err < 1e-6);
}

}  // namespace

// ---------------------------------------------------------------- regularization

TEST_CASE("sigma_delta (eq 3.4): value, monotonicity and limits") {
  for (const double delta : {1e-3, 0.05, 1.0, 30.0}) {
    CAPTURE(delta);
    const RegularizedDeterminant reg{delta};
    CHECK(reg.value(0.0) == doctest::Approx(delta).epsilon(1e-15));

    // Strictly increasing and positive on a grid spanning both signs.
    double previous = 0.0;
    for (int i = -2000; i <= 2000; ++i) {
      const double s = delta * 0.01 * i;
      const double v = reg.value(s);
      CHECK(v > previous);
      CHECK(reg.jet(s).first > 0.0);
      CHECK(reg.jet(s).first < 1.0);
      previous = v;
    }

    // -> 0 as s -> -inf (like delta^2 / |s|), and sigma_delta - s -> 0 as s -> +inf.
    for (const double s : {1e3, 1e6, 1e12}) {
      const double big = s * delta;
      const double neg = reg.value(-big);
      CHECK(neg > 0.0);
      CHECK(neg == doctest::Approx(delta * delta / big).epsilon(1e-5));
      CHECK(reg.value(big) - big == doctest::Approx(delta * delta / big).epsilon(1e-3));
      CHECK(reg.value(big) >= big);
    }

    // sigma_delta >= max(s, 0) and the closed form agrees with the naive formula where it is accurate.
    for (const double s : {-3.0, -0.5, -1e-3, 0.0, 1e-3, 0.5, 3.0}) {
      const double x = s * delta;
      CHECK(reg.value(x) >= std::max(x, 0.0));
      CHECK(reg.value(x) == doctest::Approx(0.5 * (x + std::sqrt(x * x + 4 * delta * delta))).epsilon(1e-12));
    }
  }
}

TEST_CASE("sigma_delta: derivatives agree with finite differences, jet agrees with the members") {
  Rng rng(11);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  for (const double delta : {0.01, 0.3, 2.0}) {
    const RegularizedDeterminant reg{delta};
    for (int t = 0; t < 200; ++t) {
      const double s = u(rng);
      const double h = 1e-5;
      const hom::DeterminantJet jet = reg.jet(s);
      CHECK(jet.value == reg.value(s));
      CHECK(jet.first == reg.derivative(s));
      CHECK(jet.second == reg.second_derivative(s));
      const double fd1 = (reg.value(s + h) - reg.value(s - h)) / (2 * h);
      const double fd2 = (reg.derivative(s + h) - reg.derivative(s - h)) / (2 * h);
      CHECK(fd1 == doctest::Approx(jet.first).epsilon(1e-7));
      CHECK(fd2 == doctest::Approx(jet.second).epsilon(1e-6));
      CHECK(jet.second > 0.0);  // convex
    }
  }
}

TEST_CASE("sigma_0 (eq 3.8) is the delta -> 0 limit of sigma_delta") {
  const ClampedDeterminant clamped;
  const RegularizedDeterminant zero{0.0};
  for (const double s : {-7.0, -1e-300, 0.0, 1e-300, 1e-8, 3.5}) {
    CAPTURE(s);
    CHECK(clamped.value(s) == 0.5 * (s + std::abs(s)));
    CHECK(zero.value(s) == clamped.value(s));
    // sigma_delta - sigma_0 is largest at s = 0, where it is delta.
    CHECK(std::abs(RegularizedDeterminant{1e-9}.value(s) - clamped.value(s)) <= 1e-9 * (1 + 1e-12));
  }
  CHECK(clamped.jet(2.0).first == 1.0);
  CHECK(clamped.jet(-2.0).first == 0.0);
}

TEST_CASE("delta selection (eqs 4.12-4.14)") {
  for (const double sigma_star : {-1.0, -1e-6, -0.25, -4e3}) {
    CAPTURE(sigma_star);
    const double alpha = hom::thesis_regularization_alpha;
    const double delta = hom::regularization_delta(sigma_star);
    CHECK(delta == doctest::Approx(std::abs(sigma_star) * std::sqrt(alpha * alpha + alpha)).epsilon(1e-15));
    // eq 4.12 with tau = alpha |sigma*| (eq 4.13): sigma_delta(sigma*) = tau, sigma_delta(0) = delta.
    const RegularizedDeterminant reg{delta};
    CHECK(reg.value(sigma_star) == doctest::Approx(alpha * std::abs(sigma_star)).epsilon(1e-12));
    CHECK(reg.value(0.0) == doctest::Approx(delta).epsilon(1e-15));
    for (const double a : {1e-4, 1e-2, 0.3}) {
      const RegularizedDeterminant other{hom::regularization_delta(sigma_star, a)};
      CHECK(other.value(sigma_star) == doctest::Approx(a * std::abs(sigma_star)).epsilon(1e-12));
    }
  }
  // In the frame of J = D phi_E, sigma* = -1 and delta = sqrt(alpha^2 + alpha).
  CHECK(hom::element_regularization().delta == doctest::Approx(std::sqrt(1e-6 + 1e-3)).epsilon(1e-15));
  // The master-frame and ideal-frame readings of section 4.2.2 agree: sigma_{g delta}(g s) = g sigma_delta(s).
  const double delta_e = hom::element_regularization().delta;
  for (const double g : {1e-6, 0.433, 2.0, 1e4})
    for (const double s : {-3.0, -0.01, 0.0, 0.2, 5.0}) {
      const RegularizedDeterminant master{hom::regularization_delta(-g)};
      CHECK(master.value(g * s) == doctest::Approx(g * RegularizedDeterminant{delta_e}.value(s)).epsilon(1e-13));
    }
}

// ---------------------------------------------------------------- measures

TEST_CASE_TEMPLATE("eta = 1 at the ideal and for every c R", T, HOM_MEASURE_CASES) {
  constexpr int Dim = T::dim;
  const typename T::Measure measure;
  Rng rng(1 + Dim);
  CHECK(measure.value(Mat<Dim>::Identity().eval(), ClampedDeterminant{}) == doctest::Approx(1.0).epsilon(1e-15));
  for (int t = 0; t < 200; ++t) {
    const double c = log_uniform(rng, 1e-3, 1e3);
    const Mat<Dim> J = c * random_rotation<Dim>(rng);
    CHECK(std::abs(measure.value(J, ClampedDeterminant{}) - 1.0) <= 1e-13);
    CHECK(std::abs(measure.value(J, AbsoluteDeterminant{}) - 1.0) <= 1e-13);
    CHECK(std::abs(measure.value(J, RegularizedDeterminant{0.0}) - 1.0) <= 1e-13);
  }
}

TEST_CASE_TEMPLATE("eta > 1 for non-conformal valid J, and agrees with the plain formula", T, HOM_MEASURE_CASES) {
  constexpr int Dim = T::dim;
  const typename T::Measure measure;
  const bool is_shape = std::is_same_v<typename T::Measure, ShapeMeasure>;
  Rng rng(20 + Dim);
  for (int t = 0; t < 500; ++t) {
    const Mat<Dim> J = random_jacobian<Dim>(rng, +1.0);
    const double eta = measure.value(J, ClampedDeterminant{});
    CHECK(eta > 1.0 + 1e-10);
    CHECK(1.0 / eta > 0.0);
    CHECK(1.0 / eta < 1.0);
    const double det = J.determinant();
    const double ref = is_shape ? reference_shape<Dim>(J, det) : reference_oddy<Dim>(J, det);
    CHECK(rel_diff(eta, ref) < 1e-11);
    // Regularized with delta > 0: the denominator grows, so eta_delta < eta_0.
    CHECK(measure.value(J, RegularizedDeterminant{0.1}) < eta);
  }
}

TEST_CASE("Oddy: eq 3.3 as printed in 2D, and stricter than the shape measure") {
  Rng rng(5);
  for (int t = 0; t < 500; ++t) {
    const Mat<2> J = random_jacobian<2>(rng, +1.0);
    const double m = (J.transpose() * J).squaredNorm(), n = J.squaredNorm(), s = J.determinant();
    const double printed = 3.0 * (m - n * n / 3.0) / (2.0 * s * s);  // eq 3.3 with d = 2
    const double oddy = OddyMeasure{}.value(J, ClampedDeterminant{});
    const double shape = ShapeMeasure{}.value(J, ClampedDeterminant{});
    CHECK(rel_diff(oddy, printed) < 1e-11);
    CHECK(rel_diff(oddy, 4 * shape * shape - 3) < 1e-11);
    CHECK(oddy >= shape);
  }
  for (int t = 0; t < 500; ++t) {
    const Mat<3> J = random_jacobian<3>(rng, +1.0);
    CHECK(OddyMeasure{}.value(J, ClampedDeterminant{}) >= ShapeMeasure{}.value(J, ClampedDeterminant{}));
  }
}

TEST_CASE_TEMPLATE("invariance under rotations, scaling and reflections", T, HOM_MEASURE_CASES) {
  constexpr int Dim = T::dim;
  const typename T::Measure measure;
  Rng rng(30 + Dim);
  Mat<Dim> P = Mat<Dim>::Identity();
  P(0, 0) = -1.0;  // a reflection
  for (int t = 0; t < 300; ++t) {
    const Mat<Dim> R1 = random_rotation<Dim>(rng), R2 = random_rotation<Dim>(rng);
    const double c = log_uniform(rng, 1e-2, 1e2);

    // Valid J, validation measure: rotations on both sides, uniform scaling,
    // reflection of both ideal and physical element (P J P, same determinant).
    const Mat<Dim> J = random_jacobian<Dim>(rng, +1.0);
    const ClampedDeterminant clamped;
    const double eta = measure.value(J, clamped);
    CHECK(rel_diff(measure.value((R1 * J).eval(), clamped), eta) < 1e-12);
    CHECK(rel_diff(measure.value((J * R2).eval(), clamped), eta) < 1e-12);
    CHECK(rel_diff(measure.value((R1 * J * R2).eval(), clamped), eta) < 1e-12);
    CHECK(rel_diff(measure.value((c * J).eval(), clamped), eta) < 1e-12);
    CHECK(rel_diff(measure.value((P * J * P).eval(), clamped), eta) < 1e-12);
    // Reflecting only one side inverts the element: q = 0.
    CHECK(measure.value((J * P).eval(), clamped) == inf);

    // Regularized measure, any sign of det: rotations and P J P keep det and the norms.
    const RegularizedDeterminant reg{0.3};
    for (const double sign : {-1.0, 1.0}) {
      const Mat<Dim> K = random_jacobian<Dim>(rng, sign);
      const double eta_d = measure.value(K, reg);
      CHECK(rel_diff(measure.value((R1 * K).eval(), reg), eta_d) < 1e-12);
      CHECK(rel_diff(measure.value((K * R2).eval(), reg), eta_d) < 1e-12);
      CHECK(rel_diff(measure.value((P * K * P).eval(), reg), eta_d) < 1e-12);
    }
  }
}

TEST_CASE_TEMPLATE("validation: eta -> inf as det -> 0+, eta = inf (q = 0) for det <= 0", T, HOM_MEASURE_CASES) {
  constexpr int Dim = T::dim;
  const typename T::Measure measure;
  const ClampedDeterminant clamped;
  Rng rng(40 + Dim);
  for (int t = 0; t < 50; ++t) {
    const Mat<Dim> R1 = random_rotation<Dim>(rng), R2 = random_rotation<Dim>(rng);
    double previous = 1.0;
    for (int k = 1; k <= 10; ++k) {
      Mat<Dim> D = Mat<Dim>::Identity();
      D(Dim - 1, Dim - 1) = std::pow(10.0, -k);  // flattening towards a degenerate element
      const double eta = measure.value((R1 * D * R2).eval(), clamped);
      CHECK(eta > previous);
      previous = eta;
    }
    CHECK(previous > 1e5);

    const Mat<Dim> inverted = random_jacobian<Dim>(rng, -1.0);
    CHECK(measure.value(inverted, clamped) == inf);
    CHECK(1.0 / measure.value(inverted, clamped) == 0.0);
    Mat<Dim> singular = random_matrix<Dim>(rng);
    singular.col(1) = 2.0 * singular.col(0);
    singular.row(0).setZero();
    CHECK(measure.value(singular, clamped) == inf);

    // No derivatives where eta is infinite: reported as NaN, never as numbers.
    Mat<Dim> grad;
    Hess<Dim> hess;
    CHECK(measure.value_gradient(inverted, clamped, grad) == inf);
    CHECK(std::isnan(grad(0, 0)));
    CHECK(measure.value_gradient_hessian(inverted, clamped, grad, hess) == inf);
    CHECK(std::isnan(hess(0, 0)));
  }
}

TEST_CASE_TEMPLATE("regularized measure: finite everywhere and continuous across det = 0", T, HOM_MEASURE_CASES) {
  constexpr int Dim = T::dim;
  const typename T::Measure measure;
  Rng rng(50 + Dim);
  for (const double delta : {1e-3, 0.05, 1.0}) {
    const RegularizedDeterminant reg{delta};
    for (int t = 0; t < 200; ++t) {
      CHECK(std::isfinite(measure.value(random_jacobian<Dim>(rng, -1.0), reg)));
      CHECK(std::isfinite(measure.value(random_jacobian<Dim>(rng, +1.0), reg)));
    }
    CHECK(std::isfinite(measure.value(Mat<Dim>::Zero().eval(), reg)));
    CHECK(std::isfinite(measure.value((-Mat<Dim>::Identity()).eval(), reg)));

    // Sweep J(t) = R1 diag(t, 1, ...) R2 through det = 0: no jump larger than the
    // slope allows (the unregularized measure has an asymptote here).
    const Mat<Dim> R1 = random_rotation<Dim>(rng), R2 = random_rotation<Dim>(rng);
    const int n = 4000;
    double max_jump = 0.0, max_value = 0.0, previous = 0.0;
    for (int i = 0; i <= n; ++i) {
      Mat<Dim> D = Mat<Dim>::Identity();
      D(0, 0) = -0.5 + 1.0 * i / n;
      const double eta = measure.value((R1 * D * R2).eval(), reg);
      REQUIRE(std::isfinite(eta));
      if (i > 0) max_jump = std::max(max_jump, std::abs(eta - previous));
      max_value = std::max(max_value, eta);
      previous = eta;
    }
    CHECK(max_jump < 0.01 * max_value);
  }
}

TEST_CASE_TEMPLATE("gradient and Hessian agree with central finite differences", T, HOM_MEASURE_CASES) {
  constexpr int Dim = T::dim;
  const typename T::Measure measure;
  Rng rng(60 + Dim);
  SUBCASE("validation measure, det > 0") {
    for (int t = 0; t < 200; ++t) check_derivatives<Dim>(measure, random_jacobian<Dim>(rng, +1.0), ClampedDeterminant{});
    for (int t = 0; t < 50; ++t) {
      const double c = log_uniform(rng, 1e-2, 1e2);
      check_derivatives<Dim>(measure, (c * random_jacobian<Dim>(rng, +1.0)).eval(), ClampedDeterminant{});
    }
  }
  SUBCASE("regularized measure, det of both signs") {
    for (const double delta : {0.05, 0.5, 2.0}) {
      const RegularizedDeterminant reg{delta};
      for (int t = 0; t < 100; ++t) {
        check_derivatives<Dim>(measure, random_jacobian<Dim>(rng, -1.0), reg);
        check_derivatives<Dim>(measure, random_jacobian<Dim>(rng, +1.0), reg);
      }
      // Near and at det = 0, where the regularization matters most.
      for (int t = 0; t < 50; ++t) {
        Mat<Dim> J = random_matrix<Dim>(rng);
        J.col(Dim - 1) = J.col(0) + 1e-3 * J.col(Dim - 1);
        check_derivatives<Dim>(measure, J, reg);
      }
      check_derivatives<Dim>(measure, Mat<Dim>::Identity().eval(), reg);
    }
  }
}

TEST_CASE_TEMPLATE("directional Hessian: the full Hessian contracted with rank-one directions e_a w^T", T,
                   HOM_MEASURE_CASES) {
  constexpr int Dim = T::dim;
  const typename T::Measure measure;
  Rng rng(90 + Dim);
  std::normal_distribution<double> normal;
  for (const double delta : {0.0, 0.05, 1.0}) {
    for (int t = 0; t < 100; ++t) {
      const Mat<Dim> J = random_jacobian<Dim>(rng, delta > 0.0 && t % 2 ? -1.0 : +1.0);
      Eigen::Matrix<double, Dim, 1> w;
      for (int k = 0; k < Dim; ++k) w[k] = normal(rng);
      Mat<Dim> grad, grad_full, hw;
      Hess<Dim> hess;
      double eta, eta_full;
      if (delta > 0.0) {
        const RegularizedDeterminant reg{delta};
        eta = value_gradient_directional_hessian(measure, J, reg, w, grad, hw);
        eta_full = measure.value_gradient_hessian(J, reg, grad_full, hess);
      } else {
        eta = value_gradient_directional_hessian(measure, J, ClampedDeterminant{}, w, grad, hw);
        eta_full = measure.value_gradient_hessian(J, ClampedDeterminant{}, grad_full, hess);
      }
      CHECK(eta == doctest::Approx(eta_full).epsilon(1e-13));
      CHECK((grad - grad_full).cwiseAbs().maxCoeff() <= 1e-13 * grad_full.cwiseAbs().maxCoeff());
      // Independent reference: d^2 eta / du_a du_b of J + u w^T is sum_{k,m} hess(a + D k, b + D m) w_k w_m.
      Mat<Dim> expected;
      for (int a = 0; a < Dim; ++a)
        for (int b = 0; b < Dim; ++b) {
          double sum = 0.0;
          for (int k = 0; k < Dim; ++k)
            for (int m = 0; m < Dim; ++m) sum += hess(a + Dim * k, b + Dim * m) * w[k] * w[m];
          expected(a, b) = sum;
        }
      CHECK((hw - expected).cwiseAbs().maxCoeff() <= 1e-11 * std::max(1.0, expected.cwiseAbs().maxCoeff()));
    }
  }
}

// ---------------------------------------------------------------- figure 4.5

namespace {

/// D phi_E = D phi_P (D phi_I)^{-1} for the triangle of figure 4.4:
/// x0 = (0, 0.5), x1 = (0, -0.5), x2 = (x, 0), with the equilateral ideal of side 1
/// whose third vertex is (sqrt(3)/2, 0). For a linear triangle a, b, c: D phi = [b - a, c - a].
Mat<2> figure_4_4_jacobian(double x) {
  const Eigen::Vector2d x0(0.0, 0.5), x1(0.0, -0.5), x2(x, 0.0);
  const Eigen::Vector2d i0(0.0, 0.5), i1(0.0, -0.5), i2(std::sqrt(3.0) / 2, 0.0);
  Mat<2> DP, DI;
  DP << x1 - x0, x2 - x0;
  DI << i1 - i0, i2 - i0;
  return DP * DI.inverse();
}

}  // namespace

TEST_CASE("figure 4.5: the regularized shape distortion has a single minimum near sqrt(3)/2") {
  const ShapeMeasure shape;
  const RegularizedDeterminant reg{0.05};
  const double ideal_x = std::sqrt(3.0) / 2;
  CHECK(std::abs(shape.value(figure_4_4_jacobian(ideal_x), ClampedDeterminant{}) - 1.0) < 1e-13);

  const int n = 10000;  // x in [-5, 5], step 1e-3; x = 0 is sample n/2
  std::vector<double> xs, eta_reg, eta_0, eta_abs;
  for (int i = 0; i <= n; ++i) {
    const double x = -5.0 + 10.0 * i / n;
    const Mat<2> J = figure_4_4_jacobian(x);
    xs.push_back(x);
    eta_reg.push_back(shape.value(J, reg));
    eta_0.push_back(shape.value(J, ClampedDeterminant{}));
    eta_abs.push_back(shape.value(J, AbsoluteDeterminant{}));
  }
  auto local_minima = [&](const std::vector<double>& f) {
    std::vector<double> at;
    for (int i = 1; i < n; ++i)
      if (std::isfinite(f[i]) && f[i] < f[i - 1] && f[i] <= f[i + 1]) at.push_back(xs[i]);
    return at;
  };

  // Regularized (eq 3.5): finite everywhere, no asymptote at x = 0, one minimum near the ideal.
  for (const double v : eta_reg) CHECK(std::isfinite(v));
  CHECK(eta_reg[n / 2] == doctest::Approx(shape.value(figure_4_4_jacobian(0.0), reg)));
  CHECK(eta_reg[n / 2] < 1e3);
  const std::vector<double> minima = local_minima(eta_reg);
  REQUIRE(minima.size() == 1);
  CHECK(std::abs(minima[0] - ideal_x) < 0.02);
  const double min_value = *std::min_element(eta_reg.begin(), eta_reg.end());
  CHECK(min_value == doctest::Approx(1.0).epsilon(0.01));
  CHECK(eta_reg.front() > 10 * min_value);  // grows towards both ends
  CHECK(eta_reg.back() > 2 * min_value);

  // Validation (eq 3.7): infinite (q = 0) for x <= 0, finite and >= 1 for x > 0.
  for (int i = 0; i <= n; ++i) {
    CAPTURE(xs[i]);
    if (xs[i] <= 0.0) CHECK(eta_0[i] == inf);
    else {
      CHECK(std::isfinite(eta_0[i]));
      CHECK(eta_0[i] >= 1.0 - 1e-14);
    }
  }

  // Eq 3.2 as printed (|sigma|): the inverted mirror image also scores 1, with an asymptote at 0.
  const std::vector<double> abs_minima = local_minima(eta_abs);
  REQUIRE(abs_minima.size() == 2);
  CHECK(std::abs(abs_minima[0] + ideal_x) < 2e-3);
  CHECK(std::abs(abs_minima[1] - ideal_x) < 2e-3);
  CHECK(shape.value(figure_4_4_jacobian(-ideal_x), AbsoluteDeterminant{}) == doctest::Approx(1.0).epsilon(1e-13));
  CHECK(eta_abs[n / 2] == inf);
}

TEST_CASE("point lanes: the Newton inverse cube root agrees with std::cbrt over the whole double range") {
  constexpr int W = hom::detail::point_lanes;
  Rng rng(11);
  std::uniform_real_distribution<double> exponent(-300.0, 300.0);
  double worst = 0.0;
  for (int trial = 0; trial < 20000; ++trial) {
    double s[W], y[W];
    for (int l = 0; l < W; ++l) s[l] = std::pow(10.0, trial < 10000 ? exponent(rng) / 10.0 : exponent(rng));
    hom::detail::inverse_cube_root<W>(s, y);
    for (int l = 0; l < W; ++l) worst = std::max(worst, std::abs(y[l] * std::cbrt(s[l]) - 1.0));
  }
  CHECK(worst < 1e-15);  // a few ulps, std::cbrt's own error included
  // Exact cubes, the single-precision range's ends and lanes outside it.
  double s[W] = {8.0, 1e-30, 1e30, 0.125}, y[W];
  hom::detail::inverse_cube_root<W>(s, y);
  CHECK(y[0] == doctest::Approx(0.5).epsilon(1e-15));
  CHECK(y[3] == doctest::Approx(2.0).epsilon(1e-15));
  double t[W] = {1e-200, 1e200, 0.0, -8.0}, z[W];
  hom::detail::inverse_cube_root<W>(t, z);
  CHECK(z[0] == doctest::Approx(1.0 / std::cbrt(1e-200)).epsilon(1e-15));
  CHECK(z[1] == doctest::Approx(1.0 / std::cbrt(1e200)).epsilon(1e-15));
  CHECK(z[2] == inf);
  CHECK(z[3] == doctest::Approx(-0.5).epsilon(1e-15));
}

TEST_CASE("point lanes: first_jet of sigma_delta and sigma_0 is jet's value and first derivative") {
  constexpr int W = hom::detail::point_lanes;
  const double samples[] = {-1e200, -3.0, -1e-3, -1e-12, 0.0, 1e-12, 1e-3, 0.7, 5.0, 1e200, -1e-300, 1e-300};
  for (double delta : {0.0, 1e-3, 0.0316, 2.0}) {
    const RegularizedDeterminant reg{delta};
    for (std::size_t k = 0; k + W <= std::size(samples); k += W) {
      double s[W], v[W], d[W];
      for (int l = 0; l < W; ++l) s[l] = samples[k + l];
      reg.first_jet<W>(s, v, d);
      for (int l = 0; l < W; ++l) {
        CAPTURE(delta);
        CAPTURE(s[l]);
        const auto jet = reg.jet(s[l]);
        CHECK(v[l] == doctest::Approx(jet.value).epsilon(1e-14));
        CHECK(d[l] == doctest::Approx(jet.first).epsilon(1e-14));
      }
    }
  }
  const ClampedDeterminant clamped;
  double s[W] = {-1.0, 0.0, 1e-300, 2.0}, v[W], d[W];
  clamped.first_jet<W>(s, v, d);
  for (int l = 0; l < W; ++l) {
    CHECK(v[l] == clamped.jet(s[l]).value);
    CHECK(d[l] == clamped.jet(s[l]).first);
  }
}

TEST_CASE_TEMPLATE("point lanes: value_gradient_lanes is value_gradient in every lane", T, Shape2, Shape3) {
  constexpr int D = T::dim, W = hom::detail::point_lanes;
  const typename T::Measure measure;
  static_assert(hom::BatchedMeasureFor<typename T::Measure, D, RegularizedDeterminant>);
  static_assert(hom::BatchedMeasureFor<typename T::Measure, D, ClampedDeterminant>);
  static_assert(!hom::BatchedMeasureFor<OddyMeasure, D, ClampedDeterminant>);
  Rng rng(29);
  auto check = [&](const auto& reg) {
    for (int trial = 0; trial < 500; ++trial) {
      double J[D * D][W], grad[D * D][W], eta[W];
      Mat<D> Js[W];
      for (int l = 0; l < W; ++l) {
        Js[l] = random_matrix<D>(rng);
        if (trial % 5 == 0) Js[l] *= 1e-12;  // tiny determinants: the cube root's fallback
        for (int i = 0; i < D * D; ++i) J[i][l] = Js[l].data()[i];
      }
      measure.template value_gradient_lanes<D, W>(J, reg, grad, eta);
      for (int l = 0; l < W; ++l) {
        Mat<D> g;
        const double e = measure.value_gradient(Js[l], reg, g);
        if (!std::isfinite(e)) {
          CHECK(eta[l] == inf);
          continue;
        }
        CHECK(eta[l] == doctest::Approx(e).epsilon(1e-13));
        Mat<D> gl;
        for (int i = 0; i < D * D; ++i) gl.data()[i] = grad[i][l];
        CHECK((gl - g).norm() <= 1e-13 * g.norm());
      }
    }
  };
  check(RegularizedDeterminant{0.0316});
  check(ClampedDeterminant{});
}
