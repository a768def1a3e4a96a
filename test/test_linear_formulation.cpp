// The linear formulation of eq 4.15 (include/hom/optimize/linear_formulation.hpp):
// exactness for affine boundary data, the optimality of its solution checked by
// finite differences of the directly evaluated objective, the objective's value
// for affine maps, and the Gauss-Seidel iteration against the direct solve.
#include <doctest/doctest.h>

#include <array>
#include <cmath>
#include <random>

#include <Eigen/Dense>

#include "hom/mesh/elevate.hpp"
#include "hom/mesh/structured.hpp"
#include "hom/optimize/linear_formulation.hpp"
#include "test_meshes.hpp"

using namespace hom;

namespace {

using testing::box_mesh;

// A random matrix near the identity (det > 0) and a random translation.
template <int D>
std::pair<Eigen::Matrix<double, D, D>, Eigen::Matrix<double, D, 1>> random_affine(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.4, 0.4);
  Eigen::Matrix<double, D, D> A = Eigen::Matrix<double, D, D>::Identity();
  Eigen::Matrix<double, D, 1> c;
  for (int i = 0; i < D; ++i) {
    c[i] = u(rng);
    for (int j = 0; j < D; ++j) A(i, j) += u(rng);
  }
  return {A, c};
}

template <class MeshT>
void perturb_free(MeshT& mesh, double amplitude, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-amplitude, amplitude);
  for (int i = 0; i < mesh.num_nodes(); ++i)
    if (mesh.node_class(i).kind == NodeKind::free)
      for (int a = 0; a < MeshT::dim; ++a) mesh.nodes()(a, i) += u(rng);
}

// Moves every held (non-free) node by a smooth non-affine displacement.
template <class MeshT>
void bend_boundary(MeshT& mesh) {
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    if (mesh.node_class(i).kind == NodeKind::free) continue;
    auto x = mesh.node(i);
    const double s = std::sin(2.0 * x[0] + 1.0) * std::cos(1.5 * x[1]);
    x[1] += 0.1 * s;
    x[0] += 0.05 * x[1] * x[1];
  }
}

constexpr int cells(int dim) { return dim == 2 ? 3 : 2; }

}  // namespace

TEST_CASE_TEMPLATE("an affine boundary map is reproduced exactly (straight-sided ideal)", F, Simplex<2>, Simplex<3>,
                   Cube<2>, Cube<3>) {
  constexpr int D = F::dim;
  for (int p = 1; p <= 4; ++p) {
    CAPTURE(p);
    auto mesh = box_mesh<F>(3, p);
    const auto ideal = mesh.straight_sided_ideal();
    const auto [A, c] = random_affine<D>(17u + unsigned(p));
    const auto reference = mesh.nodes();
    for (int i = 0; i < mesh.num_nodes(); ++i)
      if (mesh.node_class(i).kind != NodeKind::free) mesh.node(i) = A * reference.col(i) + c;
    perturb_free(mesh, 0.2, 5u + unsigned(p));  // the start must not matter
    int free = 0;
    for (int i = 0; i < mesh.num_nodes(); ++i) free += mesh.node_class(i).kind == NodeKind::free;
    REQUIRE(free > 0);

    const auto r = linear_formulation(mesh, ideal);
    CHECK(r.free_nodes == free);
    CHECK(r.objective <= r.initial_objective);
    double err = 0.0;
    for (int i = 0; i < mesh.num_nodes(); ++i)
      err = std::max(err, (mesh.node(i) - (A * reference.col(i) + c)).cwiseAbs().maxCoeff());
    CHECK(err < 1e-10);
    // f of an affine map x = A y + c over the unit box: ||A - Id||_F^2 * |box|.
    CHECK(r.objective == doctest::Approx((A - Eigen::Matrix<double, D, D>::Identity()).squaredNorm()).epsilon(1e-10));
  }
}

