#pragma once
/// @file surface_problem.hpp
/// The optimization problem of chapter 5 (section 5.3.3): smoothing and
/// untangling a high-order mesh whose nodes lie on a parameterized surface,
/// with the nodes' parametric coordinates as the unknowns,
///
///   f(u_1..u_nF; u_nF+1..u_nN) = 1/2 sum_e || M phi_E_e - 1 ||^2_{E_e^I}      (eqs 5.19, 5.21)
///                              = 1/2 sum_e sum_q c_q (eta_q - 1)^2,
///   {u_1*..u_nF*} = argmin f                                                  (eq 5.22)
///
/// with, at quadrature point q of element e,
///   - x_i = phi(u_i), the nodes on the surface (eq 5.9), B_q = D phi_P = X_e G_q
///     (3 x 2, G_q the shape-function gradients at the point);
///   - eta_q = eta_delta( J-bar(A_q, B_q) ) (eq 5.6), J-bar = B-bar K_q of eq 5.5
///     with K_q = (A~_q^T A_q)^{-1} the ideal's side, c_q = w_q |det(A~_q^T A_q)|
///     (surface_ideal_at_points, as in the validation of surface_element_quality.hpp);
///   - reference normals n_q = normalize(sum_i N_i(xi_q) nu_i), nu_i the unit
///     S_u x S_v at node i (interpolated_nodal_normals): they depend on the
///     nodes' positions on the surface, not on the parameterization.
///
/// Validity and quality (status) are eq 5.5 itself with gamma = sign((b1 x
/// b2) . n_q), through surface_distortion: the validation half's definition
/// (surface_element_quality with these SurfaceNormals). An element folded
/// over the surface (its tangent plane turned over) is invalid.
///
/// The objective's B-bar = [[r, s], [0, t]] takes t = (b1 x b2) . n_q / |b1|
/// instead of eq 5.5's gamma |b1 x b2| / |b1|. Both agree when the element's
/// tangent plane is the surface's ((b1 x b2) parallel to n_q: always on a
/// plane, so the consistency of section 5.5.1.1 is exact, and in the limit of
/// small elements) and have the same sign, so validity is unchanged; but
/// eq 5.5 only sees the metric of B, not how its plane tilts away from the
/// surface, and jumps from t > 0 to t < 0 when the tilt passes 90 degrees
/// with |b1 x b2| > 0: no barrier keeps the optimizer from tilting an element
/// until it folds. Measured: with eq 5.5 literally, Newton on the thesis's
/// Sigma_2 mesh (table 5.2, phi^1) stopped at such a wall with min q = 0.26
/// (line search failed, an element at 89 degrees of tilt); the signed area
/// makes the tilt a barrier (eta -> inf as it reaches 90 degrees). The
/// normals n_q are frozen while a solver takes one outer iteration (refreshed
/// by update_regularization, like delta), so f is a fixed smooth function of
/// the parameters within a line search and its derivatives need no third
/// derivatives of phi; at a converged point the gradient is that of the
/// current normals. value() is +inf when an unregularized element is invalid
/// with respect to the current normals (status's validity), so an accepted
/// step keeps valid elements valid.

/// Regularization, as in the planar case (section 4.2.2, problem.hpp): the
/// element-wise delta_e = element_regularization(alpha).delta for the invalid
/// elements, 0 (sigma_0, ClampedDeterminant) for the valid ones, reset by the
/// solver at every outer iteration (update_regularization), so a valid
/// element is never made invalid by an accepted step.
///
/// Fixed nodes: the nodes on the edges of the surface patch (their parameters
/// come from the boundary curves, eq 5.22), held by the free mask. Parameter
/// bounds: a configuration with a free node outside the range of a bounded,
/// non-periodic parameter has f = +inf, so a line search never accepts it.
///
/// Derivatives, the chain rule through x_i = phi(u_i) (eqs 5.20-5.23):
///
///   df/du_i     = D phi(u_i)^T df/dx_i,
///   d2f/du_i du_j = D phi(u_i)^T (d2f/dx_i dx_j) D phi(u_j)
///                 + delta_ij sum_a (df/dx_i)_a D2 phi_a(u_i),
///
/// df/dx, d2f/dx2 from eta's derivatives in B (detail::signed_tangent_coordinates_jet)
/// pulled back through B_q = X G_q. The second term, with phi's second derivatives,
/// involves the whole gradient at node i (all its elements): at an optimum
/// df/dx_i is normal to the surface but not zero, and the term is the surface's
/// curvature weighted by it, so it does not vanish where Newton converges.
/// Hessian forms (HessianForm): exact (derivative checks), projected (each
/// quadrature point's 6 x 6 block in B replaced by its positive semi-definite
/// part, and the curvature term's 2 x 2 block by its PSD part: a PSD model for
/// Newton's method) and gauss_newton (c_q g g^T per point, no curvature term).
///
/// Models AssembledProblem (optimize/newton.hpp): NewtonSolver's outer loop
/// (stopping criteria, regularization reset, line search rejecting +inf)
/// runs on it unchanged. Dofs are node-major: dof a + 2 k is parameter a of
/// the k-th free node (free nodes ascending). The stopping criterion's
/// gradient norm is the tangential physical gradient, sqrt(g_k^T (D phi^T
/// D phi)^{-1} g_k), relative to the planar problem's scale s_k: it does not
/// depend on the parameterization (section 5.3.4), so two parameterizations
/// of one surface stop at the same accuracy.

