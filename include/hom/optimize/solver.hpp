#pragma once
/// @file solver.hpp
/// What every optimizer of eq 4.11 shares: options, stopping criteria,
/// progress reporting, the result, and the outer iteration that ties them to
/// the element-wise regularization of section 4.2.2.
///
/// Concept MeshSolverFor<S, Problem>. A solver S (a policy: NewtonSolver,
/// MatrixFreeNewton, GaussSeidel) provides `S::name` and
///     SolverResult s.solve(OptimizationProblem<F, M>& problem, const SolverOptions&) const;
/// which moves problem.coordinates() in place. All three are built on
/// `detail::run_outer_loop` below and so share the stopping rules.
///
/// One outer iteration k (every solver):
///   1. state = validity and quality of every element; the regularization is
///      reset from it: delta_e > 0 exactly for the invalid elements
///      (OptimizationProblem::update_regularization);
///   2. f_k and grad f_k are evaluated with these deltas;
///   3. convergence test on the gradient (below);
///   4. the solver's step (a Newton step with line search, or a Gauss-Seidel
///      sweep), accepted only through line searches that reject +inf, so the
///      valid elements stay valid;
///   5. f_k+ (same deltas), the new state, progress output and the remaining tests.
///
/// Stopping criteria, in the order they are tested. The convergence criteria
/// 1-3 are only tested when every element is valid (while elements are
/// invalid the objective is regularized and changes definition between
/// iterations, so only 4-5 apply):
///   1. gradient: max_k ||grad_k f|| / s_k <= gradient_tolerance, the gradient
///      at every free node k relative to its scale s_k (the value grad_k f would
///      have if every eta - 1 and every d eta / dJ were 1, see
///      OptimizationProblem::gradient_scale): a dimensionless residual,
///      independent of the mesh's size and of the starting configuration;
///   2. objective: f_k - f_k+ <= objective_tolerance * f_k (relative change over
///      one iteration, both values with delta = 0);
///   3. quality stagnation: every element valid during the last
///      `stagnation_window` iterations and the minimum element quality grew
///      over them by at most `quality_tolerance` relative to its value
///      (q_best - q_first <= tol * q_best): relative, so that a mesh whose
///      worst element is still poor (q = 0.01 growing by 1e-4 per iteration)
///      is not taken for converged;
///   4. valid long enough (off unless iterations_after_valid >= 0): every element
///      valid for the last iterations_after_valid iterations; the early exit of
///      a p-continuation stage, whose job is a valid start for the next stage;
///   5. target reached (off unless target_quality > 0): every element valid and
///      the minimum quality >= target_quality, for users who need a good
///      enough mesh rather than the optimum;
///   6. the iteration limit (not converged);
///   7. the step failed: the line search found no acceptable step (not converged).
/// `converged` is true for 1-5 (the mesh is then valid).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <concepts>
#include <cstdio>
#include <deque>
#include <functional>
#include <iostream>
#include <limits>
#include <string>
#include <string_view>

#include <Eigen/Core>

#include "hom/optimize/problem.hpp"

