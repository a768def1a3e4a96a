#pragma once
/// @file gauss_seidel.hpp
/// Non-linear Gauss-Seidel for eq 4.11 (appendix B): one free node at a time,
///
///     x_i^{k+1} = x_i^k - alpha_i^k [grad^2_ii f^(x_i^k)]^{-1} grad_i f^(x_i^k),        (eq B.1)
///
/// where f^ is the local merit function of eq B.2, the contribution of the
/// elements that contain node i (the node's sub-mesh, remark B.1). By eqs
/// B.3-B.5 its gradient, Hessian and sufficient-decrease test are those of the
/// global f, at the cost of the node's elements only. hom's f^ keeps the 1/2
/// of eq 4.10, which changes neither the Newton step nor the Armijo test.
///
///   - The Dim x Dim nodal Hessian is the exact one; if it is not positive
///     definite, its eigenvalues are replaced by max(|lambda|, eigenvalue_floor *
///     max|lambda|) (a modified Newton step, always a descent direction).
///   - alpha_i^k by the backtracking line search of algorithm B.1 with
///     alpha = 1, rho = 0.5, c = 1e-4 on f^ (eq B.5); trials with f^ = +inf (a
///     valid element under sigma_0 would become invalid) are rejected, so the
///     consistency of section 4.2.2 holds node by node. A node whose line
///     search fails stays put.
///   - Incremental Jacobians: the Jacobians J_P,q = X G_q of every element at
///     its quadrature points are cached (Dim x Dim per point, recomputed from
///     the coordinates at the start of each sweep). Moving node i (local node l
///     of element e) by dx changes each of them by the rank-one term
///     dx G_q(l, :), so a trial and an accepted move cost O(nq Dim^2) per
///     element, not a product with all the element's nodes.
///   - Parallel sweeps: the free nodes are colored so that no element
///     contains two nodes of one color (OptimizationProblem::free_node_coloring);
///     colors are swept in order and the nodes of one color are updated
///     concurrently. Nodes of a color touch disjoint elements, so a sweep's
///     result is that of the sequential sweep in color order, whatever the
///     number of threads.
///   - Vertex culling (optional, `culling_tolerance` > 0), as mesh smoothers
///     skip vertices that have settled: after the first sweep, a sweep relaxes
///     only the free nodes that, in the previous sweep, moved by more than
///     culling_tolerance times their elements' ideal size, the nodes sharing an
///     element with such a node, and the nodes of invalid elements (delta > 0).
///     When that set is empty the next sweep visits every node again. While
///     the set is small, one outer iteration makes several passes over it
///     (max_culled_passes). The set is computed serially between passes, so
///     results still do not depend on the number of threads. The linear stage
///     of p-continuation uses it: at p = 10 its first sweep leaves 31 of 1.4
///     million sub-tetrahedra inverted, and full sweeps spend the rest of the
///     stage on them.
/// One outer iteration (solver.hpp) is one sweep over the free nodes.

#include <algorithm>
#include <cmath>
#include <string_view>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "hom/detail/parallel.hpp"
#include "hom/optimize/problem.hpp"
#include "hom/optimize/solver.hpp"

namespace hom {

struct GaussSeidel {
  static constexpr std::string_view name = "gauss-seidel";

  /// Algorithm B.1: alpha = 1, rho = 0.5, c = 1e-4.
  LineSearch line_search{1.0, 0.5, 1e-4, 30};
  double eigenvalue_floor = 1e-8;
  /// Relative move below which a node is culled from the next sweep (0: every
  /// sweep visits every free node, as in appendix B).
  double culling_tolerance = 0.0;
  /// With culling, while fewer than a tenth of the free nodes are active, one
  /// outer iteration makes up to this many passes over the active nodes (the
  /// outer iteration's evaluations over the whole mesh are paid once for them).
  int max_culled_passes = 1;

  template <ElementFamily Family, class Measure>
  SolverResult solve(OptimizationProblem<Family, Measure>& problem, const SolverOptions& options) const {
    Step<OptimizationProblem<Family, Measure>> step{*this, problem.free_node_coloring()};
    const detail::SerialEigenScope serial_eigen;
    return detail::run_outer_loop(problem, options, name, step);
  }

