#pragma once
/// @file linear_formulation.hpp
/// The linear (constant-Hessian) formulation the thesis compares its
/// non-linear method with in section 4.3.1 (table 4.2, figure 4.8(c)):
/// impose, element by element and in a least-squares sense, that the map from
/// the ideal element to the physical one is the identity,
///
///     f(x_1..x_nF; x_nF+1..x_nN) = || D phi_h - Id ||^2
///                                = sum_e  int_{E^I_e} || D phi_E(y) - Id ||_F^2 dy        (eq 4.15)
///
/// with D phi_E = D phi_P (D phi_I)^{-1} (eq 3.17, A.2) as in eq 4.10, the
/// same free / fixed split (NodeKind::free moves, every other node is held)
/// and the same integration over the ideal element (weight |det D phi_I|).
///
/// The element map is linear in the node coordinates X (Dim x n_p):
/// D phi_E(y_q) = X B_q with B_q = G_q (D phi_I)^{-1}, G_q the n_p x Dim shape
/// gradients at quadrature point q (quality/tabulation.hpp). So, with w_q the
/// rule's weight times |det D phi_I|,
///
///     f_e = sum_d ( x_d^T K_e x_d - 2 x_d^T r_{e,d} ) + Dim * |E^I_e|,
///     K_e = sum_q w_q B_q B_q^T   (n_p x n_p, the same for every coordinate d),
///     r_e = sum_q w_q B_q         (n_p x Dim),
///
/// a quadratic whose Hessian 2K = 2 sum_e K_e is constant and does not couple
/// the coordinates: one sparse SPD matrix K_FF (free rows and columns) and Dim
/// right-hand sides  r_F - K_FC x_C . K_e is a stiffness (Laplacian) matrix on
/// the ideal element, so for the straight-sided ideal the minimizer is the
/// discrete harmonic extension of the boundary positions and reproduces an
/// affine boundary map exactly (the free rows of r sum int grad N_i over the
/// patch of node i, which vanish for a conforming ideal mesh).
///
/// Two ways to minimize it (LinearFormulationOptions::solver):
///   - direct: one sparse Cholesky factorization of K_FF (CHOLMOD's
///     supernodal LLT when hom is built with HOM_HAVE_CHOLMOD, Eigen's
///     SimplicialLDLT otherwise) and Dim solves: the exact minimizer, which
///     does not depend on where the free nodes start;
///   - gauss_seidel: the nodal Gauss-Seidel iteration of appendix B (eq B.1)
///     applied to eq 4.15. For a quadratic, the local Newton step of node i is
///     its exact local minimizer (the backtracking of algorithm B.1 accepts
///     alpha = 1), so one sweep visits the free nodes in index order and sets
///     each to argmin of f in that node alone. Stopped when one sweep lowers f
///     by at most objective_tolerance * f (the relative-decrease test of the
///     non-linear solvers, optimize/solver.hpp) or after max_sweeps. Truncated
///     this way the result depends on the start, as the thesis's two "Linear"
///     rows of table 4.2 do (see bench/bench_smooth.cpp).
///
///     hom::LinearFormulationOptions o;                        // direct
///     auto r = hom::linear_formulation(mesh, mesh.straight_sided_ideal(), o);
///     double f = hom::linear_formulation_objective(mesh, mesh.straight_sided_ideal());

#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#if defined(HOM_HAVE_CHOLMOD)
#include <Eigen/CholmodSupport>
#endif

#include "hom/element/family.hpp"
#include "hom/mesh/mesh.hpp"
#include "hom/quadrature/quadrature_policy.hpp"
#include "hom/quality/ideal.hpp"
#include "hom/quality/tabulation.hpp"

