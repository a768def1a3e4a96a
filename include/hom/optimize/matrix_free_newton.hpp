#pragma once
/// @file matrix_free_newton.hpp
/// Truncated Newton-CG for eq 4.11 without assembling the Hessian: for large
/// problems, where a degree-10 tetrahedron's element Hessian alone is 858 x 858.
///
/// Step k: approximately solve (H_k + lambda_k I) p = -grad f_k by
/// preconditioned conjugate gradients, then backtrack along p (LineSearch;
/// +inf rejected, section 4.2.2).
///   - Hessian-vector products are computed element by element from data at
///     the quadrature points (OptimizationProblem::HessianOperator,
///     apply_element_hessian): dJ_q = V G_q, S_q = M_q : dJ_q, H V = sum_q S_q G_q^T,
///     with M_q the point's second-order term, never an element Hessian.
///   - Hessian model (`hessian`). HessianForm::projected by default: each
///     point's second-order term replaced by its positive semi-definite part,
///     as NewtonSolver does; Dim^4 numbers stored per quadrature point (648
///     bytes in 3D: 3.2 GB for the 1441 degree-10 tetrahedra of table 4.1 with
///     the default quadrature). HessianForm::gauss_newton, M_q = c_q g g^T
///     (g = d eta / dJ_P), the Gauss-Newton model of the least squares eq 4.10,
///     stores Dim^2 numbers per point (9x less) and is also positive
///     semi-definite, but it drops the (eta - 1) H_eta term, which is not small
///     where the optimum has f > 0 (curved boundaries): there it needs many
///     more, shorter steps (measured: 92 iterations and a stalled minimum
///     quality against 51 for the projected form on the ring of figure C.2).
///     HessianForm::exact also works (CG stops at negative curvature).
///   - CG stops (Steihaug) when ||r|| <= eta_k ||grad f_k|| with the forcing
///     term eta_k = min(forcing_max, sqrt(||grad f_k|| / ||grad f_0||)), on
///     non-positive curvature d^T H d <= 0 (returning the current iterate, or
///     the preconditioned steepest-descent direction at the first CG step), or
///     after max_cg_iterations.
///   - Preconditioner: Jacobi by nodes, (t_k + lambda_k)^-1 I for free node k,
///     t_k = trace(d^2 f / dx_k^2) / Dim (HessianOperator::diagonal_means; the
///     full Dim x Dim blocks would cost Dim^2 Hessian-vector products to form).
///   - lambda_k = mu_k * mean_k(t_k), a Levenberg-
///     Marquardt shift: mu starts at initial_shift, grows by shift_factor when
///     the line search fails (and the step is retried) or accepts only a
///     shortened step (the model over-predicted the decrease), and shrinks
///     after a full step. Shrinking after every accepted step instead kept the
///     shift too small near the optimum at p = 10 (bench_untangle --p 10
///     --pcont: 50 CG iterations and 4-5 backtracks per step, min quality
///     0.956 after 146 s of the high-order stage, not converged; with this
///     rule 28 steps and 104 s to a converged 0.958).
/// Dot products are serial Eigen reductions and products are assembled per
/// node in element order, so iterates do not depend on the number of threads.

#include <algorithm>
#include <cmath>
#include <string_view>
#include <vector>

#include <Eigen/Dense>

#include "hom/optimize/problem.hpp"
#include "hom/optimize/solver.hpp"

namespace hom {

struct MatrixFreeNewton {
  static constexpr std::string_view name = "matrix-free-newton";

  HessianForm hessian = HessianForm::projected;
  /// Truncation: near the degenerate minimum (f ~ |x - x*|^4) long inner solves
  /// buy little (bench_untangle p = 5: 90-250 CG iterations per step for a
  /// 1e-4 quality gain), so CG stops early.
  int max_cg_iterations = 50;
  double forcing_max = 0.1;
  double initial_shift = 1e-10;
  double shift_factor = 10.0;
  double max_shift = 1e10;
  LineSearch line_search{};

  template <ElementFamily Family, class Measure>
  SolverResult solve(OptimizationProblem<Family, Measure>& problem, const SolverOptions& options) const {
    Step<OptimizationProblem<Family, Measure>> step(*this);
    const detail::SerialEigenScope serial_eigen;
    return detail::run_outer_loop(problem, options, name, step);
  }