 private:
  template <class Problem>
  struct Step {
    static constexpr int D = Problem::dim;
    using Mat = Eigen::Matrix<double, D, D>;
    using Vec = Eigen::Matrix<double, D, 1>;
    Step(const GaussSeidel& solver, Coloring coloring) : s(solver), colors(std::move(coloring)) {}
    const GaussSeidel& s;
    Coloring colors;
    std::vector<Eigen::Matrix<double, D, Eigen::Dynamic>> jacobians;  // per element: J_P,q = X G_q, Dim x (Dim nq)
    std::vector<char> active;          // culling: nodes the next sweep relaxes (empty: all)
    std::vector<double> inverse_size;  // culling: 1 / ideal size around each node
    std::vector<double> moves;         // culling: |dx| * inverse_size of each node's last move

    double evaluate(Problem& problem, Eigen::VectorXd& g) { return problem.value_gradient(problem.coordinates(), g); }

    void refresh_jacobians(const Problem& problem) {
      const int ne = problem.num_elements();
      jacobians.resize(ne);
      const auto& tab = problem.tabulation();
      const auto& X = problem.coordinates();
      HOM_PARALLEL_FOR(detail::useful_threads(problem.threads(), ne, 64))
      for (int e = 0; e < ne; ++e) {
        Eigen::Matrix<double, D, Eigen::Dynamic> Xe;
        problem.element_coordinates(X, e, Xe);
        jacobians[e].noalias() = Xe * tab.shape_gradients;
      }
    }

    // f^ of eq B.2 for node `node` displaced by dx (dx = 0: current position).
    double local_value(const Problem& problem, int node, const Vec& dx) const {
      const auto& tab = problem.tabulation();
      double f = 0.0;
      for (const auto& inc : problem.incidences(node)) {
        const auto& id = problem.ideal(inc.element);
        const auto& JP = jacobians[inc.element];
        const double fe = problem.with_regularization(inc.element, [&](const auto& reg) {
          double sum = 0.0;
          for (int q = 0; q < tab.num_points(); ++q) {
            const Vec b = tab.shape_gradients.row(inc.local).template segment<D>(q * D).transpose();
            const Mat J = (JP.template middleCols<D>(q * D) + dx * b.transpose()) * id.inverse_jacobian(q);
            const double eta = problem.measure().value(J, reg);
            sum += 0.5 * id.weight(q) * (eta - 1.0) * (eta - 1.0);
          }
          return sum;
        });
        f += fe;
        if (!std::isfinite(f)) return f;
      }
      return f;
    }

    // f^, grad_i f^ and grad^2_ii f^ at the current position (eqs B.2-B.4):
    // with w = A_q^T G_q(l,:)^T, d J / dx_a = e_a w^T, so
    //   grad  = sum_q c_q r_q g_q w,
    //   H(a,b) = sum_q c_q [ (g_q w)_a (g_q w)_b + r_q sum_{k,m} h_q(a + D k, b + D m) w_k w_m ],
    // the last sum being the measure's Hessian along the rank-one directions
    // (value_gradient_directional_hessian: Dim x Dim, never the full Dim^2 x Dim^2).
    double local_derivatives(const Problem& problem, int node, Vec& grad, Mat& hess) const {
      const auto& tab = problem.tabulation();
      double f = 0.0;
      grad.setZero();
      hess.setZero();
      for (const auto& inc : problem.incidences(node)) {
        const auto& id = problem.ideal(inc.element);
        const auto& JP = jacobians[inc.element];
        problem.with_regularization(inc.element, [&](const auto& reg) {
          for (int q = 0; q < tab.num_points(); ++q) {
            const Mat& A = id.inverse_jacobian(q);
            const double c = id.weight(q);
            const Vec b = tab.shape_gradients.row(inc.local).template segment<D>(q * D).transpose();
            const Vec w = A.transpose() * b;
            const Mat J = JP.template middleCols<D>(q * D) * A;
            Mat g, hw;
            const double eta = value_gradient_directional_hessian(problem.measure(), J, reg, w, g, hw);
            const double r = eta - 1.0;
            const Vec u = g * w;
            f += 0.5 * c * r * r;
            grad += (c * r) * u;
            hess += c * (u * u.transpose() + r * hw);
          }
          return 0.0;
        });
      }
      return f;
    }