#include <algorithm>
#include <numeric>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/Sparse>

#include "hom/detail/parallel.hpp"
#include "hom/geometry/surface_geometry.hpp"
#include "hom/measure/regularization.hpp"
#include "hom/measure/shape_measure.hpp"
#include "hom/optimize/element_objective.hpp"
#include "hom/optimize/problem.hpp"
#include "hom/quality/tabulation.hpp"
#include "hom/surface/surface_distortion.hpp"
#include "hom/surface/surface_element_quality.hpp"
#include "hom/surface/unit_normal.hpp"

namespace hom {

namespace detail {

/// B-bar of eq 5.5 with the continuous signed area of the objective (see the
/// file comment): [[r, s], [0, t]], r = |b1|, s = b1 . b2 / r, t = (b1 x b2) . n / r,
/// with its first and second derivatives in vec(B) (index a + 3 k). With
/// (g11, g12, d) = (b1 . b1, b1 . b2, n . (b1 x b2)) and w = g11^(-1/2):
/// r = g11 w, s = g12 w, t = d w; d is bilinear, d = b1^T [n]x^T b2.
inline SurfaceJacobianJet signed_tangent_coordinates_jet(const SurfaceTangents& B, const Eigen::Vector3d& n,
                                                         bool second_order) {
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  SurfaceJacobianJet jet;
  for (auto& m : jet.second) m.setZero();
  const Eigen::Vector3d b1 = B.col(0), b2 = B.col(1);
  const double g11 = b1.squaredNorm(), g12 = b1.dot(b2), d = n.dot(b1.cross(b2));
  const double r = std::sqrt(g11);
  if (!(r > 0.0)) return jet;
  const double w = 1.0 / r, w1 = -0.5 * w * w * w, w2 = 0.75 * w * w * w * w * w;  // w, dw/dg11, d2w/dg11^2
  jet.value << r, g12 * w, 0.0, d * w;
  Eigen::Matrix<double, 3, 6> dv;  // rows g11, g12, d
  dv.row(0) << 2.0 * b1.transpose(), Eigen::RowVector3d::Zero();
  dv.row(1) << b2.transpose(), b1.transpose();
  dv.row(2) << b2.cross(n).transpose(), n.cross(b1).transpose();
  // Partial derivatives of r, s, t in (g11, g12, d).
  Eigen::Matrix3d F1 = Eigen::Matrix3d::Zero();
  F1(0, 0) = 0.5 * w;
  F1(1, 0) = g12 * w1;
  F1(1, 1) = w;
  F1(2, 0) = d * w1;
  F1(2, 2) = w;
  const Eigen::Matrix<double, 3, 6> dF = F1 * dv;
  jet.first.row(0) = dF.row(0);
  jet.first.row(2) = dF.row(1);
  jet.first.row(3) = dF.row(2);
  if (!second_order) return jet;
  Mat6 dd11 = Mat6::Zero(), dd12 = Mat6::Zero(), ddd = Mat6::Zero();
  dd11.topLeftCorner<3, 3>() = 2.0 * Eigen::Matrix3d::Identity();
  dd12.topRightCorner<3, 3>() = Eigen::Matrix3d::Identity();
  dd12.bottomLeftCorner<3, 3>() = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d nx;  // [n]x, nx v = n x v
  nx << 0.0, -n[2], n[1], n[2], 0.0, -n[0], -n[1], n[0], 0.0;
  ddd.topRightCorner<3, 3>() = nx.transpose();
  ddd.bottomLeftCorner<3, 3>() = nx;
  const Eigen::Matrix<double, 1, 6> d0 = dv.row(0);
  // r = g11^(1/2): r'' = -1/4 g11^(-3/2).
  jet.second[0] = (-0.25 * w * w * w) * d0.transpose() * d0 + F1(0, 0) * dd11;
  // s = g12 w(g11), t = d w(g11): x w'' dg11^2 + w' (dg11 dx + dx dg11) + w' x dd11 + w ddx.
  auto product = [&](double x, const Eigen::Matrix<double, 1, 6>& dx, const Mat6& ddx) {
    return Mat6(x * w2 * d0.transpose() * d0 + w1 * (d0.transpose() * dx + dx.transpose() * d0) + x * w1 * dd11 +
                w * ddx);
  };
  jet.second[2] = product(g12, dv.row(1), dd12);
  jet.second[3] = product(d, dv.row(2), ddd);
  return jet;
}

}  // namespace detail

/// Reference normals of an element from its nodes' parameters UV (2 x n):
/// n(xi_q) = normalize(sum_i N_i(xi_q) nu_i), nu_i the unit S_u x S_v at u_i,
/// at the quadrature points and at the nodes (SurfaceNormals). Unlike the
/// normal at the interpolated parameters (surface_normals), it depends on
/// the nodes' positions on the surface only, not on the parameterization
/// (given parameterizations of the same orientation): the optimizer's choice,
/// so that validity and the optimum are parameterization-free (section 5.3.4).
template <ElementFamily Family, SurfaceGeometry G>
SurfaceNormals interpolated_nodal_normals(const Tabulation<Family>& tab, const G& g,
                                          const Eigen::Ref<const Eigen::Matrix<double, 2, Eigen::Dynamic>>& UV) {
  SurfaceNormals r;
  r.nodes = element_unit_normals(g, UV);
  r.points = r.nodes * tab.shape_values.transpose();
  normalize_or_zero(r.points);
  return r;
}

template <ElementFamily Family, class Measure, SurfaceGeometry Surface>
class SurfaceOptimizationProblem {
  static_assert(Family::dim == 2, "hom::SurfaceOptimizationProblem: surface elements are triangles and quadrilaterals");