 private:
  template <class Problem>
  struct Step {
    static constexpr int D = Problem::dim;
    explicit Step(const MatrixFreeNewton& solver) : s(solver) {}
    const MatrixFreeNewton& s;
    typename Problem::HessianOperator op;
    double mu = 0.0;
    double first_gradient_norm = 0.0;

    double evaluate(Problem& problem, Eigen::VectorXd& g) {
      const double f = problem.hessian_operator(problem.coordinates(), s.hessian, g, op);
      if (first_gradient_norm == 0.0) first_gradient_norm = g.norm();
      return f;
    }

    // Preconditioned CG with Steihaug's stopping rules on (H + shift I) p = -g;
    // `inverse_diagonal[k]` preconditions free node k's Dim components.
    Eigen::VectorXd solve_cg(const Eigen::VectorXd& g, double shift, const Eigen::VectorXd& inverse_diagonal,
                             int& iterations) const {
      const int n = int(g.size());
      const double gnorm = g.norm();
      const double forcing =
          std::min(s.forcing_max, std::sqrt(first_gradient_norm > 0.0 ? gnorm / first_gradient_norm : 1.0));
      auto precondition = [&](const Eigen::VectorXd& r) {
        Eigen::VectorXd z(n);
        for (int k = 0; k < int(inverse_diagonal.size()); ++k)
          z.template segment<D>(D * k) = inverse_diagonal[k] * r.template segment<D>(D * k);
        return z;
      };
      Eigen::VectorXd p = Eigen::VectorXd::Zero(n);
      Eigen::VectorXd r = g;  // residual of (H + shift) p + g
      Eigen::VectorXd z = precondition(r);
      Eigen::VectorXd d = -z;
      Eigen::VectorXd Hd(n);
      double rz = r.dot(z);
      iterations = 0;
      for (int j = 0; j < s.max_cg_iterations; ++j) {
        op.apply(d, Hd);
        Hd += shift * d;
        const double curvature = d.dot(Hd);
        iterations = j + 1;
        if (!(curvature > 0.0)) {
          if (j == 0) p = d;
          break;
        }
        const double a = rz / curvature;
        p += a * d;
        r += a * Hd;
        if (r.norm() <= forcing * gnorm) break;
        z = precondition(r);
        const double rz_new = r.dot(z);
        d = -z + (rz_new / rz) * d;
        rz = rz_new;
      }
      return p;
    }

    detail::StepOutcome advance(Problem& problem, double f, const Eigen::VectorXd& g) {
      detail::StepOutcome out;
      if (problem.num_dofs() == 0) return out;
      if (mu == 0.0) mu = s.initial_shift;
      const Eigen::VectorXd& diagonal = op.diagonal_means();
      const double mean = diagonal.size() > 0 ? diagonal.mean() : 0.0;
      const double scale = mean > 0.0 ? mean : 1.0;
      const auto& X = problem.coordinates();
      int inner = 0;
      for (; mu <= s.max_shift; mu *= s.shift_factor) {
        const double shift = mu * scale;
        // The diagonal is non-negative for the PSD forms; the floor keeps nodes
        // whose diagonal vanishes (at an ideal configuration) invertible.
        const Eigen::VectorXd inverse = (diagonal.cwiseMax(0.0).array() + shift + 1e-12 * scale).inverse().matrix();
        int cg = 0;
        const Eigen::VectorXd p = solve_cg(g, shift, inverse, cg);
        inner += cg;
        const double slope = g.dot(p);
        if (!(slope < 0.0) || !p.allFinite()) continue;
        const auto ls = s.line_search.search([&](double alpha) { return problem.value(problem.displaced(X, p, alpha)); }, f,
                                             slope);
        if (!ls.accepted) continue;
        problem.coordinates() = problem.displaced(X, p, ls.step);
        out.success = true;
        out.objective = ls.value;
        out.step = ls.step;
        out.inner = inner;
        // The shift rule of the file comment (lambda_k).
        mu = ls.step < 1.0 ? std::min(mu * s.shift_factor, s.max_shift) : std::max(mu / s.shift_factor, s.initial_shift);
        return out;
      }
      return out;
    }
  };
};

static_assert(MeshSolverFor<MatrixFreeNewton, OptimizationProblem<Simplex<2>>>);

}  // namespace hom
