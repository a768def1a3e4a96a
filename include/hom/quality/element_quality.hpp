#pragma once
/// @file element_quality.hpp
/// Distortion and quality of one high-order element (definitions 3.1, 3.5, 3.6):
///
///   point-wise:  M phi_E(y) = eta(D phi_E(y)),            D phi_E = D phi_P (D phi_I)^{-1}   (eq 3.19, A.2)
///   element:     eta_E = || M phi_E ||_{E^I} / || 1 ||_{E^I}                                  (eq 3.20, 3.23)
///   quality:     q_E = 1 / eta_E                                                              (eq 3.24)
///
/// The norms are integrals over the ideal element, computed on the reference
/// element with the change of variables of eq 3.18 (weight |det D phi_I|) and
/// a quadrature rule. Validation uses sigma_0 (eq 3.8): q_E = 0 exactly when
/// det D phi_E <= 0 at some quadrature point (remark 3.3), or when the element
/// is inverted with respect to the master element (det D phi_P <= 0), which
/// also catches an inverted ideal (remark 3.1 requires a valid one).
///
/// Also here: the scaled Jacobian mu = min det D phi_P / max det D phi_P (eq 5.31,
/// section 4.3.3) over the quadrature points and the nodes, and the element's
/// volume (for the relative volume change r_v of section 4.3.3).

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Dense>

#include "hom/measure/distortion_measure.hpp"
#include "hom/measure/regularization.hpp"
#include "hom/quality/ideal.hpp"
#include "hom/quality/tabulation.hpp"

namespace hom {

/// What an element's evaluation reports.
struct ElementQuality {
  double distortion = 1.0;  ///< eta_E in [1, inf]; inf when invalid
  double quality = 1.0;     ///< q_E = 1 / eta_E in [0, 1]
  bool valid = true;        ///< det D phi_E > 0 at every quadrature point
  double min_det = 0.0;     ///< min det D phi_P at the quadrature points and the nodes
  double max_det = 0.0;     ///< max det D phi_P at the quadrature points and the nodes
  double volume = 0.0;      ///< integral of det D phi_P over the reference element
  double ideal_volume = 0.0;

  /// mu of eq 5.31: min det / max det for valid elements. Normalized by the
  /// largest |det|, so an element with det <= 0 somewhere scores in [-1, 0],
  /// never a positive ratio.
  double scaled_jacobian() const { return min_det / std::max(std::abs(max_det), std::abs(min_det)); }
  /// r_v of section 4.3.3 against the ideal's volume.
  double relative_volume_change() const { return std::abs(volume - ideal_volume) / std::abs(ideal_volume); }
};

/// Element node coordinates: Dim x n, one column per node in hom's layout order.
template <int Dim>
using ElementNodes = Eigen::Matrix<double, Dim, Eigen::Dynamic>;

/// Evaluates definitions 3.5-3.6 for one element. `pointwise`, when given,
/// receives the point-wise quality 1/eta at each quadrature point.
template <ElementFamily Family, class Measure>
ElementQuality element_quality(const Tabulation<Family>& tab, const Eigen::Ref<const ElementNodes<Family::dim>>& X,
                               const IdealVertices<Family>& ideal, const Measure& measure,
                               std::vector<double>* pointwise = nullptr) {
  constexpr int D = Family::dim;
  using Mat = Eigen::Matrix<double, D, D>;
  const int nq = tab.num_points();
  const Eigen::Matrix<double, D, Eigen::Dynamic> JP = reference_jacobians(tab, X);
  const ClampedDeterminant validation;

  ElementQuality r;
  r.min_det = std::numeric_limits<double>::infinity();
  r.max_det = -std::numeric_limits<double>::infinity();
  double integral = 0.0, ideal_measure = 0.0;
  if (pointwise) pointwise->assign(nq, 0.0);
  for (int q = 0; q < nq; ++q) {
    const Mat Jp = JP.template middleCols<D>(q * D);
    const Mat Ji = ideal_jacobian<Family>(ideal, tab.rule.points[q]);
    const double det_i = Ji.determinant();
    const double w = tab.rule.weights[q] * std::abs(det_i);
    const double det_p = Jp.determinant();
    r.min_det = std::min(r.min_det, det_p);
    r.max_det = std::max(r.max_det, det_p);
    r.volume += tab.rule.weights[q] * det_p;
    r.ideal_volume += tab.rule.weights[q] * det_i;
    const double eta = measure.value(Mat(Jp * Ji.inverse()), validation);
    // Valid: det D phi_E > 0 (finite eta under sigma_0) and the element keeps
    // the master element's orientation, det D phi_P > 0. The second test
    // matters when the ideal is itself inverted (a tangled straight-sided
    // element as its own relative ideal: remark 3.1 asks for a valid ideal).
    if (!std::isfinite(eta) || !(det_p > 0.0)) r.valid = false;
    if (pointwise) (*pointwise)[q] = std::isfinite(eta) ? 1.0 / eta : 0.0;
    integral += w * eta * eta;
    ideal_measure += w;
  }
  // Scaled Jacobian also at the nodes (section 4.3.3 samples the integration
  // points; the nodes catch folds at the element's boundary).
  const Eigen::Matrix<double, D, Eigen::Dynamic> JN = X * tab.node_shape_gradients;
  for (int i = 0; i < tab.num_nodes(); ++i) {
    const double det_p = Mat(JN.template middleCols<D>(i * D)).determinant();
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

/// Point-wise quality 1/eta(D phi_E) at each of the element's own nodes (for
/// coloring meshes by quality; 0 where det <= 0).
template <ElementFamily Family, class Measure>
std::vector<double> nodal_quality(const Tabulation<Family>& tab, const Eigen::Ref<const ElementNodes<Family::dim>>& X,
                                  const IdealVertices<Family>& ideal, const Measure& measure) {
  constexpr int D = Family::dim;
  using Mat = Eigen::Matrix<double, D, D>;
  const Eigen::Matrix<double, D, Eigen::Dynamic> JN = X * tab.node_shape_gradients;
  std::vector<double> out(tab.num_nodes());
  for (int i = 0; i < tab.num_nodes(); ++i) {
    const Mat Ji = ideal * tab.node_vertex_gradients[i];
    const double eta = measure.value(Mat(JN.template middleCols<D>(i * D) * Ji.inverse()), ClampedDeterminant{});
    out[i] = std::isfinite(eta) ? 1.0 / eta : 0.0;
  }
  return out;
}

}  // namespace hom