namespace hom {

/// Why a solver stopped.
enum class StopReason {
  gradient,            ///< relative gradient norm below tolerance
  objective_change,    ///< relative objective decrease below tolerance
  quality_stagnation,  ///< all valid and the minimum quality stopped improving
  valid,               ///< all valid for SolverOptions::iterations_after_valid iterations
  target_quality,      ///< all valid and min quality >= SolverOptions::target_quality
  max_iterations,      ///< iteration limit reached
  line_search_failed,  ///< no acceptable step (no decrease, or every trial invalid)
};

inline std::string_view to_string(StopReason r) {
  switch (r) {
    case StopReason::gradient: return "gradient";
    case StopReason::objective_change: return "objective change";
    case StopReason::quality_stagnation: return "quality stagnation";
    case StopReason::valid: return "valid";
    case StopReason::target_quality: return "target quality";
    case StopReason::max_iterations: return "max iterations";
    case StopReason::line_search_failed: return "line search failed";
  }
  return "unknown";
}

/// Progress of one outer iteration, after its step.
struct IterationInfo {
  std::string_view solver;
  std::string_view stage;      ///< SolverOptions::stage (p-continuation: "linear" or "high-order")
  int iteration = 0;           ///< 1-based
  double objective = 0.0;      ///< f after the step (deltas of this iteration)
  double gradient_norm = 0.0;  ///< scaled gradient (criterion 1) before the step
  int inverted = 0;            ///< invalid elements after the step
  double min_quality = 0.0;    ///< min element quality after the step
  double step = 0.0;           ///< accepted step length (Gauss-Seidel: fraction of free nodes moved)
  int inner = 0;               ///< solver-specific: CG iterations, backtracks, shift increases
  double time_s = 0.0;         ///< since the solve started
};

/// Prints one line per iteration (the default progress output when verbose).
inline void print_iteration(const IterationInfo& it, std::ostream& out = std::clog) {
  char line[256];
  std::snprintf(line, sizeof line, "%-18.*s it %4d  f %12.6e  grad %10.3e  inv %6d  qmin %.4f  step %9.2e  inner %4d  %8.2f s\n",
                int(it.solver.size()), it.solver.data(), it.iteration, it.objective, it.gradient_norm, it.inverted,
                it.min_quality, it.step, it.inner, it.time_s);
  out << line << std::flush;
}

struct SolverOptions {
  int max_iterations = 200;
  double gradient_tolerance = 1e-8;   ///< criterion 1
  double objective_tolerance = 1e-6; ///< criterion 2
  double quality_tolerance = 1e-3;    ///< criterion 3 (relative)
  int stagnation_window = 3;          ///< criterion 3
  int iterations_after_valid = -1;    ///< criterion 4 (< 0: off)
  double target_quality = 0.0;        ///< criterion 5 (<= 0: off)
  std::string_view stage;             ///< label copied into IterationInfo (which stage of a pipeline)
  bool verbose = false;               ///< print_iteration to std::clog
  std::function<void(const IterationInfo&)> on_iteration;  ///< called after every iteration
};

struct SolverResult {
  std::string solver;
  int iterations = 0;
  double initial_objective = 0.0;  ///< f at the start (initial deltas)
  double objective = 0.0;          ///< f at the end (deltas of the final state: 0 when all valid)
  int initial_inverted = 0;
  int inverted = 0;
  double initial_min_quality = 0.0;
  double min_quality = 0.0;
  double gradient_norm = 0.0;  ///< scaled gradient (criterion 1) at the last evaluation
  double time_s = 0.0;
  bool converged = false;
  StopReason reason = StopReason::max_iterations;
};

template <class S, class Problem>
concept MeshSolverFor = requires(const S& s, Problem& problem, const SolverOptions& options) {
  { S::name } -> std::convertible_to<std::string_view>;
  { s.solve(problem, options) } -> std::same_as<SolverResult>;
};

/// Backtracking line search (Nocedal & Wright; algorithm B.1): the first
/// alpha in initial_step * contraction^k, k = 0..max_backtracks, with
///     phi(alpha) <= phi(0) + sufficient_decrease * alpha * slope   (Armijo),
/// phi(alpha) finite. +inf (an element with sigma_0 became invalid) and NaN
/// are rejected like any insufficient decrease.
struct LineSearch {
  double initial_step = 1.0;
  double contraction = 0.5;
  double sufficient_decrease = 1e-4;
  int max_backtracks = 40;

  struct Outcome {
    bool accepted = false;
    double step = 0.0;
    double value = 0.0;  ///< phi(step)
    int backtracks = 0;
  };