 public:
  using family = Family;
  using measure_type = Measure;
  using surface_type = Surface;
  using Coordinates = Eigen::Matrix<double, 2, Eigen::Dynamic>;  ///< (u, v) per node
  using Points = Eigen::Matrix<double, 3, Eigen::Dynamic>;       ///< x = phi(u, v) per node
  using Connectivity = Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic>;
  using SparseMatrix = Eigen::SparseMatrix<double>;
  using Ideal = SurfaceIdealVertices<Family>;

  /// `uv`: 2 x N node parameters on `surface`; `elements`: n_p x nE
  /// connectivity in the local layout of `tab`; `free[i]`: node i moves;
  /// `ideals[e]`: element e's straight-sided ideal in R^3 (e.g. the regular
  /// element through embed_ideal, or the element's own snapshot vertices).
  /// `tab` must outlive the problem (tabulation() caches live for the program).
  SurfaceOptimizationProblem(const Tabulation<Family>& tab, Surface surface, Coordinates uv, Connectivity elements,
                             std::vector<bool> free, const std::vector<Ideal>& ideals, Measure measure = {})
      : tab_(&tab),
        surface_(std::move(surface)),
        u_(std::move(uv)),
        elements_(std::move(elements)),
        free_(std::move(free)),
        measure_(measure),
        threads_(detail::resolve_threads(0)) {
    const std::string who = "hom::SurfaceOptimizationProblem: ";
    const int n = tab.num_nodes();
    if (elements_.rows() != n)
      throw std::invalid_argument(who + "connectivity has " + std::to_string(elements_.rows()) + " rows, the tabulation " +
                                  std::to_string(n) + " nodes per element");
    if (int(free_.size()) != u_.cols())
      throw std::invalid_argument(who + "free mask has " + std::to_string(free_.size()) + " entries for " +
                                  std::to_string(u_.cols()) + " nodes");
    if (int(ideals.size()) != elements_.cols())
      throw std::invalid_argument(who + std::to_string(ideals.size()) + " ideals for " +
                                  std::to_string(elements_.cols()) + " elements");
    for (Eigen::Index e = 0; e < elements_.cols(); ++e)
      for (Eigen::Index i = 0; i < n; ++i)
        if (elements_(i, e) < 0 || elements_(i, e) >= u_.cols())
          throw std::invalid_argument(who + "element " + std::to_string(e) + " refers to node " +
                                      std::to_string(elements_(i, e)) + " of " + std::to_string(u_.cols()));
    for (int k = 0; k < 2; ++k) range_[k] = surface_.range(k);
    ideals_.resize(ideals.size());
    for (std::size_t e = 0; e < ideals.size(); ++e) {
      ideals_[e] = surface_ideal_at_points<Family>(tab, ideals[e]);
      for (double d : ideals_[e].det)
        if (!(d > 0.0))
          throw std::invalid_argument(who + "the ideal of element " + std::to_string(e) + " is degenerate");
    }
    free_index_.assign(u_.cols(), -1);
    for (int i = 0; i < int(u_.cols()); ++i)
      if (free_[i]) {
        free_index_[i] = int(free_nodes_.size());
        free_nodes_.push_back(i);
      }
    if (!in_domain(u_))
      throw std::invalid_argument(who + "a free node's parameters lie outside the surface's parameter range");
    deltas_.assign(elements_.cols(), 0.0);
    refresh_normals();
  }

  // --- sizes and data --------------------------------------------------------
  int num_nodes() const { return int(u_.cols()); }
  int num_elements() const { return int(elements_.cols()); }
  int nodes_per_element() const { return int(elements_.rows()); }
  int num_free_nodes() const { return int(free_nodes_.size()); }
  int num_dofs() const { return 2 * num_free_nodes(); }