namespace hom {

/// How the quadratic of eq 4.15 is minimized (see the file comment).
enum class LinearSolveKind {
  direct,        ///< sparse Cholesky: the exact minimizer
  gauss_seidel,  ///< nodal Gauss-Seidel sweeps (appendix B), truncated by a tolerance
};

struct LinearFormulationOptions {
  LinearSolveKind solver = LinearSolveKind::direct;
  int max_sweeps = 1000;              ///< gauss_seidel: sweep limit
  /// gauss_seidel: stop when a sweep lowers f by <= this * f (0: when f stops
  /// decreasing, i.e. at round-off)
  double objective_tolerance = 1e-6;
};

struct LinearFormulationResult {
  int free_nodes = 0;
  double initial_objective = 0.0;  ///< f (eq 4.15) at the start
  double objective = 0.0;          ///< f at the result
  int sweeps = 0;                  ///< Gauss-Seidel sweeps (0 for the direct solve)
  bool converged = true;           ///< gauss_seidel: the tolerance was reached within max_sweeps
  double time_s = 0.0;             ///< assembly and solve
};

/// f of eq 4.15 at the mesh's current coordinates, evaluated directly at the
/// quadrature points (independently of the assembled K and r).
template <QuadraturePolicy Q = DefaultExactness, ElementFamily Family, NodeSet Nodes>
double linear_formulation_objective(const Mesh<Family, Nodes, Family::dim>& mesh, const IdealMesh<Family>& ideal) {
  constexpr int D = Family::dim;
  using Mat = Eigen::Matrix<double, D, D>;
  if (ideal.size() != mesh.num_elements())
    throw std::invalid_argument("hom::linear_formulation_objective: the ideal mesh has " + std::to_string(ideal.size()) +
                                " elements, the mesh " + std::to_string(mesh.num_elements()));
  const auto& tab = tabulation<Family, Nodes>(mesh.degree(), quadrature_for<Family, Q>(mesh.degree()));
  double f = 0.0;
#pragma omp parallel for reduction(+ : f) schedule(static)
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const Eigen::Matrix<double, D, Eigen::Dynamic> JP = mesh.element_coordinates(e) * tab.shape_gradients;
    for (int q = 0; q < tab.num_points(); ++q) {
      const Mat Ji = ideal.vertices(e) * tab.vertex_gradients[q];
      const Mat JE = JP.template middleCols<D>(q * D) * Ji.inverse();
      f += tab.rule.weights[q] * std::abs(Ji.determinant()) * (JE - Mat::Identity()).squaredNorm();
    }
  }
  return f;
}