    // One node's modified Newton step with algorithm B.1; returns the number
    // of backtracks, or -1 if the node did not move.
    int relax_node(Problem& problem, int node) {
      Vec grad;
      Mat hess;
      const double f0 = local_derivatives(problem, node, grad, hess);
      if (!std::isfinite(f0) || !grad.allFinite() || !hess.allFinite() || grad.squaredNorm() == 0.0) return -1;
      const Eigen::SelfAdjointEigenSolver<Mat> es(hess);
      Vec lambda = es.eigenvalues().cwiseAbs();
      const double top = lambda.maxCoeff();
      if (!(top > 0.0)) return -1;
      lambda = lambda.cwiseMax(s.eigenvalue_floor * top);
      const Vec p = -(es.eigenvectors() * (es.eigenvectors().transpose() * grad).cwiseQuotient(lambda));
      const double slope = grad.dot(p);
      if (!(slope < 0.0)) return -1;
      const auto ls = s.line_search.search([&](double alpha) { return local_value(problem, node, Vec(alpha * p)); }, f0, slope);
      if (!ls.accepted) return -1;
      const Vec dx = ls.step * p;
      const auto& tab = problem.tabulation();
      for (const auto& inc : problem.incidences(node)) {
        auto& JP = jacobians[inc.element];
        for (int q = 0; q < tab.num_points(); ++q)
          JP.template middleCols<D>(q * D).noalias() +=
              dx * tab.shape_gradients.row(inc.local).template segment<D>(q * D);
      }
      problem.coordinates().col(node) += dx;
      if (!moves.empty()) moves[node] = dx.norm() * inverse_size[node];
      return ls.backtracks;
    }

    // 1 / (ideal size) around each node: the largest ||A_q||_F (A_q the ideal
    // element's inverse Jacobian at the first point) over its elements.
    void compute_inverse_sizes(const Problem& problem) {
      inverse_size.assign(problem.num_nodes(), 0.0);
      for (int node : problem.free_nodes())
        for (const auto& inc : problem.incidences(node))
          inverse_size[node] = std::max(inverse_size[node], problem.ideal(inc.element).inverse_jacobian(0).norm());
    }

    // The culling rule of the file comment, from the moves of the last pass;
    // returns the number of active free nodes.
    int update_active_set(const Problem& problem) {
      active.assign(problem.num_nodes(), 0);
      const auto& elements = problem.elements();
      auto activate_element = [&](int e) {
        for (Eigen::Index i = 0; i < elements.rows(); ++i) active[elements(i, e)] = 1;
      };
      bool any = false;
      for (int node : problem.free_nodes())
        if (moves[node] > s.culling_tolerance) {
          any = true;
          for (const auto& inc : problem.incidences(node)) activate_element(inc.element);
        }
      for (int e = 0; e < problem.num_elements(); ++e)
        if (problem.deltas()[e] > 0.0) {
          any = true;
          activate_element(e);
        }
      if (!any) {
        active.clear();
        return 0;
      }
      int count = 0;
      for (int node : problem.free_nodes()) count += active[node];
      return count;
    }

    detail::StepOutcome advance(Problem& problem, double f, const Eigen::VectorXd&) {
      detail::StepOutcome out;
      if (problem.num_free_nodes() == 0) return out;
      refresh_jacobians(problem);
      const bool culling = s.culling_tolerance > 0.0;
      if (culling && inverse_size.empty()) compute_inverse_sizes(problem);
      const bool culled = !active.empty();
      int moved = 0, backtracks = 0, active_count = 0;
      std::vector<int> result(problem.num_nodes());
      for (int pass = 0; pass == 0 || (culling && active_count > 0 && active_count * 10 < problem.num_free_nodes() &&
                                       pass < s.max_culled_passes);
           ++pass) {
        std::fill(result.begin(), result.end(), -1);
        if (culling) moves.assign(problem.num_nodes(), 0.0);
        for (const auto& group : colors.groups) {
          const int size = int(group.size());
          HOM_PARALLEL_FOR_DYNAMIC(detail::useful_threads(problem.threads(), size, 64))
          for (int k = 0; k < size; ++k)
            if (active.empty() || active[group[k]]) result[group[k]] = relax_node(problem, group[k]);
        }
        if (culling) active_count = update_active_set(problem);
        for (int node : problem.free_nodes())
          if (result[node] >= 0) {
            ++moved;
            backtracks += result[node];
          }
      }
      out.objective = problem.value(problem.coordinates());
      // A culled sweep that moved nothing is not a failure: the next sweep visits every node.
      if (culled && moved == 0) active.clear();
      out.success = (moved > 0 || culled) && std::isfinite(out.objective);
      out.step = double(moved) / problem.num_free_nodes();  // relaxations that moved; > 1 after several passes
      out.inner = backtracks;
      (void)f;
      return out;
    }
  };
};

static_assert(MeshSolverFor<GaussSeidel, OptimizationProblem<Simplex<2>>>);

}  // namespace hom