  const Tabulation<Family>& tabulation() const { return *tab_; }
  const Surface& surface() const { return surface_; }
  const Measure& measure() const { return measure_; }
  const Connectivity& elements() const { return elements_; }
  bool is_free(int node) const { return free_[node]; }
  /// Free node ids, ascending; free dof block k belongs to free_nodes()[k].
  const std::vector<int>& free_nodes() const { return free_nodes_; }

  /// The current node parameters (solvers move the free columns).
  const Coordinates& coordinates() const { return u_; }
  Coordinates& coordinates() { return u_; }
  /// x_i = phi(u_i) for every node of U.
  Points points(const Coordinates& U) const {
    Points X(3, U.cols());
    for (Eigen::Index i = 0; i < U.cols(); ++i) X.col(i) = surface_.evaluate(U.col(i));
    return X;
  }
  /// The current physical nodes.
  Points physical_coordinates() const { return points(u_); }

  int threads() const { return threads_; }
  /// threads <= 0: OpenMP's default.
  void set_threads(int threads) { threads_ = detail::resolve_threads(threads); }

  // --- regularization (section 4.2.2, as OptimizationProblem) -------------------
  const std::vector<double>& deltas() const { return deltas_; }
  void set_deltas(std::vector<double> d) {
    if (int(d.size()) != num_elements())
      throw std::invalid_argument("hom::SurfaceOptimizationProblem::set_deltas: wrong size");
    deltas_ = std::move(d);
  }
  double regularization_alpha() const { return alpha_; }
  void set_regularization_alpha(double alpha) { alpha_ = alpha; }
  /// delta_e = element_regularization(alpha).delta for the invalid elements
  /// of `state`, 0 (sigma_0) for the valid ones. Returns the number regularized.
  int update_regularization(const MeshState& state) {
    refresh_normals();
    const double delta = element_regularization(alpha_).delta;
    int n = 0;
    for (int e = 0; e < num_elements(); ++e) {
      deltas_[e] = state.valid[e] ? 0.0 : delta;
      n += !state.valid[e];
    }
    return n;
  }

  /// Freezes the objective's reference normals at the current coordinates
  /// (interpolated_nodal_normals at the quadrature points); the solvers'
  /// outer loop does it at every iteration through update_regularization.
  void refresh_normals() {
    const Points nu = nodal_normals(u_);
    normals_.resize(3, Eigen::Index(num_elements()) * num_points());
    for (int e = 0; e < num_elements(); ++e)
      normals_.middleCols(Eigen::Index(e) * num_points(), num_points()) = point_normals(nu, u_, e);
  }
  /// The frozen reference normals of element e (3 x nq).
  auto reference_normals(int e) const { return normals_.middleCols(Eigen::Index(e) * num_points(), num_points()); }

  // --- free dofs <-> coordinates ----------------------------------------------
  /// Whether every free node's parameters lie in the surface's range
  /// (bounded, non-periodic parameters; the range is closed).
  bool in_domain(const Coordinates& U) const {
    for (int node : free_nodes_)
      for (int k = 0; k < 2; ++k)
        if (!std::isfinite(U(k, node)) || !range_[k].contains(U(k, node))) return false;
    return true;
  }
  Eigen::VectorXd free_vector(const Coordinates& U) const {
    Eigen::VectorXd v(num_dofs());
    for (int k = 0; k < num_free_nodes(); ++k) v.template segment<2>(2 * k) = U.col(free_nodes_[k]);
    return v;
  }
  /// U with its free nodes moved by alpha * p (p over the free dofs).
  Coordinates displaced(const Coordinates& U, const Eigen::VectorXd& p, double alpha) const {
    Coordinates Y = U;
    for (int k = 0; k < num_free_nodes(); ++k) Y.col(free_nodes_[k]) += alpha * p.template segment<2>(2 * k);
    return Y;
  }

  // --- evaluation ----------------------------------------------------------
  /// Validity and quality of every element at U (sigma_0, independent of
  /// delta), eq 5.5 with the current reference normals: q_E = 1 / eta_E
  /// (defs. 5.1-5.2), 0 when det J-bar <= 0 at a point.
  MeshState status(const Coordinates& U) const {
    const int ne = num_elements();
    const Points X = points(U);
    const Points nu = nodal_normals(U);
    MeshState s;
    s.valid.assign(ne, 1);
    s.quality.assign(ne, 0.0);
    HOM_PARALLEL_FOR_DYNAMIC(detail::useful_threads(threads_, ne, 16))
    for (int e = 0; e < ne; ++e) {
      Work w;
      gather(X, e, w);
      const Points n = point_normals(nu, U, e);
      const SurfaceIdealAtPoints& id = ideals_[e];
      double integral = 0.0, area = 0.0;
      bool valid = true;
      for (int q = 0; q < num_points() && valid; ++q) {
        // Eq 5.5 itself (gamma from the current normals): the validation's quality.
        const double eta = surface_distortion(measure_, id.inverse[q], tangents(w, q), Eigen::Vector3d(n.col(q)),
                                              ClampedDeterminant{});
        valid = std::isfinite(eta);
        integral += id.weight[q] * eta * eta;
        area += id.weight[q];
      }
      s.valid[e] = valid;
      s.quality[e] = valid ? 1.0 / std::sqrt(integral / area) : 0.0;
    }
    s.min_quality = ne > 0 ? 1.0 : 0.0;
    for (int e = 0; e < ne; ++e) {
      s.inverted += !s.valid[e];
      s.min_quality = std::min(s.min_quality, s.quality[e]);
    }
    return s;
  }

