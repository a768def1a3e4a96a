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
///   - The factorization is CHOLMOD's supernodal Cholesky (Eigen's
///     CholmodSupport) when hom is built with HOM_HAVE_CHOLMOD (meson defines
///     it when SuiteSparse is found), Eigen::SimplicialLDLT otherwise; the
///     pattern is analysed once per solve. (On 1512 degree-2 tetrahedra the
///     simplicial factorization took 40% of the solve.)
///   - Memory: the matrix is kept three times (the cached pattern, H_k and the
///     shifted copy that is factorized), 12 bytes per stored entry each, and
///     the factor holds at least half as many entries again. Before assembling
///     anything the solver counts the entries and refuses (std::runtime_error)
///     a problem that needs more than the memory available; with CHOLMOD it
///     checks the factor's predicted size again after the symbolic analysis.
///     (Table 4.1 at p = 10 would need tens of GB: the matrix-free solver is
///     the one for it.)

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <string_view>

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#if defined(HOM_HAVE_CHOLMOD)
#include <Eigen/CholmodSupport>
#endif

#include "hom/detail/available_memory.hpp"
#include "hom/optimize/problem.hpp"
#include "hom/optimize/solver.hpp"

namespace hom {

/// The sparse Cholesky factorization NewtonSolver uses (see the file comment).
#if defined(HOM_HAVE_CHOLMOD)
template <class SparseMatrix>
using SparseCholesky = Eigen::CholmodSupernodalLLT<SparseMatrix, Eigen::Lower>;
#else
template <class SparseMatrix>
using SparseCholesky = Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower>;
#endif

/// What the outer loop (solver.hpp) and the Newton step need of a problem:
/// OptimizationProblem (node coordinates) and the surface problem of chapter 5
/// (parametric coordinates) both model it.
template <class P>
concept AssembledProblem = requires(P& p, const P& cp, const typename P::Coordinates& X, const Eigen::VectorXd& v,
                                    Eigen::VectorXd& g, typename P::SparseMatrix& H, const MeshState& state) {
  { p.coordinates() } -> std::same_as<typename P::Coordinates&>;
  { cp.num_dofs() } -> std::convertible_to<int>;
  { cp.value(X) } -> std::convertible_to<double>;
  { cp.displaced(X, v, 1.0) } -> std::convertible_to<typename P::Coordinates>;
  { cp.hessian(X, HessianForm::projected, g, H) } -> std::convertible_to<double>;
  { cp.status(X) } -> std::same_as<MeshState>;
  { p.update_regularization(state) } -> std::convertible_to<int>;
  { cp.scaled_gradient_norm(v) } -> std::convertible_to<double>;
};

struct NewtonSolver {
  static constexpr std::string_view name = "newton";

  HessianForm hessian = HessianForm::projected;
  double initial_shift = 1e-10;  ///< mu_0, relative to mean(diag H)
  double shift_factor = 10.0;
  double max_shift = 1e10;  ///< give up (line search failed) beyond this mu
  int backtracks_to_increase_shift = 3;  ///< an accepted step this short raises mu
  LineSearch line_search{};
  /// Bytes the solver may use; <= 0: the system's available memory, read when
  /// solve starts (no check where the system does not say).
  double memory_limit_bytes = 0.0;

  /// Lower bound of the bytes the assembled solve needs (see the file comment).
  static double memory_needed_bytes(std::int64_t nonzeros, std::int64_t pattern_extra_bytes) {
    const double per_entry = 3.0 * (sizeof(double) + sizeof(int)) + 0.5 * sizeof(double);
    return per_entry * double(nonzeros) + double(pattern_extra_bytes);
  }

  template <AssembledProblem Problem>
  SolverResult solve(Problem& problem, const SolverOptions& options) const {
    if constexpr (requires { problem.hessian_nonzeros(); problem.hessian_pattern_extra_bytes(); }) {
      const std::int64_t nonzeros = problem.hessian_nonzeros();
      refuse_beyond_memory(memory_needed_bytes(nonzeros, problem.hessian_pattern_extra_bytes()),
                           std::to_string(nonzeros) + " nonzeros over " + std::to_string(problem.num_dofs()) +
                               " free coordinates");
    }
    Step<Problem> step(*this);
    const detail::SerialEigenScope serial_eigen;
    return detail::run_outer_loop(problem, options, name, step);
  }

 private:
  double memory_limit() const { return memory_limit_bytes > 0.0 ? memory_limit_bytes : detail::available_memory_bytes(); }

  /// Throws when `needed` bytes exceed the limit; `what` says what needs them.
  void refuse_beyond_memory(double needed, const std::string& what) const {
    const double limit = memory_limit();
    if (limit <= 0.0 || needed <= limit) return;
    char sizes[96];
    std::snprintf(sizes, sizeof sizes, "at least %.2f GB, more than the %.2f GB available", needed / 1e9, limit / 1e9);
    throw std::runtime_error("solver newton: the assembled Hessian (" + what + ") needs " + sizes +
                             "; use the matrix-free solver (matrix-free), which stores no matrix");
  }

  template <class Problem>
  struct Step {
    explicit Step(const NewtonSolver& solver) : s(solver) {}
    const NewtonSolver& s;
    typename Problem::SparseMatrix H;
    SparseCholesky<typename Problem::SparseMatrix> chol;
    bool analysed = false;
    double mu = 0.0;

    double evaluate(Problem& problem, Eigen::VectorXd& g) {
      return problem.hessian(problem.coordinates(), s.hessian, g, H);
    }

    bool positive_definite() const {
      if (chol.info() != Eigen::Success) return false;
#if defined(HOM_HAVE_CHOLMOD)
      return true;
#else
      return chol.vectorD().minCoeff() > 0.0;
#endif
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
#if defined(HOM_HAVE_CHOLMOD)
          chol.cholmod().print = 0;  // a failed factorization is expected (the shift grows); no messages
#endif
          chol.analyzePattern(A);
          analysed = true;
#if defined(HOM_HAVE_CHOLMOD)
          // The symbolic analysis predicts the factor's entries (fill-in included).
          s.refuse_beyond_memory(chol.cholmod().lnz * sizeof(double),
                                 "its Cholesky factor of " + std::to_string(std::int64_t(chol.cholmod().lnz)) + " entries");
#endif
        }
        chol.factorize(A);
        if (!positive_definite()) continue;
        const Eigen::VectorXd p = chol.solve(-g);
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
        // Levenberg-Marquardt update: a full step means the model is good
        // (less shift); a heavily backtracked one means it overshoots (more shift).
        if (ls.backtracks == 0)
          mu = std::max(mu / s.shift_factor, s.initial_shift);
        else if (ls.backtracks >= s.backtracks_to_increase_shift)
          mu *= s.shift_factor;
        return out;
      }
      return out;
    }
  };
};

static_assert(AssembledProblem<OptimizationProblem<Simplex<2>>>);
static_assert(MeshSolverFor<NewtonSolver, OptimizationProblem<Simplex<2>>>);

}  // namespace hom