  /// phi(alpha): the objective along the search direction; slope = phi'(0) < 0.
  template <class Phi>
  Outcome search(Phi&& phi, double phi0, double slope) const {
    Outcome o;
    double alpha = initial_step;
    for (int k = 0; k <= max_backtracks; ++k, alpha *= contraction) {
      const double v = phi(alpha);
      o.backtracks = k;
      if (std::isfinite(v) && v <= phi0 + sufficient_decrease * alpha * slope) {
        o.accepted = true;
        o.step = alpha;
        o.value = v;
        return o;
      }
    }
    return o;
  }
};

namespace detail {

/// Criterion 3: over the window (oldest first), the best minimum quality is
/// at most `tolerance` (relative) above the oldest.
inline bool quality_stagnated(const std::deque<double>& window, double tolerance) {
  const double best = *std::max_element(window.begin(), window.end());
  return best - window.front() <= tolerance * best;
}

/// What a solver's step reports to the outer loop.
struct StepOutcome {
  bool success = false;
  double objective = 0.0;  ///< f after the step (same deltas)
  double step = 0.0;
  int inner = 0;
};

/// The outer iteration shared by all solvers (see the file comment).
/// `step` provides
///   double evaluate(Problem&, Eigen::VectorXd& g)        f and grad f at the current coordinates
///   StepOutcome advance(Problem&, double f, const Eigen::VectorXd& g)   one step, moves the coordinates
template <class Problem, class Step>
SolverResult run_outer_loop(Problem& problem, const SolverOptions& opt, std::string_view name, Step& step) {
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  const auto seconds = [&] { return std::chrono::duration<double>(clock::now() - start).count(); };

  SolverResult res;
  res.solver = std::string(name);
  MeshState state = problem.status(problem.coordinates());
  res.initial_inverted = state.inverted;
  res.initial_min_quality = state.min_quality;
  std::deque<double> recent_quality;  // min quality over the trailing all-valid iterations
  int valid_iterations = 0;           // trailing iterations ending with every element valid
  Eigen::VectorXd g;
  bool stopped = false;
  for (int k = 0; !stopped; ++k) {
    problem.update_regularization(state);
    const double f = step.evaluate(problem, g);
    const double gnorm = problem.scaled_gradient_norm(g);
    res.gradient_norm = gnorm;
    if (k == 0) res.initial_objective = f;
    if (state.all_valid()) {
      if (gnorm <= opt.gradient_tolerance) {
        res.reason = StopReason::gradient;
        res.converged = true;
        break;
      }
    }
    if (k >= opt.max_iterations) {
      res.reason = StopReason::max_iterations;
      break;
    }
    const bool valid_before = state.all_valid();
    const StepOutcome out = step.advance(problem, f, g);
    if (!out.success) {
      res.reason = StopReason::line_search_failed;
      break;
    }
    res.iterations = k + 1;
    state = problem.status(problem.coordinates());

    IterationInfo info;
    info.solver = name;
    info.stage = opt.stage;
    info.iteration = k + 1;
    info.objective = out.objective;
    info.gradient_norm = gnorm;
    info.inverted = state.inverted;
    info.min_quality = state.min_quality;
    info.step = out.step;
    info.inner = out.inner;
    info.time_s = seconds();
    if (opt.verbose) print_iteration(info);
    if (opt.on_iteration) opt.on_iteration(info);

    if (valid_before && state.all_valid() && f - out.objective <= opt.objective_tolerance * f) {
      res.reason = StopReason::objective_change;
      res.converged = true;
      stopped = true;
    }
    if (state.all_valid()) {
      ++valid_iterations;
      if (!stopped && opt.iterations_after_valid >= 0 && valid_iterations > opt.iterations_after_valid) {
        res.reason = StopReason::valid;
        res.converged = true;
        stopped = true;
      }
      if (!stopped && opt.target_quality > 0.0 && state.min_quality >= opt.target_quality) {
        res.reason = StopReason::target_quality;
        res.converged = true;
        stopped = true;
      }
      recent_quality.push_back(state.min_quality);
      if (int(recent_quality.size()) > opt.stagnation_window + 1) recent_quality.pop_front();
      if (!stopped && opt.stagnation_window > 0 && int(recent_quality.size()) == opt.stagnation_window + 1 &&
          quality_stagnated(recent_quality, opt.quality_tolerance)) {
        res.reason = StopReason::quality_stagnation;
        res.converged = true;
        stopped = true;
      }
    } else {
      recent_quality.clear();
      valid_iterations = 0;
    }
  }
  problem.update_regularization(state);
  res.objective = problem.value(problem.coordinates());
  res.inverted = state.inverted;
  res.min_quality = state.min_quality;
  res.time_s = seconds();
  return res;
}

}  // namespace detail

}  // namespace hom