  /// f at U with the current deltas; +inf if an element with delta = 0 is
  /// invalid or a free node left the parameter range.
  double value(const Coordinates& U) const {
    if (!in_domain(U)) return std::numeric_limits<double>::infinity();
    const int ne = num_elements();
    const Points X = points(U);
    const Points nu = nodal_normals(U);
    std::vector<double> fe(ne);
    HOM_PARALLEL_FOR_DYNAMIC(detail::useful_threads(threads_, ne, 16))
    for (int e = 0; e < ne; ++e) {
      Work w;
      gather(X, e, w);
      const SurfaceIdealAtPoints& id = ideals_[e];
      const auto n = reference_normals(e);
      if (!(deltas_[e] > 0.0) && !oriented(w, point_normals(nu, U, e))) {
        fe[e] = std::numeric_limits<double>::infinity();  // invalid with sigma_0 (consistency, section 4.2.2)
        continue;
      }
      fe[e] = with_regularization(e, [&](const auto& reg) {
        double f = 0.0;
        for (int q = 0; q < num_points(); ++q) {
          const double eta = point_value(id.inverse[q], tangents(w, q), n.col(q), reg);
          f += 0.5 * id.weight[q] * (eta - 1.0) * (eta - 1.0);
        }
        return f;
      });
    }
    return sum_in_order(fe);
  }

  /// f at U and its gradient over the free dofs (g undefined when f = +inf).
  double value_gradient(const Coordinates& U, Eigen::VectorXd& g) const {
    if (!in_domain(U)) return std::numeric_limits<double>::infinity();
    const int ne = num_elements(), n = nodes_per_element();
    const Points X = points(U);
    std::vector<double> fe(ne);
    Points Ge(3, Eigen::Index(n) * ne);
    HOM_PARALLEL_FOR_DYNAMIC(detail::useful_threads(threads_, ne, 16))
    for (int e = 0; e < ne; ++e) {
      Work w;
      gather(X, e, w);
      fe[e] = with_regularization(e, [&](const auto& reg) { return element_gradient(w, e, reg, w.grad); });
      Ge.middleCols(Eigen::Index(e) * n, n) = w.grad;
    }
    const Points GX = node_gradients(Ge);
    g.resize(num_dofs());
    for (int k = 0; k < num_free_nodes(); ++k) {
      const int node = free_nodes_[k];
      g.template segment<2>(2 * k) = surface_.derivatives(U.col(node)).transpose() * GX.col(node);
    }
    return sum_in_order(fe);
  }

