#pragma once
/// @file surface_element_quality.hpp
/// Distortion and quality of one high-order element on a surface
/// (section 5.4), triangles and quadrilaterals of any degree:
///
///   point-wise:  M phi_E(y) = eta(J-bar(D phi_I, D phi_P))                  (eq 5.6)
///   element:     eta_E = || M phi_E ||_{E^I} / || 1 ||_{E^I}                 (def. 5.1, eq 5.25)
///   quality:     q_E = 1 / eta_E                                             (def. 5.2, eq 5.26)
///
/// The element's map is phi_E = phi_P o phi_I^{-1} (section 5.2.2) with
///   - phi_P(xi) = sum_i x_i N_i(xi), x_i the 3D node coordinates (for nodes on
///     a parameterized surface x_i = phi(u_i), eq 5.9: the physical element
///     interpolates the nodes' images, so it, and every quantity here, depends
///     on the nodes' positions only, never on the parameterization:
///     proposition 5.1, remark 5.3); B = D phi_P = X G_q (3 x 2);
///   - phi_I the straight-sided ideal (affine on triangles, bilinear on
///     quadrilaterals) through its vertices in R^3: the element's own
///     straight-sided counterpart, or a regular element (equilateral triangle,
///     unit square) embedded in z = 0 (embed_ideal); A = D phi_I (3 x 2).
/// The norms integrate over the ideal with the change of variables to the
/// reference element, weight |det(A~^T A)| = |a1 x a2|, the ideal's area
/// element, as in the planar case (element_quality.hpp).
///
/// Orientation (the gamma of section 5.2.1). The physical tangents are
/// oriented by a reference normal per quadrature point (SurfaceNormals): the
/// surface's S_u x S_v at the point (surface_normals, from the nodes'
/// parameters), or, without geometry, the normal of the element's
/// straight-sided facet (facet_normals). The ideal is oriented by its own
/// facet normal (it is valid by construction). Validation uses sigma_0 (eq 3.8)
/// as in the planar case: q_E = 0 exactly when det J-bar <= 0 at some
/// quadrature point, i.e. the element folds over, or is inverted with respect
/// to, the surface orientation there (section 5.4, remark 5.4).
///
/// Derivatives (for the optimizer of section 5.3.3): the gradient of eta_E
/// with respect to the node coordinates X, and its pull back to the nodes'
/// parameters (u_i, v_i) (parameter_gradient), d/du_i = D phi(u_i)^T d/dx_i (the
/// chain rule of eqs 5.20-5.23; the reference normals only choose gamma, which
/// is locally constant).

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Dense>

#include "hom/element/family.hpp"
#include "hom/geometry/surface_geometry.hpp"
#include "hom/measure/regularization.hpp"
#include "hom/quality/element_quality.hpp"
#include "hom/quality/ideal.hpp"
#include "hom/quality/tabulation.hpp"
#include "hom/surface/surface_distortion.hpp"
#include "hom/surface/surface_jacobian.hpp"
#include "hom/surface/unit_normal.hpp"

namespace hom {

/// Vertices of a straight-sided ideal surface element in R^3 (3 x num_vertices).
template <ElementFamily Family>
using SurfaceIdealVertices = Eigen::Matrix<double, 3, Family::num_vertices>;

/// A planar ideal (e.g. regular_ideal_vertices) placed in the plane z = 0.
template <ElementFamily Family>
SurfaceIdealVertices<Family> embed_ideal(const IdealVertices<Family>& v) {
  static_assert(Family::dim == 2, "hom::embed_ideal: surface elements are triangles and quadrilaterals");
  SurfaceIdealVertices<Family> e = SurfaceIdealVertices<Family>::Zero();
  e.template topRows<2>() = v;
  return e;
}

/// Unit normal of the straight-sided facet through the first num_vertices
/// columns of V, oriented by the vertex order: (v1 - v0) x (v2 - v0) for a
/// triangle, the cross product of the diagonals (v2 - v0) x (v3 - v1) for a
/// quadrilateral (its mean normal). Zero for a degenerate facet.
template <ElementFamily Family>
Eigen::Vector3d facet_normal(const Eigen::Ref<const Eigen::Matrix<double, 3, Eigen::Dynamic>>& V) {
  static_assert(Family::dim == 2, "hom::facet_normal: surface elements are triangles and quadrilaterals");
  Eigen::Vector3d n;
  if constexpr (Family::is_simplex)
    n = (V.col(1) - V.col(0)).cross(V.col(2) - V.col(0));
  else
    n = (V.col(2) - V.col(0)).cross(V.col(3) - V.col(1));
  const double l = n.norm();
  return l > 0.0 ? Eigen::Vector3d(n / l) : Eigen::Vector3d::Zero();
}

/// Reference normals orienting the physical tangents (gamma of section 5.2.1),
/// at the quadrature points and at the nodes; a matrix with one column is
/// the same normal everywhere.
struct SurfaceNormals {
  Eigen::Matrix3Xd points;
  Eigen::Matrix3Xd nodes;