TEST_CASE_TEMPLATE("the solution is a stationary point of the directly evaluated objective", F, Simplex<2>, Simplex<3>,
                   Cube<2>, Cube<3>) {
  constexpr int D = F::dim;
  for (const IdealKind kind : {IdealKind::straight_sided, IdealKind::regular}) {
    for (int p : {1, 3}) {
      CAPTURE(p);
      CAPTURE(int(kind));
      auto mesh = box_mesh<F>(cells(D), p);
      const auto ideal = kind == IdealKind::regular ? IdealMesh<F>::regular(mesh.num_elements()) : mesh.straight_sided_ideal();
      bend_boundary(mesh);
      perturb_free(mesh, 0.05, 3u);
      linear_formulation(mesh, ideal);
      const double f0 = linear_formulation_objective(mesh, ideal);
      REQUIRE(f0 > 0.0);

      // Central differences are exact for a quadratic up to round-off
      // (~ eps f / h), so every free coordinate's derivative must vanish.
      const double h = 1e-3;
      double max_derivative = 0.0;
      int checked = 0;
      for (int i = 0; i < mesh.num_nodes(); ++i) {
        if (mesh.node_class(i).kind != NodeKind::free) continue;
        for (int a = 0; a < D; ++a) {
          const double x = mesh.nodes()(a, i);
          mesh.nodes()(a, i) = x + h;
          const double fp = linear_formulation_objective(mesh, ideal);
          mesh.nodes()(a, i) = x - h;
          const double fm = linear_formulation_objective(mesh, ideal);
          mesh.nodes()(a, i) = x;
          max_derivative = std::max(max_derivative, std::abs(fp - fm) / (2 * h));
          // And a minimum: a move of either sign raises f, by the curvature h^2 K_ii.
          CHECK(fp > f0);
          CHECK(fm > f0);
          ++checked;
        }
        if (checked > 60) break;
      }
      CHECK(max_derivative < 1e-9 * std::max(1.0, f0));

      // Control: away from the solution the same finite differences do not vanish.
      perturb_free(mesh, 0.05, 9u);
      double moved_derivative = 0.0;
      for (int i = 0; i < mesh.num_nodes() && moved_derivative == 0.0; ++i) {
        if (mesh.node_class(i).kind != NodeKind::free) continue;
        const double x = mesh.nodes()(0, i);
        mesh.nodes()(0, i) = x + h;
        const double fp = linear_formulation_objective(mesh, ideal);
        mesh.nodes()(0, i) = x - h;
        const double fm = linear_formulation_objective(mesh, ideal);
        mesh.nodes()(0, i) = x;
        moved_derivative = std::abs(fp - fm) / (2 * h);
      }
      CHECK(moved_derivative > 1e-6);
    }
  }
}

TEST_CASE_TEMPLATE("Gauss-Seidel sweeps converge to the direct minimizer; truncated, they depend on the start", F,
                   Simplex<2>, Cube<2>, Simplex<3>) {
  constexpr int D = F::dim;
  const int p = 2;
  auto base = box_mesh<F>(cells(D), p);
  bend_boundary(base);
  const auto ideal = base.straight_sided_ideal();

  auto direct = base;
  const auto rd = linear_formulation(direct, ideal);
  CHECK(rd.sweeps == 0);

  auto iterative = base;
  perturb_free(iterative, 0.05, 11u);
  LinearFormulationOptions gs;
  gs.solver = LinearSolveKind::gauss_seidel;
  gs.objective_tolerance = 0.0;  // sweep until f stops decreasing (round-off)
  gs.max_sweeps = 3000;
  const auto rg = linear_formulation(iterative, ideal, gs);
  CHECK(rg.converged);
  CHECK(rg.sweeps > 2);
  CHECK(rg.objective == doctest::Approx(rd.objective).epsilon(1e-12));
  // f is flat at its minimum: a round-off change of f leaves the nodes
  // undetermined at about sqrt(eps) relative.
  CHECK((iterative.nodes() - direct.nodes()).cwiseAbs().maxCoeff() < 1e-6);

  // Two sweeps from two starts: different meshes, both above the minimum.
  gs.max_sweeps = 2;
  auto a = base, b = base;
  perturb_free(b, 0.05, 12u);
  const auto ra = linear_formulation(a, ideal, gs);
  const auto rb = linear_formulation(b, ideal, gs);
  CHECK(ra.sweeps == 2);
  CHECK_FALSE(ra.converged);
  CHECK(ra.objective > rd.objective);
  CHECK(rb.objective > rd.objective);
  CHECK((a.nodes() - b.nodes()).cwiseAbs().maxCoeff() > 1e-6);
  // Every sweep lowers f (each node update is an exact local minimization).
  CHECK(ra.objective < ra.initial_objective);
}