  /// f, gradient and the Hessian over the free dofs (symmetric, full
  /// storage) in the given form (see the file comment).
  double hessian(const Coordinates& U, HessianForm form, Eigen::VectorXd& g, SparseMatrix& H) const {
    const int ne = num_elements(), n = nodes_per_element(), nf = num_free_nodes();
    H.resize(num_dofs(), num_dofs());
    g.setZero(num_dofs());
    if (!in_domain(U)) return std::numeric_limits<double>::infinity();
    const Points X = points(U);
    // D phi at the free nodes.
    std::vector<Eigen::Matrix<double, 3, 2>> D(num_nodes(), Eigen::Matrix<double, 3, 2>::Zero());
    for (int node : free_nodes_) D[node] = surface_.derivatives(U.col(node));
    std::vector<double> fe(ne);
    Points Ge(3, Eigen::Index(n) * ne);
    std::vector<Eigen::MatrixXd> He(ne);  // per element, (2 n) x (2 n) in the nodes' parameters
    HOM_PARALLEL_FOR_DYNAMIC(detail::useful_threads(threads_, ne, 4))
    for (int e = 0; e < ne; ++e) {
      Work w;
      gather(X, e, w);
      Eigen::MatrixXd HX;
      fe[e] = with_regularization(e, [&](const auto& reg) { return element_hessian(w, e, reg, form, w.grad, HX); });
      Ge.middleCols(Eigen::Index(e) * n, n) = w.grad;
      // Pull back to the parameters: blocks D_i^T HX_ij D_j for free i, j.
      Eigen::MatrixXd& Hu = He[e];
      Hu.setZero(2 * n, 2 * n);
      for (int j = 0; j < n; ++j) {
        const int nj = elements_(j, e);
        if (!free_[nj]) continue;
        for (int i = 0; i < n; ++i) {
          const int ni = elements_(i, e);
          if (!free_[ni]) continue;
          Hu.template block<2, 2>(2 * i, 2 * j).noalias() =
              D[ni].transpose() * HX.template block<3, 3>(3 * i, 3 * j) * D[nj];
        }
      }
    }
    const Points GX = node_gradients(Ge);
    std::vector<Eigen::Triplet<double>> t;
    t.reserve(std::size_t(ne) * 4 * n * n + 4 * std::size_t(nf));
    for (int e = 0; e < ne; ++e)
      for (int j = 0; j < n; ++j) {
        const int fj = free_index_[elements_(j, e)];
        if (fj < 0) continue;
        for (int i = 0; i < n; ++i) {
          const int fi = free_index_[elements_(i, e)];
          if (fi < 0) continue;
          for (int b = 0; b < 2; ++b)
            for (int a = 0; a < 2; ++a) t.emplace_back(2 * fi + a, 2 * fj + b, He[e](2 * i + a, 2 * j + b));
        }
      }
    for (int k = 0; k < nf; ++k) {
      const int node = free_nodes_[k];
      const Eigen::Vector3d gx = GX.col(node);
      g.template segment<2>(2 * k) = D[node].transpose() * gx;
      // The curvature term sum_a (df/dx)_a D2 phi_a (see the file comment).
      Eigen::Matrix2d C = Eigen::Matrix2d::Zero();
      if (form != HessianForm::gauss_newton) {
        const SurfaceSecondDerivatives s = surface_.second_derivatives(U.col(node));
        C << gx.dot(s.uu), gx.dot(s.uv), gx.dot(s.uv), gx.dot(s.vv);
        if (form == HessianForm::projected) C = detail::psd_part<2>(C);
      }
      for (int b = 0; b < 2; ++b)
        for (int a = 0; a < 2; ++a) t.emplace_back(2 * k + a, 2 * k + b, C(a, b));
    }
    H.setFromTriplets(t.begin(), t.end());
    return sum_in_order(fe);
  }

  /// s_k for each free node k: the size the physical gradient at the node
  /// would have if every eta - 1 and d eta / dJ-bar were 1, computed once, in
  /// the root-mean-square form of OptimizationProblem::gradient_scale: each
  /// element (local node l) adds sqrt((sum_q c_q) sum_q c_q |K_q^T G_q(l,:)^T|^2).
  const Eigen::VectorXd& gradient_scale() const {
    if (gradient_scale_.size() == num_free_nodes()) return gradient_scale_;
    const int n = nodes_per_element();
    const Tabulation<Family>& tab = *tab_;
    Eigen::VectorXd s = Eigen::VectorXd::Zero(num_free_nodes());
    for (int e = 0; e < num_elements(); ++e) {
      const SurfaceIdealAtPoints& id = ideals_[e];
      const double area = std::accumulate(id.weight.begin(), id.weight.end(), 0.0);
      for (int l = 0; l < n; ++l) {
        const int k = free_index_[elements_(l, e)];
        if (k < 0) continue;
        double squares = 0.0;
        for (int q = 0; q < tab.num_points(); ++q)
          squares += id.weight[q] *
                     (id.inverse[q].transpose() * tab.shape_gradients.row(l).template segment<2>(2 * q).transpose()).squaredNorm();
        s[k] += std::sqrt(area * squares);
      }
    }
    for (int k = 0; k < s.size(); ++k)
      if (!(s[k] > 0.0)) s[k] = 1.0;
    gradient_scale_ = std::move(s);
    return gradient_scale_;
  }

  /// max_k |tangential physical gradient at free node k| / s_k, at the
  /// current coordinates: |.| = sqrt(g_k^T (D phi^T D phi)^{-1} g_k), the
  /// norm of the gradient in the surface's metric (parameterization-free).
  double scaled_gradient_norm(const Eigen::VectorXd& g) const {
    const Eigen::VectorXd& s = gradient_scale();
    double r = 0.0;
    for (int k = 0; k < num_free_nodes(); ++k) {
      const Eigen::Matrix<double, 3, 2> D = surface_.derivatives(u_.col(free_nodes_[k]));
      const Eigen::Matrix2d metric = D.transpose() * D;
      const Eigen::Vector2d gk = g.template segment<2>(2 * k);
      const double t = gk.dot(metric.ldlt().solve(gk));
      r = std::max(r, std::sqrt(std::max(t, 0.0)) / s[k]);
    }
    return r;
  }

 private:
  /// One element's data at a configuration.
  struct Work {
    Points X;     ///< physical nodes
    Points JP;    ///< B_q = X G_q, 3 x (2 nq)
    Points grad;  ///< df_e / dX (3 x n)
  };

  int num_points() const { return tab_->num_points(); }

