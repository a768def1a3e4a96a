#pragma once
/// @file optimize.hpp
/// Smoothing and untangling of a curved high-order mesh (chapter 4) in one
/// call: `optimize(mesh, options)` moves the free nodes of `mesh` in place to
/// minimize the regularized distortion objective of eq 4.10 against the
/// chosen ideal, with the fixed and boundary nodes held, and returns what
/// happened.
///
///     hom::OptimizeOptions opt;
///     opt.solver = hom::SolverKind::gauss_seidel;
///     opt.p_continuation = true;
///     auto r = hom::optimize(mesh, opt);              // ShapeMeasure, DefaultExactness
///     auto s = hom::optimize<hom::OddyMeasure, hom::ThesisExactness>(mesh, opt);
///
/// Compile-time choices: the distortion measure and the quadrature policy
/// (template arguments). Run-time choices (OptimizeOptions): the solver
/// (NewtonSolver, MatrixFreeNewton, GaussSeidel), the ideal (straight-sided
/// or regular, or a user IdealMesh through the second overload), the
/// p-continuation of appendix C, threads, tolerances and progress output.
/// For other solver settings call `optimize_with` with policy objects.

#include <chrono>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "hom/measure/shape_measure.hpp"
#include "hom/mesh/mesh.hpp"
#include "hom/optimize/continuation.hpp"
#include "hom/optimize/gauss_seidel.hpp"
#include "hom/optimize/matrix_free_newton.hpp"
#include "hom/optimize/mesh_problem.hpp"
#include "hom/optimize/newton.hpp"
#include "hom/optimize/solver.hpp"
#include "hom/quadrature/quadrature_policy.hpp"
#include "hom/quality/ideal.hpp"

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

struct OptimizeOptions {
  SolverKind solver = SolverKind::newton;
  IdealKind ideal = IdealKind::straight_sided;
  bool p_continuation = false;  ///< appendix C: untangle the linear sub-mesh first when it is tangled
  int threads = 0;              ///< <= 0: OpenMP's default
  int max_iterations = 200;     ///< per stage (linear sub-mesh, high order)
  double gradient_tolerance = 1e-8;
  double objective_tolerance = 1e-10;
  double quality_tolerance = 1e-6;
  int stagnation_window = 5;
  double regularization_alpha = thesis_regularization_alpha;  ///< alpha of eq 4.13
  bool verbose = false;
  std::function<void(const IterationInfo&)> on_iteration;

  SolverOptions solver_options() const {
    SolverOptions o;
    o.max_iterations = max_iterations;
    o.gradient_tolerance = gradient_tolerance;
    o.objective_tolerance = objective_tolerance;
    o.quality_tolerance = quality_tolerance;
    o.stagnation_window = stagnation_window;
    o.verbose = verbose;
    o.on_iteration = on_iteration;
    return o;
  }
};

struct OptimizeResult {
  std::optional<SolverResult> continuation;  ///< the linear sub-mesh stage, when it ran
  SolverResult result;                       ///< the high-order optimization
  double time_s = 0.0;                       ///< both stages

  bool converged() const { return result.converged; }
  int inverted() const { return result.inverted; }
  double min_quality() const { return result.min_quality; }
};

/// The general form: explicit solver and continuation policies.
template <class Measure = ShapeMeasure, QuadraturePolicy Q = DefaultExactness, class Solver, class Continuation,
          ElementFamily Family, NodeSet Nodes, int SpaceDim>
  requires MeshSolverFor<Solver, OptimizationProblem<Family, Measure>>
OptimizeResult optimize_with(Mesh<Family, Nodes, SpaceDim>& mesh, const IdealMesh<Family>& ideal, const Solver& solver,
                             const Continuation& continuation, const OptimizeOptions& options = {},
                             const Measure& measure = {}) {
  static_assert(SpaceDim == Family::dim, "hom::optimize: surface meshes are optimized in parametric space (chapter 5)");
  const auto start = std::chrono::steady_clock::now();
  const SolverOptions so = options.solver_options();
  OptimizeResult out;
  out.continuation = continuation.template run<Q>(mesh, ideal, solver, so, options.threads, measure, options.regularization_alpha);
  auto problem = make_problem<Measure, Q>(mesh, ideal, measure);
  problem.set_threads(options.threads);
  problem.set_regularization_alpha(options.regularization_alpha);
  out.result = solver.solve(problem, so);
  mesh.nodes() = problem.coordinates();
  out.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

/// Optimizes `mesh` in place against a given ideal mesh.
template <class Measure = ShapeMeasure, QuadraturePolicy Q = DefaultExactness, ElementFamily Family, NodeSet Nodes, int SpaceDim>
OptimizeResult optimize(Mesh<Family, Nodes, SpaceDim>& mesh, const IdealMesh<Family>& ideal, const OptimizeOptions& options = {},
                        const Measure& measure = {}) {
  auto with_continuation = [&](const auto& solver) {
    if (options.p_continuation)
      return optimize_with<Measure, Q>(mesh, ideal, solver, LinearSubMeshContinuation{}, options, measure);
    return optimize_with<Measure, Q>(mesh, ideal, solver, NoContinuation{}, options, measure);
  };
  switch (options.solver) {
    case SolverKind::newton: return with_continuation(NewtonSolver{});
    case SolverKind::matrix_free_newton: return with_continuation(MatrixFreeNewton{});
    case SolverKind::gauss_seidel: return with_continuation(GaussSeidel{});
  }
  throw std::invalid_argument("hom::optimize: unknown solver kind");
}

/// Optimizes `mesh` in place against the ideal of options.ideal.
template <class Measure = ShapeMeasure, QuadraturePolicy Q = DefaultExactness, ElementFamily Family, NodeSet Nodes, int SpaceDim>
OptimizeResult optimize(Mesh<Family, Nodes, SpaceDim>& mesh, const OptimizeOptions& options = {}, const Measure& measure = {}) {
  return optimize<Measure, Q>(mesh, make_ideal_mesh(mesh, options.ideal), options, measure);
}

}  // namespace hom
