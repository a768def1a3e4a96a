#pragma once
/// @file newton.hpp
/// Global Newton's method for eq 4.11 with the assembled sparse Hessian
/// (appendix B: "for small problems solving the global system resulting from
/// assembling the contributions of all the elements works well").
///
/// Step k: solve (H_k + lambda_k I) p = -grad f_k, then backtrack along p
/// (LineSearch, Armijo, +inf rejected: section 4.2.2's consistency).
///   - H_k is assembled over the free dofs from the element Hessians with each
///     quadrature point's block replaced by its positive semi-definite part
///     (HessianForm::projected), so H_k is PSD: the modification for
///     indefinite Hessians. (The minimum of eq 4.10 at an ideal configuration
///     is degenerate, f ~ |x - x*|^4, so H vanishes there; the final iterations
///     converge linearly, as the element tests document.)
///   - lambda_k = mu_k * mean(diag H_k) is a Levenberg-Marquardt shift that
///     makes the factorization positive definite. mu starts at initial_shift;
///     when the factorization is not positive definite, p is not a descent
///     direction or the line search fails, mu grows by shift_factor (shorter,
///     more gradient-like steps) and the step is retried; after an accepted
///     step mu shrinks by shift_factor, down to initial_shift.
///   - The factorization is Eigen::SimplicialLDLT (sparse Cholesky, AMD
///     ordering; the pattern is analysed once per solve).

#include <algorithm>
#include <string_view>

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include "hom/optimize/problem.hpp"
#include "hom/optimize/solver.hpp"

namespace hom {

struct NewtonSolver {
  static constexpr std::string_view name = "newton";

  HessianForm hessian = HessianForm::projected;
  double initial_shift = 1e-10;  ///< mu_0, relative to mean(diag H)
  double shift_factor = 10.0;
  double max_shift = 1e10;  ///< give up (line search failed) beyond this mu
  LineSearch line_search{};

  template <ElementFamily Family, class Measure>
  SolverResult solve(OptimizationProblem<Family, Measure>& problem, const SolverOptions& options) const {
    Step<OptimizationProblem<Family, Measure>> step{*this};
    const detail::SerialEigenScope serial_eigen;
    return detail::run_outer_loop(problem, options, name, step);
  }

 private:
  template <class Problem>
  struct Step {
    const NewtonSolver& s;
    typename Problem::SparseMatrix H;
    Eigen::SimplicialLDLT<typename Problem::SparseMatrix> ldlt;
    bool analysed = false;
    double mu = 0.0;

    double evaluate(Problem& problem, Eigen::VectorXd& g) {
      return problem.hessian(problem.coordinates(), s.hessian, g, H);
    }

    detail::StepOutcome advance(Problem& problem, double f, const Eigen::VectorXd& g) {
      detail::StepOutcome out;
      if (problem.num_dofs() == 0) return out;
      if (mu == 0.0) mu = s.initial_shift;
      const Eigen::VectorXd diag = H.diagonal();
      const double scale = diag.size() > 0 && diag.mean() > 0.0 ? diag.mean() : 1.0;
      const auto& X = problem.coordinates();
      for (int tries = 0; mu <= s.max_shift; ++tries, mu *= s.shift_factor) {
        typename Problem::SparseMatrix A = H;
        for (int i = 0; i < A.rows(); ++i) A.coeffRef(i, i) += mu * scale;
        if (!analysed) {
          ldlt.analyzePattern(A);
          analysed = true;
        }
        ldlt.factorize(A);
        if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) continue;
        const Eigen::VectorXd p = ldlt.solve(-g);
        const double slope = g.dot(p);
        if (!(slope < 0.0) || !p.allFinite()) continue;
        const auto ls = s.line_search.search([&](double alpha) { return problem.value(problem.displaced(X, p, alpha)); }, f,
                                             slope);
        if (!ls.accepted) continue;
        problem.coordinates() = problem.displaced(X, p, ls.step);
        out.success = true;
        out.objective = ls.value;
        out.step = ls.step;
        out.inner = tries;
        mu = std::max(mu / s.shift_factor, s.initial_shift);
        return out;
      }
      return out;
    }
  };
};

}  // namespace hom