  void gather(const Points& X, int e, Work& w) const {
    const int n = nodes_per_element();
    w.X.resize(3, n);
    for (int i = 0; i < n; ++i) w.X.col(i) = X.col(elements_(i, e));
    w.JP.noalias() = w.X * tab_->shape_gradients;
  }

  /// unit_normal at every node of U (3 x N): zero at a degenerate point,
  /// which point_normals replaces element by element.
  Points nodal_normals(const Coordinates& U) const {
    Points nu(3, U.cols());
    for (Eigen::Index i = 0; i < U.cols(); ++i) nu.col(i) = unit_normal(surface_, Eigen::Vector2d(U.col(i)));
    return nu;
  }

  /// interpolated_nodal_normals at the quadrature points of element e, from
  /// the nodal normals nu of nodal_normals(U); a degenerate node's normal is
  /// its limit from inside e (unit_normal_from).
  Points point_normals(const Points& nu, const Coordinates& U, int e) const {
    const int n = nodes_per_element();
    Eigen::Matrix2Xd Ue(2, n);
    for (int i = 0; i < n; ++i) Ue.col(i) = U.col(elements_(i, e));
    Eigen::Matrix3Xd ne(3, n);
    for (int i = 0; i < n; ++i) ne.col(i) = nu.col(elements_(i, e));
    fill_degenerate_normals(surface_, Ue, nodes_with_normal(ne), ne);
    Eigen::Matrix3Xd r = ne * tab_->shape_values.transpose();
    normalize_or_zero(r);
    return r;
  }

  /// Whether (b1 x b2) . n > 0 at every quadrature point: the element is
  /// valid (gamma = +1, det J-bar > 0) with respect to the normals n.
  bool oriented(const Work& w, const Points& n) const {
    for (int q = 0; q < num_points(); ++q)
      if (!(w.JP.col(2 * q).cross(w.JP.col(2 * q + 1)).dot(n.col(q)) > 0.0)) return false;
    return true;
  }

  /// eta of the objective at one point (signed area (b1 x b2) . n, see the file comment).
  template <class Reg>
  double point_value(const Eigen::Matrix2d& K, const SurfaceTangents& B, const Eigen::Vector3d& n, const Reg& reg) const {
    const Eigen::Vector3d b1 = B.col(0), b2 = B.col(1);
    const double r = b1.norm();
    Eigen::Matrix2d Bb = Eigen::Matrix2d::Zero();
    if (r > 0.0) Bb << r, b1.dot(b2) / r, 0.0, n.dot(b1.cross(b2)) / r;
    return measure_.value(Eigen::Matrix2d(Bb * K), reg);
  }

  /// eta, d eta / dB and (hess != nullptr) d2 eta / d vec(B)^2 at one point.
  template <class Reg>
  double point_derivatives(const Eigen::Matrix2d& K, const SurfaceTangents& B, const Eigen::Vector3d& n, const Reg& reg,
                           SurfaceTangents& grad, Eigen::Matrix<double, 6, 6>* hess) const {
    const bool second = hess != nullptr;
    const SurfaceJacobianJet j = detail::right_multiply_jet(detail::signed_tangent_coordinates_jet(B, n, second), K, second);
    Eigen::Matrix2d g;
    Eigen::Matrix4d h;
    const double eta = second ? measure_.value_gradient_hessian(j.value, reg, g, h) : measure_.value_gradient(j.value, reg, g);
    const Eigen::Map<const Eigen::Vector4d> gv(g.data());
    const Eigen::Matrix<double, 6, 1> gb = j.first.transpose() * gv;
    grad = Eigen::Map<const SurfaceTangents>(gb.data());
    if (second) {
      *hess = j.first.transpose() * h * j.first;
      for (int i = 0; i < 4; ++i) *hess += gv[i] * j.second[i];
    }
    return eta;
  }

  static SurfaceTangents tangents(const Work& w, int q) { return w.JP.template middleCols<2>(2 * q); }

  template <class Fn>
  decltype(auto) with_regularization(int e, Fn&& fn) const {
    if (deltas_[e] > 0.0) return fn(RegularizedDeterminant{deltas_[e]});
    return fn(ClampedDeterminant{});
  }

  /// f_e and df_e / dX (3 x n): sum_q c_q (eta_q - 1) (d eta_q / dB_q) G_q^T.
  template <class Reg>
  double element_gradient(const Work& w, int e, const Reg& reg, Points& grad) const {
    const SurfaceIdealAtPoints& id = ideals_[e];
    const int nq = num_points();
    const auto n = reference_normals(e);
    Points P(3, 2 * nq);
    double f = 0.0;
    for (int q = 0; q < nq; ++q) {
      SurfaceTangents gb;
      const double eta = point_derivatives(id.inverse[q], tangents(w, q), n.col(q), reg, gb, nullptr);
      const double r = eta - 1.0;
      f += 0.5 * id.weight[q] * r * r;
      P.template middleCols<2>(2 * q) = (id.weight[q] * r) * gb;
    }
    grad.noalias() = P * tab_->shape_gradients.transpose();
    return f;
  }

