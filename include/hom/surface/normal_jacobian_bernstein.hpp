#pragma once
/// @file normal_jacobian_bernstein.hpp
/// The surface element's oriented area density as one polynomial in
/// Bernstein form, for certifying a surface element (certified_surface.hpp):
///
///   g(xi) = (x_xi x x_eta) . n(xi),   n(xi) = sum_i N_i(xi) nu_i,
///
/// x(xi) = sum_i N_i(xi) x_i the element's degree-p map into R^3 and nu_i the
/// unit surface normals at its nodes (unit_normal.hpp). The sign of g is the
/// sign the surface optimizer tests at its quadrature points (gamma of eq 5.5
/// against the normals n_q = n(xi_q) / |n(xi_q)|, surface_problem.hpp), so a
/// certificate of g > 0 on the whole element extends that test to every
/// point, and a point where g <= 0 is one the optimizer can be shown.
///
/// Degrees: the derivatives of x have degree p - 1 (triangle; on a
/// quadrilateral p - 1 along their own axis, p along the other), their cross
/// product 2 (p - 1) (quadrilateral 2 p - 1 per axis), and g, times n of
/// degree p, 3 p - 2 (quadrilateral 3 p - 1 per axis). The construction is
/// exact up to round-off, as jacobian_bernstein.hpp's: nodal values to
/// Bernstein form, exact derivatives, exact products.

#include <Eigen/Core>
#include <array>

#include "hom/basis/bernstein.hpp"
#include "hom/element/family.hpp"
#include "hom/nodes/node_set.hpp"

namespace hom {

/// A polynomial on Family's reference element in Bernstein form.
template <ElementFamily Family>
struct BernsteinPolynomial {
  const BernsteinSpace<Family>* space = nullptr;
  Eigen::VectorXd coefficients;
};

/// Degree of g for degree-p elements of Family.
template <ElementFamily Family>
BernsteinDegree<Family> normal_jacobian_degree(int p) {
  static_assert(Family::dim == 2, "hom::normal_jacobian_degree: surface elements are triangles and quadrilaterals");
  return detail::uniform_degree<Family>(Family::is_simplex ? 3 * p - 2 : 3 * p - 1);
}

/// g of the file comment for the degree-p element with nodes X (3 x n) and
/// unit nodal normals nu (3 x n), both in the element's layout order.
template <ElementFamily Family, NodeSet Nodes>
BernsteinPolynomial<Family> normal_jacobian_bernstein(int p, const Eigen::Ref<const Eigen::Matrix3Xd>& X,
                                                      const Eigen::Ref<const Eigen::Matrix3Xd>& nu) {
  static_assert(Family::dim == 2, "hom::normal_jacobian_bernstein: surface elements are triangles and quadrilaterals");
  const LagrangeToBernstein<Family>& to_bernstein = lagrange_to_bernstein<Family, Nodes>(p);
  const BernsteinSpace<Family>& sp = to_bernstein.space();
  const Eigen::Matrix3Xd Xc = X.colwise() - X.col(0);  // g is translation invariant: keep the digits
  const Eigen::MatrixXd P = to_bernstein.apply(Xc), Nu = to_bernstein.apply(nu);
  const BernsteinSpace<Family>& s_xi = bernstein_space<Family>(derivative_degree<Family>(sp.degree(), 0));
  const BernsteinSpace<Family>& s_eta = bernstein_space<Family>(derivative_degree<Family>(sp.degree(), 1));
  std::array<Eigen::VectorXd, 3> x_xi, x_eta;
  for (int i = 0; i < 3; ++i) {
    x_xi[i] = bernstein_derivative(sp, P.row(i).transpose(), 0);
    x_eta[i] = bernstein_derivative(sp, P.row(i).transpose(), 1);
  }
  const BernsteinSpace<Family>& s_cross =
      bernstein_space<Family>(product_degree<Family>(s_xi.degree(), s_eta.degree()));
  BernsteinPolynomial<Family> g{&bernstein_space<Family>(normal_jacobian_degree<Family>(p)), {}};
  g.coefficients = Eigen::VectorXd::Zero(g.space->size());
  for (int k = 0; k < 3; ++k) {
    const int a = (k + 1) % 3, b = (k + 2) % 3;
    const Eigen::VectorXd cross =
        bernstein_product(s_xi, x_xi[a], s_eta, x_eta[b]) - bernstein_product(s_xi, x_xi[b], s_eta, x_eta[a]);
    g.coefficients += bernstein_product(s_cross, cross, sp, Nu.row(k).transpose());
  }
  return g;
}

}  // namespace hom
