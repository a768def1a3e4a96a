#pragma once
/// @file solve.hpp
/// The three solvers of eq 4.11 behind one run-time switch: SolverKind names
/// them (for options and command lines) and `solve_with` runs the chosen one
/// with its default settings.

#include <stdexcept>
#include <string>
#include <string_view>

#include "hom/optimize/gauss_seidel.hpp"
#include "hom/optimize/matrix_free_newton.hpp"
#include "hom/optimize/newton.hpp"
#include "hom/optimize/problem.hpp"
#include "hom/optimize/solver.hpp"

namespace hom {

enum class SolverKind {
  newton,              ///< NewtonSolver: assembled sparse Hessian (small and medium meshes)
  matrix_free_newton,  ///< MatrixFreeNewton: truncated Newton-CG (large meshes, high p)
  gauss_seidel,        ///< GaussSeidel: non-linear Gauss-Seidel of appendix B (low memory)
};

inline std::string_view to_string(SolverKind k) {
  switch (k) {
    case SolverKind::newton: return "newton";
    case SolverKind::matrix_free_newton: return "matrix-free-newton";
    case SolverKind::gauss_seidel: return "gauss-seidel";
  }
  return "unknown";
}

inline SolverKind parse_solver_kind(const std::string& s) {
  if (s == "newton") return SolverKind::newton;
  if (s == "matrix-free" || s == "matrix-free-newton" || s == "newton-cg" || s == "cg") return SolverKind::matrix_free_newton;
  if (s == "gauss-seidel" || s == "gs") return SolverKind::gauss_seidel;
  throw std::invalid_argument("unknown solver '" + s + "' (expected newton, matrix-free or gauss-seidel)");
}

/// Free coordinates up to which the "auto" solver choice (`hom optimize
/// --solver auto`, `hom curve`) is the assembled Newton method; above it the
/// sparse Hessian's factorization costs more memory and time than the
/// matrix-free Newton-CG iterations.
constexpr long auto_newton_max_dofs = 20000;

/// The "auto" solver for a problem of `free_dofs` free coordinates.
inline SolverKind auto_solver_kind(long free_dofs) {
  return free_dofs <= auto_newton_max_dofs ? SolverKind::newton : SolverKind::matrix_free_newton;
}

/// Runs the solver `kind` (default settings) on `problem`.
template <ElementFamily Family, class Measure>
SolverResult solve_with(SolverKind kind, OptimizationProblem<Family, Measure>& problem, const SolverOptions& options) {
  switch (kind) {
    case SolverKind::newton: return NewtonSolver{}.solve(problem, options);
    case SolverKind::matrix_free_newton: return MatrixFreeNewton{}.solve(problem, options);
    case SolverKind::gauss_seidel: return GaussSeidel{}.solve(problem, options);
  }
  throw std::invalid_argument("hom::solve_with: unknown solver kind");
}

}  // namespace hom
