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
/// p-continuation of appendix C, threads, tolerances and progress output,
/// and certification as the final acceptance test (certified.hpp).
/// For other solver settings call `optimize_with` with policy objects.

#include <chrono>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "hom/measure/shape_measure.hpp"
#include "hom/mesh/mesh.hpp"
#include "hom/optimize/certified.hpp"
#include "hom/optimize/continuation.hpp"
#include "hom/optimize/gauss_seidel.hpp"
#include "hom/optimize/matrix_free_newton.hpp"
#include "hom/optimize/mesh_problem.hpp"
#include "hom/optimize/newton.hpp"
#include "hom/optimize/solve.hpp"
#include "hom/optimize/solver.hpp"
#include "hom/quadrature/quadrature_policy.hpp"
#include "hom/quality/ideal.hpp"

namespace hom {

struct OptimizeOptions {
  SolverKind solver = SolverKind::newton;
  IdealKind ideal = IdealKind::straight_sided;
  bool p_continuation = false;  ///< appendix C: untangle the linear sub-mesh first when it is tangled
  /// Continuation from degree 1 (VertexMeshContinuation): untangle the mesh of
  /// element vertices first when it is tangled, then place the free
  /// high-order nodes straight-sided on it (before the appendix C stage when
  /// p_continuation is also set). For large boundary motions (table 4.2).
  bool vertex_continuation = false;
  /// Solver of the linear sub-mesh stage. Non-linear Gauss-Seidel by default:
  /// its local moves untangle a randomly tangled linear sub-mesh in a few
  /// sweeps (bench_untangle, p = 5: valid after 4 sweeps), where the global
  /// Newton-type solvers take tens of short steps.
  SolverKind continuation_solver = SolverKind::gauss_seidel;
  /// Stop the linear stage once its sub-mesh has stayed valid this many
  /// iterations (SolverOptions::iterations_after_valid); < 0 (default): run it
  /// to convergence, as appendix C does. Converging pays off on small meshes
  /// (the degree-4 ring of figure C.2: 26 linear + 6 Newton iterations, against
  /// 12 + 33 when stopping 3 iterations after validity, bench_ring); on large
  /// ones a few sweeps after untangling can be enough for a valid high-order
  /// start (bench_untangle, p = 5: 3 Gauss-Seidel sweeps after validity gave a
  /// valid degree-5 mesh of minimum quality 0.88; stopping right at validity
  /// left 38 elements inverted).
  int continuation_iterations_after_valid = -1;
  /// Second-order model of the Newton-type solvers (HessianForm::projected or
  /// gauss_newton; exact only for derivative checks).
  HessianForm hessian = HessianForm::projected;
  int threads = 0;              ///< <= 0: OpenMP's default
  int max_iterations = 200;     ///< per stage (linear sub-mesh, high order)
  double gradient_tolerance = 1e-8;
  double objective_tolerance = 1e-6;
  double quality_tolerance = 1e-3;
  int stagnation_window = 3;
  /// Stop the high-order stage as soon as every element is valid with minimum
  /// quality >= target_quality (<= 0: off, optimize to convergence).
  double target_quality = 0.0;
  /// Stop the high-order stage once every element has been valid this many
  /// iterations (< 0: off), for callers whose goal is a valid mesh.
  int iterations_after_valid = -1;
  double regularization_alpha = thesis_regularization_alpha;  ///< alpha of eq 4.13
  /// Which elements are regularized while the mesh is invalid (problem.hpp).
  RegularizationScope regularization_scope = RegularizationScope::invalid_elements;
  Regularization regularization() const { return {regularization_alpha, regularization_scope}; }
  /// Certification as the final acceptance test (issue 8, certified.hpp):
  /// after the high-order stage, certify every element (Bernstein bounds of
  /// det D phi_P, subdivision depth <= certify_depth) and repair the
  /// uncertified ones in up to certify_rounds local rounds, with the failing
  /// points added to their quadrature as sentinels of relative weight
  /// certify_sentinel_weight. Off by default: the normal stage is unchanged
  /// either way; on a mesh that certifies valid the stage costs one certification.
  bool certify = false;
  int certify_depth = CertifyOptions{}.max_depth;
  int certify_rounds = CertifyRepairOptions{}.max_rounds;
  double certify_sentinel_weight = CertifyRepairOptions{}.sentinel_weight;
  bool verbose = false;
  std::function<void(const IterationInfo&)> on_iteration;