  /// f_e, df_e / dX and d2f_e / dX2 ((3 n) x (3 n), node-major: a + 3 i)
  /// in the given form. Per point M_q = c_q (g g^T + (eta - 1) H_B) in vec(B)
  /// (index a + 3 k), pulled back through B_q(a, k) = sum_i X(a, i) G_q(i, k):
  ///   HX(a + 3 i, c + 3 j) = sum_q sum_kl G_q(i, k) M_q(a + 3 k, c + 3 l) G_q(j, l).
  template <class Reg>
  double element_hessian(const Work& w, int e, const Reg& reg, HessianForm form, Points& grad, Eigen::MatrixXd& HX) const {
    using Mat6 = Eigen::Matrix<double, 6, 6>;
    using Vec6 = Eigen::Matrix<double, 6, 1>;
    const SurfaceIdealAtPoints& id = ideals_[e];
    const int nq = num_points(), n = nodes_per_element();
    const Eigen::MatrixXd& G = tab_->shape_gradients;
    const auto normals = reference_normals(e);
    Points P(3, 2 * nq);
    std::vector<Mat6> M(nq);
    double f = 0.0;
    for (int q = 0; q < nq; ++q) {
      SurfaceTangents gb;
      Mat6 hb;
      const double eta = point_derivatives(id.inverse[q], tangents(w, q), normals.col(q), reg, gb,
                                           form == HessianForm::gauss_newton ? nullptr : &hb);
      const double r = eta - 1.0, c = id.weight[q];
      f += 0.5 * c * r * r;
      P.template middleCols<2>(2 * q) = (c * r) * gb;
      const Eigen::Map<const Vec6> gv(gb.data());
      if (form == HessianForm::gauss_newton) {
        M[q] = c * gv * gv.transpose();
      } else {
        M[q] = c * (gv * gv.transpose() + r * hb);
        if (form == HessianForm::projected) M[q] = detail::psd_part<6>(Mat6(0.5 * (M[q] + M[q].transpose())));
      }
    }
    grad.noalias() = P * G.transpose();
    HX.setZero(3 * n, 3 * n);
    Eigen::MatrixXd Bm(n, 2 * nq), Hac(n, n);
    for (int a = 0; a < 3; ++a)
      for (int c = a; c < 3; ++c) {
        for (int q = 0; q < nq; ++q) {
          Eigen::Matrix2d block;
          for (int k = 0; k < 2; ++k)
            for (int l = 0; l < 2; ++l) block(k, l) = M[q](a + 3 * k, c + 3 * l);
          Bm.template middleCols<2>(2 * q).noalias() = G.template middleCols<2>(2 * q) * block;
        }
        Hac.noalias() = Bm * G.transpose();
        for (int i = 0; i < n; ++i)
          for (int j = 0; j < n; ++j) {
            HX(a + 3 * i, c + 3 * j) = Hac(i, j);
            HX(c + 3 * j, a + 3 * i) = Hac(i, j);
          }
      }
    return f;
  }

  /// df/dx per node (3 x N): the element contributions summed in element order.
  Points node_gradients(const Points& Ge) const {
    const int n = nodes_per_element();
    Points GX = Points::Zero(3, num_nodes());
    for (int e = 0; e < num_elements(); ++e)
      for (int i = 0; i < n; ++i) GX.col(elements_(i, e)) += Ge.col(Eigen::Index(e) * n + i);
    return GX;
  }

  static double sum_in_order(const std::vector<double>& v) {
    double s = 0.0;
    for (double x : v) s += x;
    return s;
  }

  const Tabulation<Family>* tab_;
  Surface surface_;
  Coordinates u_;
  Connectivity elements_;
  std::vector<bool> free_;
  std::vector<SurfaceIdealAtPoints> ideals_;
  Measure measure_;
  int threads_ = 1;
  ParameterRange range_[2];
  double alpha_ = thesis_regularization_alpha;
  std::vector<double> deltas_;
  std::vector<int> free_nodes_;
  std::vector<int> free_index_;  // -1 for fixed nodes
  Points normals_;  // frozen reference normals, 3 x (nq per element)
  mutable Eigen::VectorXd gradient_scale_;
};

/// Deduces the problem's types: make_surface_problem(tab, surface, uv, conn, free, ideals[, measure]).
template <ElementFamily Family, class Measure = ShapeMeasure, SurfaceGeometry Surface>
SurfaceOptimizationProblem<Family, Measure, Surface> make_surface_problem(
    const Tabulation<Family>& tab, const Surface& surface, Eigen::Matrix<double, 2, Eigen::Dynamic> uv,
    Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic> elements, std::vector<bool> free,
    const std::vector<SurfaceIdealVertices<Family>>& ideals, const Measure& measure = {}) {
  return SurfaceOptimizationProblem<Family, Measure, Surface>(tab, surface, std::move(uv), std::move(elements),
                                                              std::move(free), ideals, measure);
}

}  // namespace hom
