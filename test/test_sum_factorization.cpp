// Sum-factorized Jacobians of tetrahedra (include/hom/quality/sum_factorization.hpp)
// against the dense products with the tabulated Lagrange gradients, and the
// optimization problem's value, gradient and Hessian-vector product with and
// without it.
#include <doctest/doctest.h>

#include <random>

#include <Eigen/Dense>

#include "hom/mesh/elevate.hpp"
#include "hom/mesh/structured.hpp"
#include "hom/nodes/equispaced.hpp"
#include "hom/nodes/warp_blend.hpp"
#include "hom/optimize/mesh_problem.hpp"
#include "hom/quadrature/quadrature_policy.hpp"
#include "hom/quality/sum_factorization.hpp"
#include "hom/quality/tabulation.hpp"

using namespace hom;

namespace {

template <NodeSet Nodes>
TetrahedronSumFactorization factorization(int p, const QuadratureRule<3>& rule) {
  const LagrangeBasis<Simplex<3>, Nodes> basis(p);
  const Eigen::MatrixXd vt_inverse = basis.vandermonde_matrix().transpose().partialPivLu().inverse();
  return TetrahedronSumFactorization(p, vt_inverse, gauss_points_per_direction(rule.exactness));
}

double relative_difference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).norm() / std::max(b.norm(), 1e-300);
}

template <NodeSet Nodes>
void check_against_dense(int p, int exactness) {
  const auto rule = gauss_rule<Simplex<3>>(exactness);
  const Tabulation<Simplex<3>> tab = make_tabulation<Simplex<3>, Nodes>(p, rule);
  const auto sf = factorization<Nodes>(p, rule);
  const Eigen::MatrixXd& G = tab.shape_gradients;
  std::mt19937 rng(17 + p);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int rows = 7;
  const Eigen::MatrixXd X = Eigen::MatrixXd::NullaryExpr(rows, G.rows(), [&] { return u(rng); });
  const Eigen::MatrixXd P = Eigen::MatrixXd::NullaryExpr(rows, G.cols(), [&] { return u(rng); });
  TetrahedronSumFactorization::Workspace w;
  Eigen::MatrixXd JP, out;
  sf.gradients(X, JP, w);
  sf.gradients_transpose(P, out, w);
  CHECK(JP.rows() == rows);
  CHECK(JP.cols() == G.cols());
  CHECK(out.cols() == G.rows());
  CHECK(relative_difference(JP, X * G) < 1e-12);
  CHECK(relative_difference(out, P * G.transpose()) < 1e-12);
}

}  // namespace

TEST_CASE("sum-factorized tetrahedron gradients equal the dense products (warp & blend nodes, default rule)") {
  for (int p = 1; p <= 10; ++p) {
    CAPTURE(p);
    check_against_dense<WarpBlend>(p, DefaultExactness::exactness<Simplex<3>>(p));
  }
}

TEST_CASE("sum-factorized tetrahedron gradients equal the dense products (equispaced nodes, thesis rule)") {
  for (int p : {1, 2, 4, 6}) {
    CAPTURE(p);
    check_against_dense<Equispaced>(p, ThesisExactness::exactness<Simplex<3>>(p));
  }
}

TEST_CASE("the affine map's gradient is its constant Jacobian at every point") {
  // phi(xi) = A xi + b: the gradients are A at every point, whatever p.
  const int p = 4;
  const auto rule = gauss_rule<Simplex<3>>(DefaultExactness::exactness<Simplex<3>>(p));
  const auto sf = factorization<WarpBlend>(p, rule);
  Eigen::Matrix3d A;
  A << 1.0, 0.2, -0.3, 0.1, 2.0, 0.4, -0.5, 0.3, 0.7;
  const Eigen::Vector3d b(0.3, -1.0, 2.0);
  const LagrangeBasis<Simplex<3>, WarpBlend> basis(p);
  Eigen::MatrixXd X(3, basis.size());
  for (int i = 0; i < basis.size(); ++i) X.col(i) = A * basis.nodes()[i] + b;
  TetrahedronSumFactorization::Workspace w;
  Eigen::MatrixXd JP;
  sf.gradients(X, JP, w);
  double worst = 0.0;
  for (int q = 0; q < int(rule.points.size()); ++q) worst = std::max(worst, (JP.middleCols(3 * q, 3) - A).cwiseAbs().maxCoeff());
  CHECK(worst < 1e-12);
}

TEST_CASE("the tabulation uses sum factorization only where it is cheaper and on hom's collapsed rules") {
  const auto& low = tabulation<Simplex<3>, WarpBlend>(1, quadrature_for<Simplex<3>, DefaultExactness>(1));
  const auto& high = tabulation<Simplex<3>, WarpBlend>(8, quadrature_for<Simplex<3>, DefaultExactness>(8));
  CHECK(low.sum_factorization == nullptr);
  REQUIRE(high.sum_factorization != nullptr);
  CHECK(high.sum_factorization->num_points() == high.num_points());
  // A rule that is not a collapsed Gauss-Jacobi product gets none.
  QuadratureRule<3> other = gauss_rule<Simplex<3>>(DefaultExactness::exactness<Simplex<3>>(8));
  std::swap(other.points[0], other.points[1]);
  const Eigen::MatrixXd vt = Eigen::MatrixXd::Identity(165, 165);
  CHECK(make_tetrahedron_sum_factorization(8, vt, other) == nullptr);
}

TEST_CASE("the optimization problem gives the same value, gradient and Hessian products with either kernel") {
  auto mesh = elevate(structured_mesh<Simplex<3>, WarpBlend>({2, 2, 2}), 6);
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.002);
  for (int i = 0; i < mesh.num_nodes(); ++i)
    if (mesh.node_class(i).kind == NodeKind::free)
      for (int c = 0; c < 3; ++c) mesh.nodes()(c, i) += noise(rng);
  auto problem = make_problem(mesh, make_ideal_mesh(mesh, IdealKind::straight_sided));
  REQUIRE(problem.use_sum_factorization());
  const auto X = problem.coordinates();
  Eigen::VectorXd g_sf, g_dense, h_sf, h_dense;
  const double f_sf = problem.value_gradient(X, g_sf);
  const Eigen::VectorXd v = Eigen::VectorXd::NullaryExpr(problem.num_dofs(), [&] { return noise(rng); });
  problem.hessian_vector_product(X, HessianForm::exact, v, h_sf);
  problem.set_sum_factorization(false);
  CHECK_FALSE(problem.use_sum_factorization());
  const double f_dense = problem.value_gradient(X, g_dense);
  problem.hessian_vector_product(X, HessianForm::exact, v, h_dense);
  CHECK(f_sf == doctest::Approx(f_dense).epsilon(1e-12));
  CHECK((g_sf - g_dense).norm() <= 1e-10 * g_dense.norm());
  CHECK((h_sf - h_dense).norm() <= 1e-10 * h_dense.norm());
  CHECK(g_dense.norm() > 0.0);
}

TEST_CASE("reference_jacobians of one element equal the dense product, with and without sum factorization") {
  for (int p : {3, 9}) {
    CAPTURE(p);
    const auto& tab = tabulation<Simplex<3>, WarpBlend>(p, quadrature_for<Simplex<3>, DefaultExactness>(p));
    std::mt19937 rng(p);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const Eigen::Matrix<double, 3, Eigen::Dynamic> X = Eigen::MatrixXd::NullaryExpr(3, tab.num_nodes(), [&] { return u(rng); });
    const Eigen::MatrixXd dense = X * tab.shape_gradients;
    CHECK(relative_difference(reference_jacobians(tab, X), dense) < 1e-12);
  }
}