  CertifyRepairOptions certify_repair_options() const {
    CertifyRepairOptions o;
    o.certify.max_depth = certify_depth;
    o.certify.threads = threads;
    o.max_rounds = certify_rounds;
    o.sentinel_weight = certify_sentinel_weight;
    return o;
  }

  SolverOptions solver_options() const {
    SolverOptions o;
    o.max_iterations = max_iterations;
    o.gradient_tolerance = gradient_tolerance;
    o.objective_tolerance = objective_tolerance;
    o.quality_tolerance = quality_tolerance;
    o.stagnation_window = stagnation_window;
    o.target_quality = target_quality;
    o.iterations_after_valid = iterations_after_valid;
    o.verbose = verbose;
    o.on_iteration = on_iteration;
    return o;
  }
};

struct OptimizeResult {
  std::optional<SolverResult> continuation;  ///< the continuation stage(s), when they ran
  std::string continuation_policy;           ///< its policy's name ("none", "linear-sub-mesh", "vertex-mesh")
  /// The high-order optimization. With a certify stage that moved nodes,
  /// `inverted` and `min_quality` are those of the final mesh.
  SolverResult result;
  /// The certify stage (OptimizeOptions::certify), when it ran.
  std::optional<CertificationOutcome> certification;
  double time_s = 0.0;                       ///< all stages

  /// Every element certified valid (false when the certify stage did not run).
  bool certified() const { return certification && certification->certified(); }
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
  SolverOptions so = options.solver_options();
  so.stage = "high-order";
  OptimizeResult out;
  SolverOptions linear_options = so;
  linear_options.iterations_after_valid = options.continuation_iterations_after_valid;
  linear_options.target_quality = 0.0;  // the linear sub-mesh's quality is not the mesh's
  linear_options.stage = "linear";
  out.continuation_policy = std::string(Continuation::name);
  out.continuation =
      continuation.template run<Q>(mesh, ideal, linear_options, options.threads, measure, options.regularization());
  auto problem = make_problem<Measure, Q>(mesh, ideal, measure);
  problem.set_threads(options.threads);
  problem.set_regularization(options.regularization());
  // The stage's start: where it is certified valid, the repair pulls folded patches back towards it.
  std::optional<typename Mesh<Family, Nodes, SpaceDim>::Coordinates> stage_start;
  if (options.certify) stage_start = mesh.nodes();
  out.result = solver.solve(problem, so);
  mesh.nodes() = problem.coordinates();
  if (options.certify) {
    out.certification = certify_and_repair<Measure, Q>(mesh, ideal, solver, so, options.certify_repair_options(),
                                                       options.threads, options.regularization(), measure,
                                                       &*stage_start);
    if (out.certification->rounds > 0) {  // the repair moved nodes: report the final mesh's state
      problem.coordinates() = mesh.nodes();
      const MeshState state = problem.status(problem.coordinates());
      out.result.inverted = state.inverted;
      out.result.min_quality = state.min_quality;
    }
  }
  out.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

/// Optimizes `mesh` in place against a given ideal mesh.
template <class Measure = ShapeMeasure, QuadraturePolicy Q = DefaultExactness, ElementFamily Family, NodeSet Nodes, int SpaceDim>
OptimizeResult optimize(Mesh<Family, Nodes, SpaceDim>& mesh, const IdealMesh<Family>& ideal, const OptimizeOptions& options = {},
                        const Measure& measure = {}) {
  auto with_continuation = [&](const auto& solver) {
    if (options.vertex_continuation) {
      VertexMeshContinuation c;
      if (options.p_continuation)
        c.sub_mesh = LinearSubMeshContinuation{options.continuation_solver};
      else
        c.sub_mesh.reset();
      return optimize_with<Measure, Q>(mesh, ideal, solver, c, options, measure);
    }
    if (options.p_continuation)
      return optimize_with<Measure, Q>(mesh, ideal, solver, LinearSubMeshContinuation{options.continuation_solver}, options,
                                       measure);
    return optimize_with<Measure, Q>(mesh, ideal, solver, NoContinuation{}, options, measure);
  };
  switch (options.solver) {
    case SolverKind::newton: return with_continuation(NewtonSolver{.hessian = options.hessian});
    case SolverKind::matrix_free_newton: return with_continuation(MatrixFreeNewton{.hessian = options.hessian});
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