/// Minimizes eq 4.15 over the free nodes of `mesh` (moved in place; every
/// node not classified NodeKind::free is held) against `ideal`, integrated
/// with the rule of quadrature policy Q. Throws std::runtime_error if K_FF
/// is singular (a set of free nodes not connected to any held node).
template <QuadraturePolicy Q = DefaultExactness, ElementFamily Family, NodeSet Nodes>
LinearFormulationResult linear_formulation(Mesh<Family, Nodes, Family::dim>& mesh, const IdealMesh<Family>& ideal,
                                           const LinearFormulationOptions& options = {}) {
  constexpr int D = Family::dim;
  using Mat = Eigen::Matrix<double, D, D>;
  using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;
  const auto start = std::chrono::steady_clock::now();
  LinearFormulationResult result;
  result.initial_objective = linear_formulation_objective<Q>(mesh, ideal);

  // Free nodes get consecutive unknowns in node order (the Gauss-Seidel order).
  std::vector<int> unknown(mesh.num_nodes(), -1);
  int nf = 0;
  for (int i = 0; i < mesh.num_nodes(); ++i)
    if (mesh.node_class(i).kind == NodeKind::free) unknown[i] = nf++;
  result.free_nodes = nf;
  if (nf == 0) {
    result.objective = result.initial_objective;
    result.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
  }

  // Element matrices K_e = Bw Bw^T with Bw = [sqrt(w_q) B_q]_q (n x Dim nq, one
  // product per element) and r_e = sum_q w_q B_q, in parallel over elements.
  const auto& tab = tabulation<Family, Nodes>(mesh.degree(), quadrature_for<Family, Q>(mesh.degree()));
  const int n = mesh.nodes_per_element(), nq = tab.num_points(), ne = mesh.num_elements();
  std::vector<Eigen::MatrixXd> Ke(ne);
  std::vector<Eigen::MatrixXd> re(ne);
#pragma omp parallel for schedule(dynamic, 16)
  for (int e = 0; e < ne; ++e) {
    Eigen::MatrixXd Bw(n, D * nq);
    Eigen::MatrixXd r = Eigen::MatrixXd::Zero(n, D);
    for (int q = 0; q < nq; ++q) {
      const Mat Ji = ideal.vertices(e) * tab.vertex_gradients[q];
      const double w = tab.rule.weights[q] * std::abs(Ji.determinant());
      const Eigen::MatrixXd B = tab.shape_gradients.middleCols(q * D, D) * Ji.inverse();
      Bw.middleCols(q * D, D) = std::sqrt(w) * B;
      r += w * B;
    }
    Ke[e].noalias() = Bw * Bw.transpose();
    re[e] = std::move(r);
  }

  // Global K_FF (both triangles) and right-hand sides r_F - K_FC x_C.
  std::vector<Eigen::Triplet<double, int>> triplets;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(nf, D);
  for (int e = 0; e < ne; ++e) {
    for (int a = 0; a < n; ++a) {
      const int ia = unknown[mesh.elements()(a, e)];
      if (ia < 0) continue;
      rhs.row(ia) += re[e].row(a);
      for (int b = 0; b < n; ++b) {
        const int gb = mesh.elements()(b, e);
        const int ib = unknown[gb];
        if (ib >= 0)
          triplets.emplace_back(ia, ib, Ke[e](a, b));
        else
          rhs.row(ia) -= Ke[e](a, b) * mesh.node(gb).transpose();
      }
    }
    Ke[e] = Eigen::MatrixXd();  // release as we go
  }
  SparseMatrix K(nf, nf);
  K.setFromTriplets(triplets.begin(), triplets.end());
  triplets = {};

  Eigen::MatrixXd X(nf, D);
  for (int i = 0; i < mesh.num_nodes(); ++i)
    if (unknown[i] >= 0) X.row(unknown[i]) = mesh.node(i).transpose();
  // f(x) = sum_d (x_d^T K x_d - 2 x_d^T rhs_d) + c over the free unknowns; c from the start.
  auto reduced = [&](const Eigen::MatrixXd& Y) { return (Y.transpose() * (K * Y)).trace() - 2.0 * (Y.transpose() * rhs).trace(); };
  const double offset = result.initial_objective - reduced(X);

  if (options.solver == LinearSolveKind::direct) {
#if defined(HOM_HAVE_CHOLMOD)
    Eigen::CholmodSupernodalLLT<SparseMatrix, Eigen::Lower> solver;
#else
    Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower> solver;
#endif
    solver.compute(K);
    if (solver.info() != Eigen::Success)
      throw std::runtime_error("hom::linear_formulation: the stiffness of the free nodes is singular "
                               "(free nodes not connected to a held node?)");
    X = solver.solve(rhs);
    if (solver.info() != Eigen::Success) throw std::runtime_error("hom::linear_formulation: the sparse solve failed");
  } else {
    // K is symmetric and stored whole, so column i lists row i's entries.
    double f = result.initial_objective;
    result.converged = false;
    for (int sweep = 0; sweep < options.max_sweeps; ++sweep) {
      for (int i = 0; i < nf; ++i) {
        Eigen::Matrix<double, 1, D> s = rhs.row(i);
        double diagonal = 0.0;
        for (SparseMatrix::InnerIterator it(K, i); it; ++it) {
          if (it.row() == i)
            diagonal = it.value();
          else
            s -= it.value() * X.row(it.row());
        }
        if (!(diagonal > 0.0)) throw std::runtime_error("hom::linear_formulation: a free node has no stiffness");
        X.row(i) = s / diagonal;
      }
      ++result.sweeps;
      const double f_new = reduced(X) + offset;
      const bool small = f - f_new <= options.objective_tolerance * std::abs(f);
      f = f_new;
      if (small) {
        result.converged = true;
        break;
      }
    }
  }

  for (int i = 0; i < mesh.num_nodes(); ++i)
    if (unknown[i] >= 0) mesh.node(i) = X.row(unknown[i]).transpose();
  result.objective = linear_formulation_objective<Q>(mesh, ideal);
  result.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace hom