  Eigen::Vector3d at_point(int q) const { return points.cols() == 1 ? points.col(0) : points.col(q); }
  Eigen::Vector3d at_node(int i) const { return nodes.cols() == 1 ? nodes.col(0) : nodes.col(i); }

  static SurfaceNormals constant(const Eigen::Vector3d& n) { return {n, n}; }
};

/// Without geometry: the normal of the straight-sided facet through the
/// element's vertices (the first num_vertices columns of X, or the ideal's).
template <ElementFamily Family>
SurfaceNormals facet_normals(const Eigen::Ref<const Eigen::Matrix<double, 3, Eigen::Dynamic>>& vertices) {
  return SurfaceNormals::constant(facet_normal<Family>(vertices));
}

/// With geometry: S_u x S_v (normalized) at u(xi) = sum_i u_i N_i(xi) for each
/// quadrature point, and at u_i for node i (unit_normal.hpp: zero at a
/// degenerate point, or at a node its limit from inside). UV (2 x n) are the nodes'
/// parameters, unwrapped across periodic seams (ParameterRange::unwrap) so
/// that interpolating them stays inside the element.
template <ElementFamily Family, SurfaceGeometry G>
SurfaceNormals surface_normals(const Tabulation<Family>& tab, const G& g,
                               const Eigen::Ref<const Eigen::Matrix<double, 2, Eigen::Dynamic>>& UV) {
  SurfaceNormals r;
  const int nq = tab.num_points();
  r.points.resize(3, nq);
  r.nodes = nodal_unit_normals(g, UV);
  const std::vector<bool> regular = nodes_with_normal(r.nodes);
  // A pole's free parameter follows the element (parameters_at_poles), or the
  // quadrature points near it would take the normal of the surface's far side.
  const Eigen::Matrix<double, 2, Eigen::Dynamic> uq =
      parameters_at_poles(g, UV, regular) * tab.shape_values.transpose();
  for (int q = 0; q < nq; ++q) r.points.col(q) = unit_normal(g, Eigen::Vector2d(uq.col(q)));
  fill_degenerate_normals(g, UV, regular, r.nodes);
  return r;
}

/// X = phi(UV): node coordinates (3 x n) of the nodes with parameters UV.
template <SurfaceGeometry G>
ElementNodes<3> surface_points(const G& g, const Eigen::Ref<const Eigen::Matrix<double, 2, Eigen::Dynamic>>& UV) {
  ElementNodes<3> X(3, UV.cols());
  for (Eigen::Index i = 0; i < UV.cols(); ++i) X.col(i) = g.evaluate(UV.col(i));
  return X;
}

/// The ideal's side of eq 5.5 at the quadrature points, computed once per
/// element: K_q = (A~_q^T A_q)^{-1}, the weight c_q = w_q |det(A~_q^T A_q)| and
/// the signed det(A~_q^T A_q), oriented by the ideal's facet normal.
struct SurfaceIdealAtPoints {
  std::vector<Eigen::Matrix2d> inverse;
  std::vector<double> weight;
  std::vector<double> det;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
};

template <ElementFamily Family>
SurfaceIdealAtPoints surface_ideal_at_points(const Tabulation<Family>& tab, const SurfaceIdealVertices<Family>& ideal) {
  SurfaceIdealAtPoints r;
  r.normal = facet_normal<Family>(ideal);
  const int nq = tab.num_points();
  r.inverse.resize(nq);
  r.weight.resize(nq);
  r.det.resize(nq);
  for (int q = 0; q < nq; ++q) {
    const Eigen::Matrix2d Ab = tangent_plane_coordinates(ideal * tab.vertex_gradients[q], r.normal);
    r.det[q] = Ab.determinant();
    r.inverse[q] = Ab.inverse();
    r.weight[q] = tab.rule.weights[q] * std::abs(r.det[q]);
  }
  return r;
}

/// Definitions 5.1-5.2 for one element with node coordinates X (3 x n, hom's
/// layout order). `pointwise`, when given, receives 1/eta at each quadrature
/// point. min_det / max_det / volume of the result refer to the signed area
/// element det(B~^T B) = gamma |b1 x b2| (the surface analogue of det D phi_P).
template <ElementFamily Family, class Measure>
ElementQuality surface_element_quality(const Tabulation<Family>& tab, const Eigen::Ref<const ElementNodes<3>>& X,
                                       const SurfaceIdealVertices<Family>& ideal, const SurfaceNormals& normals,
                                       const Measure& measure, std::vector<double>* pointwise = nullptr) {
  static_assert(Family::dim == 2, "hom::surface_element_quality: surface elements are triangles and quadrilaterals");
  const int nq = tab.num_points();
  const SurfaceIdealAtPoints id = surface_ideal_at_points<Family>(tab, ideal);
  const Eigen::Matrix<double, 3, Eigen::Dynamic> JP = X * tab.shape_gradients;
  const ClampedDeterminant validation;

  ElementQuality r;
  r.min_det = std::numeric_limits<double>::infinity();
  r.max_det = -std::numeric_limits<double>::infinity();
  double integral = 0.0, ideal_measure = 0.0;
  if (pointwise) pointwise->assign(nq, 0.0);
  for (int q = 0; q < nq; ++q) {
    const Eigen::Matrix2d Bb = tangent_plane_coordinates(JP.middleCols<2>(2 * q), normals.at_point(q));
    const double det_p = Bb.determinant();
    r.min_det = std::min(r.min_det, det_p);
    r.max_det = std::max(r.max_det, det_p);
    r.volume += tab.rule.weights[q] * det_p;
    r.ideal_volume += tab.rule.weights[q] * id.det[q];
    const double eta = measure.value(Eigen::Matrix2d(Bb * id.inverse[q]), validation);
    // As in the planar case: finite eta (det J-bar > 0) and the physical
    // element keeps the surface's orientation (det B-bar > 0; matters when
    // the ideal itself is inverted).
    if (!std::isfinite(eta) || !(det_p > 0.0)) r.valid = false;
    if (pointwise) (*pointwise)[q] = std::isfinite(eta) ? 1.0 / eta : 0.0;
    integral += id.weight[q] * eta * eta;
    ideal_measure += id.weight[q];
  }
  const Eigen::Matrix<double, 3, Eigen::Dynamic> JN = X * tab.node_shape_gradients;
  for (int i = 0; i < tab.num_nodes(); ++i) {
    const double det_p = tangent_plane_coordinates(JN.middleCols<2>(2 * i), normals.at_node(i)).determinant();
    r.min_det = std::min(r.min_det, det_p);
    r.max_det = std::max(r.max_det, det_p);
  }
  if (r.valid) {
    r.distortion = std::sqrt(integral / ideal_measure);
    r.quality = 1.0 / r.distortion;
  } else {
    r.distortion = std::numeric_limits<double>::infinity();
    r.quality = 0.0;
  }
  return r;
}

/// The same for nodes on a parameterized surface: x_i = phi(u_i) (eq 5.9),
/// oriented by the surface normal (surface_normals; UV unwrapped).
template <ElementFamily Family, SurfaceGeometry G, class Measure>
ElementQuality surface_element_quality(const Tabulation<Family>& tab, const G& g,
                                       const Eigen::Ref<const Eigen::Matrix<double, 2, Eigen::Dynamic>>& UV,
                                       const SurfaceIdealVertices<Family>& ideal, const Measure& measure,
                                       std::vector<double>* pointwise = nullptr) {
  return surface_element_quality<Family>(tab, surface_points(g, UV), ideal, surface_normals(tab, g, UV), measure,
                                         pointwise);
}

/// eta_E (def. 5.1, with the regularization `reg`) and its gradient with
/// respect to the node coordinates X (3 x n):
///   d eta_E / dX = sum_q c_q eta_q (d eta_q / dB_q) G_q^T / (eta_E sum_q c_q),
/// from eta_E^2 = sum_q c_q eta_q^2 / sum_q c_q and B_q = X G_q. NaN where some
/// eta_q is infinite (an invalid element under sigma_0).
template <ElementFamily Family, class Measure, DeterminantRegularization Reg>
double surface_element_distortion_gradient(const Tabulation<Family>& tab, const Eigen::Ref<const ElementNodes<3>>& X,
                                           const SurfaceIdealAtPoints& ideal, const SurfaceNormals& normals,
                                           const Measure& measure, const Reg& reg, ElementNodes<3>& grad) {
  const int nq = tab.num_points();
  const Eigen::Matrix<double, 3, Eigen::Dynamic> JP = X * tab.shape_gradients;
  Eigen::Matrix<double, 3, Eigen::Dynamic> P(3, 2 * nq);
  double integral = 0.0, area = 0.0;
  for (int q = 0; q < nq; ++q) {
    SurfaceTangents g;
    const double eta =
        surface_distortion_gradient(measure, ideal.inverse[q], JP.middleCols<2>(2 * q), normals.at_point(q), reg, g);
    integral += ideal.weight[q] * eta * eta;
    area += ideal.weight[q];
    P.middleCols<2>(2 * q) = (ideal.weight[q] * eta) * g;
  }
  const double eta_e = std::sqrt(integral / area);
  grad.noalias() = P * tab.shape_gradients.transpose();
  grad /= eta_e * area;
  return eta_e;
}

/// Pull back of a gradient in the node coordinates (3 x n) to the nodes'
/// parameters (2 x n): column i is D phi(u_i)^T grad.col(i) (x_i = phi(u_i)).
template <SurfaceGeometry G>
Eigen::Matrix<double, 2, Eigen::Dynamic> parameter_gradient(
    const G& g, const Eigen::Ref<const Eigen::Matrix<double, 2, Eigen::Dynamic>>& UV,
    const Eigen::Ref<const ElementNodes<3>>& grad) {
  Eigen::Matrix<double, 2, Eigen::Dynamic> r(2, UV.cols());
  for (Eigen::Index i = 0; i < UV.cols(); ++i) r.col(i) = g.derivatives(UV.col(i)).transpose() * grad.col(i);
  return r;
}

/// Point-wise quality 1/eta at each of the element's own nodes (0 where
/// det J-bar <= 0), for coloring surface meshes.
template <ElementFamily Family, class Measure>
std::vector<double> surface_nodal_quality(const Tabulation<Family>& tab, const Eigen::Ref<const ElementNodes<3>>& X,
                                          const SurfaceIdealVertices<Family>& ideal, const SurfaceNormals& normals,
                                          const Measure& measure) {
  const Eigen::Vector3d ni = facet_normal<Family>(ideal);
  const Eigen::Matrix<double, 3, Eigen::Dynamic> JN = X * tab.node_shape_gradients;
  std::vector<double> out(tab.num_nodes());
  for (int i = 0; i < tab.num_nodes(); ++i) {
    const Eigen::Matrix2d K = ideal_factor_inverse(ideal * tab.node_vertex_gradients[i], ni);
    const double eta =
        surface_distortion(measure, K, JN.middleCols<2>(2 * i), normals.at_node(i), ClampedDeterminant{});
    out[i] = std::isfinite(eta) ? 1.0 / eta : 0.0;
  }
  return out;
}

}  // namespace hom
