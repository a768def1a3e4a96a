#pragma once
/// @file problem.hpp
/// The global mesh optimization problem of eq 4.11: minimize over the free
/// node coordinates
///
///     f(x_1..x_nF; x_nF+1..x_nN) = 1/2 sum_e || M_delta_e phi_E_e - 1 ||^2_{E_e^I}     (eqs 4.9, 4.10)
///
/// with the fixed nodes (boundary nodes, already on the geometry) held in
/// place. `OptimizationProblem` is independent of the Mesh class: it holds
/// the node coordinates (Dim x N), the connectivity (n_p x nE, hom's local
/// layout), a free-node mask, each element's ideal at the quadrature points
/// (IdealAtPoints), the shared tabulation, the measure and an element-wise
/// regularization delta_e. It evaluates, for any trial coordinates X,
///   - f (value), the gradient over the free degrees of freedom,
///   - the assembled sparse Hessian over the free dofs (exact, projected or
///     Gauss-Newton, element_objective.hpp), and
///   - a Hessian operator that applies the Hessian to a vector element by
///     element without storing element Hessians (matrix-free Newton-CG).
/// Free dofs are numbered node-major: dof a + Dim * k is coordinate a of the
/// k-th free node (free nodes in ascending node id).
///
/// Regularization (section 4.2.2). delta_e is element-wise and constant while
/// a solver takes one outer iteration. `update_regularization(state)` sets
///     delta_e = element_regularization(alpha).delta   if element e is invalid
///                                                     (det D phi_E <= 0 at some quadrature point),
///     delta_e = 0                                      otherwise,
/// where delta_e = 0 means sigma_0 (ClampedDeterminant, eq 3.8): f_e = +inf
/// as soon as the element is invalid. Solvers call it at the start of every
/// outer iteration, so
///   - a line search, which rejects +inf, never accepts a step that makes a
///     valid element invalid: the number of invalid elements never increases
///     and an element valid at the start is valid at the end (consistency);
///   - invalid elements see the smooth regularized measure (eq 3.5) and can
///     be untangled; once every element is valid, delta = 0 everywhere and the
///     optimization is the unregularized one (section 4.2.1).
/// In hom's units (J = D phi_E relative to the ideal) the thesis's delta of
/// eq 4.14 is the same constant sqrt(alpha^2 + alpha) for every element
/// (see element_regularization()).
///
/// Parallelism: element loops run on `threads()` OpenMP threads; each element
/// writes its own slot and every sum over elements is taken afterwards in a
/// fixed order (per node, in element order), so results do not depend on the
/// number of threads. A problem object is not meant to be evaluated from
/// several threads at once (it caches the Hessian's sparsity pattern).

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <cmath>
#include <limits>
#include <memory>
#include <span>
#include <type_traits>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/Sparse>

#include "hom/detail/parallel.hpp"
#include "hom/detail/point_lanes.hpp"
#include "hom/measure/distortion_measure.hpp"
#include "hom/measure/regularization.hpp"
#include "hom/measure/shape_measure.hpp"
#include "hom/mesh/coloring.hpp"
#include "hom/optimize/element_objective.hpp"
#include "hom/quality/tabulation.hpp"

namespace hom {

/// Per-element validity and quality of a configuration (what solvers watch).
struct MeshState {
  std::vector<char> valid;      ///< det D phi_E > 0 at every quadrature point
  std::vector<double> quality;  ///< q_E = 1 / eta_E (def 3.6, eq 3.24) with sigma_0; 0 when invalid
  int inverted = 0;             ///< number of invalid elements
  double min_quality = 0.0;     ///< min_e q_E (0 if any element is invalid)

  bool all_valid() const { return inverted == 0; }
};

/// Which elements section 4.2.2's delta regularizes while the mesh is invalid.
///   - invalid_elements (default, the thesis's "only use the regularized
///     distortion measure when the element is invalid"): valid elements keep
///     sigma_0, so their distortion is a barrier at det = 0 from the start;
///   - whole_mesh: every element while any is invalid (the mesh-level reading
///     of section 4.2.1: "delta is only set to non-zero values when an invalid
///     mesh configuration is considered"), so a valid element may pass through
///     a degenerate configuration on the way to untangling its neighbours.
/// Both switch to delta = 0 everywhere once every element is valid, after
/// which the barrier keeps the mesh valid. Only invalid_elements guarantees
/// that an element valid at the start is never invalid at the end (issue 5's
/// consistency requirement), which is why it is the default; whole_mesh
/// trades that for robustness (bench_smooth, table 4.2: with the element-wise
/// scope the degree-1 solve stalls with 7-10 elements inverted).
enum class RegularizationScope { invalid_elements, whole_mesh };

inline std::string_view to_string(RegularizationScope s) {
  return s == RegularizationScope::whole_mesh ? "whole-mesh" : "invalid";
}

/// "invalid" or "whole-mesh" (command lines).
inline RegularizationScope parse_regularization_scope(const std::string& s) {
  if (s == "invalid") return RegularizationScope::invalid_elements;
  if (s == "whole-mesh") return RegularizationScope::whole_mesh;
  throw std::invalid_argument("unknown regularization scope '" + s + "' (expected invalid or whole-mesh)");
}

/// The regularization policy of an optimization: alpha of eq 4.13 (delta from
/// eq 4.14) and the scope above.
struct Regularization {
  double alpha = thesis_regularization_alpha;
  RegularizationScope scope = RegularizationScope::invalid_elements;
};

/// Where a node appears: local node `local` of element `element`.
struct NodeIncidence {
  int element = 0;
  int local = 0;
};

template <ElementFamily Family, class Measure = ShapeMeasure>
class OptimizationProblem {
 public:
  static constexpr int dim = Family::dim;
  using family = Family;
  using measure_type = Measure;
  using Coordinates = Eigen::Matrix<double, dim, Eigen::Dynamic>;
  using Connectivity = Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic>;
  using Ideal = IdealAtPoints<dim>;
  using SparseMatrix = Eigen::SparseMatrix<double>;
  using NodeMatrix = Eigen::Matrix<double, dim, dim>;

  /// `x`: Dim x N node coordinates; `elements`: n_p x nE connectivity in the
  /// local layout of `tab`; `free[i]`: node i moves; `ideals[e]`: element e's
  /// ideal at the quadrature points of `tab` (ideal_at_points). `tab` must
  /// outlive the problem (tabulation() caches live for the program).
  OptimizationProblem(const Tabulation<Family>& tab, Coordinates x, Connectivity elements, std::vector<bool> free,
                      std::vector<Ideal> ideals, Measure measure = {})
      : tab_(&tab),
        x_(std::move(x)),
        elements_(std::move(elements)),
        free_(std::move(free)),
        ideals_(std::move(ideals)),
        measure_(measure),
        threads_(detail::resolve_threads(0)) {
    const int n = tab.num_nodes();
    if (elements_.rows() != n)
      throw std::invalid_argument("hom::OptimizationProblem: connectivity has " + std::to_string(elements_.rows()) +
                                  " rows, the tabulation " + std::to_string(n) + " nodes per element");
    if (int(free_.size()) != x_.cols())
      throw std::invalid_argument("hom::OptimizationProblem: free mask has " + std::to_string(free_.size()) +
                                  " entries for " + std::to_string(x_.cols()) + " nodes");
    if (int(ideals_.size()) != elements_.cols())
      throw std::invalid_argument("hom::OptimizationProblem: " + std::to_string(ideals_.size()) + " ideals for " +
                                  std::to_string(elements_.cols()) + " elements");
    for (const auto& id : ideals_)
      if (id.num_points() != tab.num_points())
        throw std::invalid_argument("hom::OptimizationProblem: an ideal was tabulated with another quadrature rule");
    for (Eigen::Index e = 0; e < elements_.cols(); ++e)
      for (Eigen::Index i = 0; i < n; ++i)
        if (elements_(i, e) < 0 || elements_(i, e) >= x_.cols())
          throw std::invalid_argument("hom::OptimizationProblem: element " + std::to_string(e) + " refers to node " +
                                      std::to_string(elements_(i, e)) + " of " + std::to_string(x_.cols()));
    free_index_.assign(x_.cols(), -1);
    for (int i = 0; i < int(x_.cols()); ++i)
      if (free_[i]) {
        free_index_[i] = int(free_nodes_.size());
        free_nodes_.push_back(i);
      }
    build_incidences();
    deltas_.assign(elements_.cols(), 0.0);
  }

  // --- sizes and data --------------------------------------------------------
  int num_nodes() const { return int(x_.cols()); }
  int num_elements() const { return int(elements_.cols()); }
  int nodes_per_element() const { return int(elements_.rows()); }
  int num_free_nodes() const { return int(free_nodes_.size()); }
  int num_dofs() const { return dim * num_free_nodes(); }

  /// Stored entries of the assembled Hessian (full symmetric storage): dim^2
  /// for every ordered pair of free nodes that share an element. Counted
  /// without building the pattern, so that NewtonSolver can refuse a problem
  /// whose matrix would not fit in memory before allocating it (at p = 10 a
  /// node inside a tetrahedron couples with all 286 of its nodes).
  std::int64_t hessian_nonzeros() const {
    if (pattern_) return pattern_->matrix.nonZeros();  // built already: no need to count
    const int n = nodes_per_element();
    std::vector<int> seen_by(num_free_nodes(), -1);
    std::int64_t pairs = 0;
    for (int k = 0; k < num_free_nodes(); ++k)
      for (const auto& inc : incidences(free_nodes_[k]))
        for (int i = 0; i < n; ++i) {
          const int fi = free_index_[elements_(i, inc.element)];
          if (fi >= 0 && seen_by[fi] != k) {
            seen_by[fi] = k;
            ++pairs;
          }
        }
    return pairs * dim * dim;
  }

  /// Bytes the cached Hessian pattern keeps besides its matrix: every
  /// element's n x n table of positions in the matrix's columns.
  std::int64_t hessian_pattern_extra_bytes() const {
    const std::int64_t n = nodes_per_element();
    return std::int64_t(num_elements()) * n * n * std::int64_t(sizeof(int));
  }

  const Tabulation<Family>& tabulation() const { return *tab_; }
  const Measure& measure() const { return measure_; }
  const Connectivity& elements() const { return elements_; }
  const Ideal& ideal(int e) const { return ideals_[e]; }
  bool is_free(int node) const { return free_[node]; }
  /// Free node ids, ascending; free dof block k belongs to free_nodes()[k].
  const std::vector<int>& free_nodes() const { return free_nodes_; }
  /// Position of a free node in free_nodes() (precondition: is_free(node)).
  int free_index(int node) const { return free_index_[node]; }
  /// The (element, local node) pairs of a node, in element order.
  std::span<const NodeIncidence> incidences(int node) const {
    return {incidences_.data() + incidence_offsets_[node],
            std::size_t(incidence_offsets_[node + 1] - incidence_offsets_[node])};
  }

  /// The current configuration (solvers move the free columns).
  const Coordinates& coordinates() const { return x_; }
  Coordinates& coordinates() { return x_; }

  /// Whether the blocked kernels use the tabulation's sum factorization
  /// (tetrahedra, sum_factorization.hpp) where it has one; on by default. The
  /// dense products give the same results to round-off.
  void set_sum_factorization(bool on) { sum_factorization_enabled_ = on; }
  bool use_sum_factorization() const { return sum_factorization_enabled_ && tab_->sum_factorization != nullptr; }

  int threads() const { return threads_; }
  /// threads <= 0: OpenMP's default.
  void set_threads(int threads) { threads_ = detail::resolve_threads(threads); }

  // --- regularization (section 4.2.2) ------------------------------------------
  const std::vector<double>& deltas() const { return deltas_; }
  void set_deltas(std::vector<double> d) {
    if (int(d.size()) != num_elements()) throw std::invalid_argument("hom::OptimizationProblem::set_deltas: wrong size");
    deltas_ = std::move(d);
  }
  double regularization_alpha() const { return alpha_; }
  void set_regularization_alpha(double alpha) { alpha_ = alpha; }
  RegularizationScope regularization_scope() const { return scope_; }
  void set_regularization_scope(RegularizationScope scope) { scope_ = scope; }
  void set_regularization(const Regularization& r) {
    alpha_ = r.alpha;
    scope_ = r.scope;
  }
  /// delta_e = element_regularization(alpha).delta for the elements the scope
  /// names (the invalid elements of `state`, or all of them while any is
  /// invalid), 0 (sigma_0) for the others. Returns the number regularized.
  int update_regularization(const MeshState& state) {
    const double delta = element_regularization(alpha_).delta;
    const bool everywhere = scope_ == RegularizationScope::whole_mesh && !state.all_valid();
    int n = 0;
    for (int e = 0; e < num_elements(); ++e) {
      const bool regularize = everywhere || !state.valid[e];
      deltas_[e] = regularize ? delta : 0.0;
      n += regularize;
    }
    return n;
  }
  /// Calls fn(reg) with element e's regularization policy: RegularizedDeterminant
  /// when delta_e > 0, ClampedDeterminant (sigma_0) otherwise.
  template <class Fn>
  decltype(auto) with_regularization(int e, Fn&& fn) const {
    if (deltas_[e] > 0.0) return fn(RegularizedDeterminant{deltas_[e]});
    return fn(ClampedDeterminant{});
  }

  // --- free dofs <-> coordinates ----------------------------------------------
  void element_coordinates(const Coordinates& X, int e, Eigen::Matrix<double, dim, Eigen::Dynamic>& Xe) const {
    const int n = nodes_per_element();
    Xe.resize(dim, n);
    for (int i = 0; i < n; ++i) Xe.col(i) = X.col(elements_(i, e));
  }
  Eigen::VectorXd free_vector(const Coordinates& X) const {
    Eigen::VectorXd v(num_dofs());
    for (int k = 0; k < num_free_nodes(); ++k) v.template segment<dim>(dim * k) = X.col(free_nodes_[k]);
    return v;
  }
  /// X with its free nodes moved by alpha * p (p over the free dofs).
  Coordinates displaced(const Coordinates& X, const Eigen::VectorXd& p, double alpha) const {
    Coordinates Y = X;
    for (int k = 0; k < num_free_nodes(); ++k) Y.col(free_nodes_[k]) += alpha * p.template segment<dim>(dim * k);
    return Y;
  }

  // --- evaluation ----------------------------------------------------------
  /// Validity and quality of every element at X (sigma_0, independent of delta).
  MeshState status(const Coordinates& X) const {
    const int ne = num_elements();
    MeshState s;
    s.valid.assign(ne, 1);
    s.quality.assign(ne, 0.0);
    for_each_block(X, [&](int first, int count, const Eigen::MatrixXd& JP, Workspace&) {
      for (int b = 0; b < count; ++b) {
        const int e = first + b;
        const Ideal& id = ideals_[e];
        double integral = 0.0, volume = 0.0;
        bool valid = true;
        auto add = [&](int q, double eta) {
          valid = valid && std::isfinite(eta);
          integral += id.weight(q) * eta * eta;
          volume += id.weight(q);
        };
        if constexpr (BatchedMeasureFor<Measure, dim, ClampedDeterminant>)
          element_point_values_lanes(JP, b, id, ClampedDeterminant{}, add);
        else
          for (int q = 0; q < num_points() && valid; ++q)
            add(q, measure_.value(point_jacobian(JP, b, q, id), ClampedDeterminant{}));
        s.valid[e] = valid;
        s.quality[e] = valid ? 1.0 / std::sqrt(integral / volume) : 0.0;  // eqs 3.20, 3.24
      }
    });
    s.min_quality = ne > 0 ? 1.0 : 0.0;
    for (int e = 0; e < ne; ++e) {
      s.inverted += !s.valid[e];
      s.min_quality = std::min(s.min_quality, s.quality[e]);
    }
    return s;
  }

  /// f at X with the current deltas; +inf if an element with delta = 0 is invalid.
  double value(const Coordinates& X) const {
    std::vector<double> fe(num_elements());
    for_each_block(X, [&](int first, int count, const Eigen::MatrixXd& JP, Workspace&) {
      for (int b = 0; b < count; ++b) {
        const int e = first + b;
        const Ideal& id = ideals_[e];
        fe[e] = with_regularization(e, [&](const auto& reg) {
          double f = 0.0;
          auto add = [&](int q, double eta) { f += 0.5 * id.weight(q) * (eta - 1.0) * (eta - 1.0); };
          if constexpr (BatchedMeasureFor<Measure, dim, std::decay_t<decltype(reg)>>)
            element_point_values_lanes(JP, b, id, reg, add);
          else
            for (int q = 0; q < num_points(); ++q) add(q, measure_.value(point_jacobian(JP, b, q, id), reg));
          return f;
        });
      }
    });
    return sum_in_order(fe);
  }

  /// f at X and its gradient over the free dofs (g is undefined when f = +inf).
  double value_gradient(const Coordinates& X, Eigen::VectorXd& g) const {
    const int n = nodes_per_element();
    std::vector<double> fe(num_elements());
    Eigen::Matrix<double, dim, Eigen::Dynamic> Ge(dim, Eigen::Index(n) * num_elements());
    for_each_block(X, [&](int first, int count, const Eigen::MatrixXd& JP, Workspace& w) {
      w.P.resize(JP.rows(), JP.cols());
      for (int b = 0; b < count; ++b) {
        const int e = first + b;
        const Ideal& id = ideals_[e];
        fe[e] = with_regularization(e, [&](const auto& reg) {
          if constexpr (BatchedMeasureFor<Measure, dim, std::decay_t<decltype(reg)>>)
            return element_value_gradient_lanes(JP, b, id, reg, w.P);
          else
            return element_value_gradient_points(JP, b, id, reg, w.P);
        });
      }
      pull_back(w, first, count, Ge);
    });
    gather(Ge, g);
    return sum_in_order(fe);
  }

  /// s_k for each free node k: the size grad_k f would have if every
  /// eta - 1 and every d eta / dJ had size 1 (computed once). Each element e
  /// in which k is local node l contributes the root-mean-square form
  ///   sqrt( (sum_q c_q) (sum_q c_q |A_q^T grad N_l(xi_q)|^2) ),
  /// by Cauchy-Schwarz an upper bound of sum_q c_q |A_q^T grad N_l(xi_q)|
  /// (equal where the reference gradient's size is constant). The squared
  /// form costs O(n) per element for an affine ideal (A_q = A, c_q = |det| w_q):
  /// sum_q c_q |A^T g_lq|^2 = |det| (A A^T) : K_l with K_l = sum_q w_q g_lq g_lq^T
  /// shared by all elements; the plain sum of norms took 22 s at p = 10.
  const Eigen::VectorXd& gradient_scale() const {
    if (gradient_scale_.size() == num_free_nodes()) return gradient_scale_;
    const int ne = num_elements();
    const int n = nodes_per_element();
    const Tabulation<Family>& tab = *tab_;
    const int nq = tab.num_points();
    auto reference_gradient = [&](int l, int q) -> Eigen::Matrix<double, dim, 1> {
      return tab.shape_gradients.row(l).template segment<dim>(dim * q).transpose();
    };
    const Eigen::MatrixXd& K = reference_stiffness_diagonal();
    Eigen::VectorXd Se(Eigen::Index(n) * ne);
    HOM_PARALLEL_FOR(detail::useful_threads(threads_, ne, 64))
    for (int e = 0; e < ne; ++e) {
      const Ideal& id = ideals_[e];
      const double volume = std::accumulate(id.weights.begin(), id.weights.end(), 0.0);
      const bool affine = id.affine();
      const NodeMatrix S = id.inverse_jacobian(0) * id.inverse_jacobian(0).transpose();
      for (int l = 0; l < n; ++l) {
        double squares = 0.0;
        if (affine) {
          squares = id.weight(0) / tab.rule.weights[0] * K.row(l).dot(S.reshaped().transpose());
        } else {
          for (int q = 0; q < nq; ++q)
            squares += id.weight(q) * (id.inverse_jacobian(q).transpose() * reference_gradient(l, q)).squaredNorm();
        }
        Se[Eigen::Index(e) * n + l] = std::sqrt(volume * squares);
      }
    }
    const int nf = num_free_nodes();
    Eigen::VectorXd scale(nf);
    for (int k = 0; k < nf; ++k) {
      double s = 0.0;
      for (const auto& inc : incidences(free_nodes_[k])) s += Se[Eigen::Index(inc.element) * n + inc.local];
      scale[k] = s > 0.0 ? s : 1.0;
    }
    gradient_scale_ = std::move(scale);
    return gradient_scale_;
  }

  /// max_k ||grad_k f|| / s_k: the gradient as a dimensionless residual,
  /// invariant under scaling of the mesh (stopping criterion of solver.hpp).
  double scaled_gradient_norm(const Eigen::VectorXd& g) const {
    const Eigen::VectorXd& s = gradient_scale();
    double r = 0.0;
    for (int k = 0; k < num_free_nodes(); ++k) r = std::max(r, g.template segment<dim>(dim * k).norm() / s[k]);
    return r;
  }

  /// f, gradient and the Hessian over the free dofs (symmetric, full storage).
  /// Elements are assembled color by color (no two elements of a color share a
  /// node), so every matrix entry is summed in the same order on any number of threads.
  double hessian(const Coordinates& X, HessianForm form, Eigen::VectorXd& g, SparseMatrix& H) const {
    const detail::SerialEigenScope serial_eigen;
    const HessianPattern& pat = pattern();
    const int ne = num_elements();
    const int n = nodes_per_element();
    std::vector<double> fe(ne);
    Eigen::Matrix<double, dim, Eigen::Dynamic> Ge(dim, Eigen::Index(n) * ne);
    H = pat.matrix;
    double* values = H.valuePtr();
    const int* outer = H.outerIndexPtr();
    std::fill(values, values + H.nonZeros(), 0.0);
    const Tabulation<Family>& tab = *tab_;
    for (const auto& group : pat.colors.groups) {
      const int size = int(group.size());
      HOM_PARALLEL_FOR_DYNAMIC(detail::useful_threads(threads_, size, 16))
      for (int k = 0; k < size; ++k) {
        const int e = group[k];
        Eigen::Matrix<double, dim, Eigen::Dynamic> Xe;
        ElementGradient<dim> grad;
        Eigen::MatrixXd He;
        element_coordinates(X, e, Xe);
        fe[e] = with_regularization(e, [&](const auto& reg) {
          return element_objective_hessian<Family>(tab, Xe, ideals_[e], measure_, reg, grad, He, form);
        });
        Ge.middleCols(Eigen::Index(e) * n, n) = grad;
        const int* rank = pat.rank.data() + std::size_t(e) * n * n;
        for (int j = 0; j < n; ++j) {
          const int fj = free_index_[elements_(j, e)];
          if (fj < 0) continue;
          for (int i = 0; i < n; ++i) {
            const int fi = free_index_[elements_(i, e)];
            if (fi < 0) continue;
            for (int c = 0; c < dim; ++c) {
              double* col = values + outer[dim * fj + c] + dim * rank[i + n * j];
              for (int a = 0; a < dim; ++a) col[a] += He(a + dim * i, c + dim * j);
            }
          }
        }
      }
    }
    gather(Ge, g);
    return sum_in_order(fe);
  }

  /// The Hessian at a configuration as an operator on free-dof vectors, from
  /// per-quadrature-point data (Dim^2 numbers per point for Gauss-Newton,
  /// Dim^4 otherwise; see ElementHessianData), never forming element
  /// Hessians. It also holds, per free node k, the mean of the diagonal of
  /// the nodal block d^2 f / dx_k^2, trace / Dim: the scalar Jacobi
  /// preconditioner of MatrixFreeNewton. (The full Dim x Dim blocks cost Dim^2
  /// times more than a Hessian-vector product to form, the traces a fraction of one.)
  class HessianOperator {
   public:
    int size() const { return problem_ ? problem_->num_dofs() : 0; }
    HessianForm form() const { return form_; }
    /// out = H v.
    void apply(const Eigen::VectorXd& v, Eigen::VectorXd& out) const {
      const OptimizationProblem& P = *problem_;
      const int n = P.nodes_per_element();
      const int nq = P.num_points();
      const int stride = point_stride();
      Eigen::Matrix<double, dim, Eigen::Dynamic> Oe(dim, Eigen::Index(n) * P.num_elements());
      P.for_each_block_of(
          [&](int first, int count, Eigen::MatrixXd& Vb) {
            Vb.resize(dim * count, n);
            for (int i = 0; i < n; ++i)
              for (int b = 0; b < count; ++b) {
                const int fi = P.free_index_[P.elements_(i, first + b)];
                if (fi >= 0)
                  Vb.template block<dim, 1>(dim * b, i) = v.template segment<dim>(dim * fi);
                else
                  Vb.template block<dim, 1>(dim * b, i).setZero();
              }
          },
          [&](int first, int count, const Eigen::MatrixXd& dJ, Workspace& w) {
            w.P.resize(dJ.rows(), dJ.cols());
            for (int b = 0; b < count; ++b) {
              const double* data = data_.data() + (std::size_t(first + b) * nq) * stride;
              for (int q = 0; q < nq; ++q, data += stride) {
                Eigen::Matrix<double, D2, 1> s;
                for (int c = 0; c < dim; ++c) s.template segment<dim>(dim * c) = dJ.template block<dim, 1>(dim * b, dim * q + c);
                if (form_ == HessianForm::gauss_newton) {
                  const Eigen::Map<const Eigen::Matrix<double, D2, 1>> u(data);
                  s = u * u.dot(s);
                } else {
                  s = Eigen::Map<const Eigen::Matrix<double, D2, D2>>(data).lazyProduct(s).eval();  // no GEMV call for Dim^2 x Dim^2
                }
                for (int c = 0; c < dim; ++c) w.P.template block<dim, 1>(dim * b, dim * q + c) = s.template segment<dim>(dim * c);
              }
            }
            P.pull_back(w, first, count, Oe);
          });
      P.gather(Oe, out);
    }
    /// trace(d^2 f / dx_k^2) / Dim for each free node k.
    const Eigen::VectorXd& diagonal_means() const { return diagonal_; }

   private:
    friend class OptimizationProblem;
    static constexpr int D2 = dim * dim;
    int point_stride() const { return form_ == HessianForm::gauss_newton ? D2 : D2 * D2; }
    const OptimizationProblem* problem_ = nullptr;
    HessianForm form_ = HessianForm::gauss_newton;
    std::vector<double> data_;  // per element, per point: u (Gauss-Newton) or M (column-major)
    Eigen::VectorXd diagonal_;
  };

  /// f, gradient and the Hessian operator at X. Memory: per quadrature point
  /// Dim^2 numbers (Gauss-Newton) or Dim^4 (exact, projected).
  double hessian_operator(const Coordinates& X, HessianForm form, Eigen::VectorXd& g, HessianOperator& op) const {
    constexpr int D2 = dim * dim;
    const int ne = num_elements();
    const int n = nodes_per_element();
    const int nq = num_points();
    std::vector<double> fe(ne);
    Eigen::Matrix<double, dim, Eigen::Dynamic> Ge(dim, Eigen::Index(n) * ne);
    Eigen::VectorXd Te(Eigen::Index(n) * ne);  // per element and local node: trace of its diagonal block
    op.problem_ = this;
    op.form_ = form;
    const int stride = op.point_stride();
    op.data_.resize(std::size_t(ne) * nq * stride);
    // The exact traces cost a dense product with W (n x Dim^2 nq) per block, as
    // much as the dense Jacobian products; with sum factorization they are
    // approximated element by element (see averaged_traces).
    const bool averaged = use_sum_factorization();
    if (!averaged && diagonal_basis_.rows() == 0) diagonal_basis_ = diagonal_block_basis<Family>(*tab_);
    const Eigen::MatrixXd& W = diagonal_basis_;
    for_each_block(X, [&](int first, int count, const Eigen::MatrixXd& JP, Workspace& w) {
      w.P.resize(JP.rows(), JP.cols());
      w.T.resize(D2 * nq, count);  // per element: sum_a M_q(a + D b, a + D d), the trace part of each point matrix
      for (int b = 0; b < count; ++b) {
        const int e = first + b;
        const Ideal& id = ideals_[e];
        double* data = op.data_.data() + (std::size_t(e) * nq) * stride;
        fe[e] = with_regularization(e, [&](const auto& reg) {
          double f = 0.0;
          for (int q = 0; q < nq; ++q, data += stride) {
            const NodeMatrix& A = id.inverse_jacobian(q);
            const double c = id.weight(q);
            const NodeMatrix J = point_jacobian(JP, b, q, id);
            const auto pd = point_second_order(J, A, c, reg, form, data);
            f += 0.5 * c * pd.residual * pd.residual;
            w.P.template block<dim, dim>(dim * b, dim * q).noalias() = (c * pd.residual) * pd.gradient;
            for (int d = 0; d < dim; ++d)
              for (int bb = 0; bb < dim; ++bb) {
                double t = 0.0;
                if (form == HessianForm::gauss_newton)
                  for (int a = 0; a < dim; ++a) t += data[a + dim * bb] * data[a + dim * d];
                else
                  for (int a = 0; a < dim; ++a) t += data[(a + dim * bb) + D2 * (a + dim * d)];
                w.T(q * D2 + bb + dim * d, b) = t;
              }
          }
          return f;
        });
      }
      pull_back(w, first, count, Ge);
      const Eigen::MatrixXd traces = averaged ? averaged_traces(w.T, count) : Eigen::MatrixXd(W * w.T.leftCols(count));  // n x count
      for (int b = 0; b < count; ++b) Te.segment(Eigen::Index(first + b) * n, n) = traces.col(b);
    });
    gather(Ge, g);
    const int nf = num_free_nodes();
    op.diagonal_.setZero(nf);
    HOM_PARALLEL_FOR(detail::useful_threads(threads_, nf, 4096))
    for (int k = 0; k < nf; ++k) {
      double t = 0.0;
      for (const auto& inc : incidences(free_nodes_[k])) t += Te[Eigen::Index(inc.element) * n + inc.local];
      op.diagonal_[k] = t / dim;
    }
    return sum_in_order(fe);
  }

  /// out = H(X) v for the given form (builds a HessianOperator; for repeated
  /// products build the operator once).
  void hessian_vector_product(const Coordinates& X, HessianForm form, const Eigen::VectorXd& v, Eigen::VectorXd& out) const {
    HessianOperator op;
    Eigen::VectorXd g;
    hessian_operator(X, form, g, op);
    op.apply(v, out);
  }

  /// Free nodes colored so that no element contains two nodes of one color
  /// (greedy first fit in ascending node order): nodes of one color can move
  /// concurrently in a Gauss-Seidel sweep (appendix B).
  Coloring free_node_coloring() const {
    const int n = nodes_per_element();
    std::vector<int> color(num_nodes(), -1);
    std::vector<int> stamp;
    Coloring out;
    for (int node : free_nodes_) {
      for (const auto& inc : incidences(node))
        for (int i = 0; i < n; ++i) {
          const int c = color[elements_(i, inc.element)];
          if (c >= 0) stamp[c] = node + 1;
        }
      int c = 0;
      while (c < int(stamp.size()) && stamp[c] == node + 1) ++c;
      if (c == int(stamp.size())) {
        stamp.push_back(0);
        out.groups.emplace_back();
      }
      color[node] = c;
      out.groups[c].push_back(node);
    }
    return out;
  }

 private:
  struct HessianPattern {
    SparseMatrix matrix;  ///< structure with zero values
    /// Per element, n x n (column-major, (i, j) at i + n j): offset of free
    /// node i's rows inside the columns of free node j, divided by Dim.
    std::vector<int> rank;
    Coloring colors;  ///< elements, no two of a color sharing a node
  };

  // --- blocked evaluation ----------------------------------------------------
  // Elements are evaluated in blocks of block_size() consecutive elements:
  // the block's coordinates are stacked into Xb ((Dim * count) x n, rows
  // Dim b .. Dim b + Dim - 1 for its b-th element) and all their Jacobians at
  // all quadrature points come from one matrix product with the shared
  // tabulation, JP = Xb * G ((Dim * count) x (Dim * nq)); gradients go back
  // the same way, out = P * G^T. A product per block instead of per element
  // reads G (n x Dim nq: 9 MB for a degree-10 tetrahedron) once per block and
  // runs at dense matrix-product speed. Blocks are fixed by element index and
  // each is computed by one thread, so results do not depend on the number of threads.
  struct Workspace {
    Eigen::MatrixXd Xb, JP, P, T, out;
    TetrahedronSumFactorization::Workspace sum_factorization;
  };

  int num_points() const { return tab_->num_points(); }

  /// Elements per block of the blocked kernels (dense products): up to 128, fewer for large
  /// elements (the block's products JP = Xb G take Dim x block x Dim n_q
  /// numbers). Large blocks amortize the packing of the shared tabulation G
  /// that every product repeats (13% of the time at p = 10 with 57-element blocks).
  int block_size() const {
    // Sum factorization has no shared matrix to amortize, and small blocks keep
    // JP and P (Dim x block x Dim n_q) in cache for the point loops: 8 elements
    // were 10-20% faster than 128 at p = 10 (bench_kernel, one thread).
    if (use_sum_factorization()) return 8;
    return std::clamp(65536 / std::max(1, nodes_per_element()), 16, 128);
  }

  static NodeMatrix point_jacobian(const Eigen::MatrixXd& JP, int b, int q, const Ideal& id) {
    return JP.template block<dim, dim>(dim * b, dim * q) * id.inverse_jacobian(q);
  }

  /// Calls fn(first, count, JP, workspace) for every block, JP = Xb * G with
  /// Xb filled by rows(first, count, Xb).
  template <class Rows, class Fn>
  void for_each_block_of(Rows&& rows, Fn&& fn) const {
    const detail::SerialEigenScope serial_eigen;
    const int ne = num_elements();
    const int B = block_size();
    const int blocks = (ne + B - 1) / B;
    const Eigen::MatrixXd& G = tab_->shape_gradients;
    // About 2e5 multiply-adds of the products per thread at least.
    const long long work = (long long)ne * num_points() * nodes_per_element();
    HOM_PARALLEL_FOR_EACH(std::min(detail::useful_threads(threads_, work, 200000), blocks))
    for (int k = 0; k < blocks; ++k) {
      static thread_local Workspace w;
      const int first = k * B;
      const int count = std::min(B, ne - first);
      rows(first, count, w.Xb);
      if (use_sum_factorization())
        tab_->sum_factorization->gradients(w.Xb, w.JP, w.sum_factorization);
      else
        w.JP.noalias() = w.Xb * G;
      fn(first, count, w.JP, w);
    }
  }

  template <class Fn>
  void for_each_block(const Coordinates& X, Fn&& fn) const {
    const int n = nodes_per_element();
    for_each_block_of(
        [&](int first, int count, Eigen::MatrixXd& Xb) {
          Xb.resize(dim * count, n);
          for (int i = 0; i < n; ++i)
            for (int b = 0; b < count; ++b) Xb.template block<dim, 1>(dim * b, i) = X.col(elements_(i, first + b));
        },
        fn);
  }

  // --- the point loops on detail::point_lanes points at a time ---------------
  // (the measure's value_lanes / value_gradient_lanes, point_lanes.hpp). A
  // batch past an element's last point is padded with that point; padded
  // lanes are neither summed nor stored.
  static constexpr int lanes = detail::point_lanes;
  using LaneMatrix = double[dim * dim][lanes];

  /// A_q of the points q0 .. q0 + lanes - 1 (column-major entries in rows).
  void load_ideal_lanes(const Ideal& id, int q0, LaneMatrix& A) const {
    for (int l = 0; l < lanes; ++l) {
      const NodeMatrix& Aq = id.inverse_jacobian(std::min(q0 + l, num_points() - 1));
      for (int i = 0; i < dim * dim; ++i) A[i][l] = Aq.data()[i];
    }
  }

  /// J_q = JP_q A_q of element b of a block at the points q0 .. (JP_q: rows
  /// dim b .., columns dim q ..).
  void load_jacobian_lanes(const Eigen::MatrixXd& JP, int b, int q0, const LaneMatrix& A, LaneMatrix& J) const {
    const Eigen::Index rows = JP.rows();
    LaneMatrix JPq;
    for (int l = 0; l < lanes; ++l) {
      const double* col = JP.data() + dim * b + rows * dim * std::min(q0 + l, num_points() - 1);
      for (int j = 0; j < dim; ++j)
        for (int i = 0; i < dim; ++i) JPq[i + dim * j][l] = col[i + rows * j];
    }
    for (int j = 0; j < dim; ++j)
      for (int i = 0; i < dim; ++i) {
        HOM_LANES
        for (int l = 0; l < lanes; ++l) J[i + dim * j][l] = 0.0;
        for (int k = 0; k < dim; ++k) {
          HOM_LANES
          for (int l = 0; l < lanes; ++l) J[i + dim * j][l] += JPq[i + dim * k][l] * A[k + dim * j][l];
        }
      }
  }

  /// Calls fn(q, eta_q) for every point of element b of a block.
  template <class Reg, class Fn>
  void element_point_values_lanes(const Eigen::MatrixXd& JP, int b, const Ideal& id, const Reg& reg, Fn&& fn) const {
    const int nq = num_points();
    LaneMatrix A, J;
    double eta[lanes];
    if (id.affine()) load_ideal_lanes(id, 0, A);
    for (int q0 = 0; q0 < nq; q0 += lanes) {
      if (!id.affine()) load_ideal_lanes(id, q0, A);
      load_jacobian_lanes(JP, b, q0, A, J);
      measure_.template value_lanes<dim, lanes>(J, reg, eta);
      for (int l = 0; l < std::min(lanes, nq - q0); ++l) fn(q0 + l, eta[l]);
    }
  }

  /// value_gradient's point loop for element b of a block, one point at a
  /// time (measures without value_gradient_lanes): as element_value_gradient_lanes.
  template <class Reg>
  double element_value_gradient_points(const Eigen::MatrixXd& JP, int b, const Ideal& id, const Reg& reg,
                                       Eigen::MatrixXd& P) const {
    double f = 0.0;
    for (int q = 0; q < num_points(); ++q) {
      const NodeMatrix& A = id.inverse_jacobian(q);
      NodeMatrix gq;
      const double eta = measure_.value_gradient(point_jacobian(JP, b, q, id), reg, gq);
      const double r = eta - 1.0;
      f += 0.5 * id.weight(q) * r * r;
      P.template block<dim, dim>(dim * b, dim * q).noalias() = (id.weight(q) * r) * gq * A.transpose();
    }
    return f;
  }

  /// value_gradient's point loop for element b of a block: writes
  /// P_q = c_q (eta_q - 1) (d eta / dJ)_q A_q^T into P's block (dim b, dim q)
  /// and returns f_e = sum_q c_q (eta_q - 1)^2 / 2 (+inf when an eta_q is).
  template <class Reg>
  double element_value_gradient_lanes(const Eigen::MatrixXd& JP, int b, const Ideal& id, const Reg& reg,
                                      Eigen::MatrixXd& P) const {
    constexpr int D = dim;
    const int nq = num_points();
    const Eigen::Index rows = P.rows();
    LaneMatrix A, J, grad, Pq;
    double eta[lanes], c[lanes], fq[lanes];
    if (id.affine()) load_ideal_lanes(id, 0, A);
    double f = 0.0;
    for (int q0 = 0; q0 < nq; q0 += lanes) {
      const int m = std::min(lanes, nq - q0);
      if (!id.affine()) load_ideal_lanes(id, q0, A);
      load_jacobian_lanes(JP, b, q0, A, J);
      measure_.template value_gradient_lanes<D, lanes>(J, reg, grad, eta);
      for (int l = 0; l < lanes; ++l) c[l] = id.weight(std::min(q0 + l, nq - 1));
      HOM_LANES
      for (int l = 0; l < lanes; ++l) {
        fq[l] = 0.5 * c[l] * (eta[l] - 1.0) * (eta[l] - 1.0);
        c[l] *= eta[l] - 1.0;  // c_q r_q
      }
      for (int j = 0; j < D; ++j)  // P_q = c_q r_q grad_q A_q^T
        for (int i = 0; i < D; ++i) {
          HOM_LANES
          for (int l = 0; l < lanes; ++l) Pq[i + D * j][l] = 0.0;
          for (int k = 0; k < D; ++k) {
            HOM_LANES
            for (int l = 0; l < lanes; ++l) Pq[i + D * j][l] += c[l] * grad[i + D * k][l] * A[j + D * k][l];
          }
        }
      for (int l = 0; l < m; ++l) {
        f += fq[l];
        double* col = P.data() + D * b + rows * D * (q0 + l);
        for (int j = 0; j < D; ++j)
          for (int i = 0; i < D; ++i) col[i + rows * j] = Pq[i + D * j][l];
      }
    }
    return f;
  }

  /// Ge's columns of the block's elements = w.P * G^T (element b's rows Dim b ..).
  void pull_back(Workspace& w, int first, int count, Eigen::Matrix<double, dim, Eigen::Dynamic>& Ge) const {
    const int n = nodes_per_element();
    if (use_sum_factorization())
      tab_->sum_factorization->gradients_transpose(w.P, w.out, w.sum_factorization);
    else
      w.out.noalias() = w.P * tab_->shape_gradients.transpose();
    for (int b = 0; b < count; ++b)
      for (int i = 0; i < n; ++i) Ge.col(Eigen::Index(first + b) * n + i) = w.out.template block<dim, 1>(dim * b, i);
  }

  /// A point's residual eta - 1 and d eta / d J_P, its second-order data written to `data`.
  template <class Reg>
  PointSecondOrder<dim> point_second_order(const NodeMatrix& J, const NodeMatrix& A, double c, const Reg& reg,
                                           HessianForm form, double* data) const {
    return hom::point_second_order<dim>(measure_, reg, J, A, c, form, data);
  }

  /// n x Dim^2, row l = vec(K_l), K_l = sum_q w_q grad N_l(xi_q) grad N_l(xi_q)^T
  /// (reference rule weights): the diagonal blocks of the reference element's
  /// stiffness matrix. Computed on first use.
  const Eigen::MatrixXd& reference_stiffness_diagonal() const {
    if (stiffness_diagonal_.rows() == 0) {
      const Tabulation<Family>& tab = *tab_;
      const int n = nodes_per_element();
      Eigen::MatrixXd K = Eigen::MatrixXd::Zero(n, dim * dim);
      for (int q = 0; q < tab.num_points(); ++q)
        for (int l = 0; l < n; ++l) {
          const Eigen::Matrix<double, dim, 1> g = tab.shape_gradients.row(l).template segment<dim>(dim * q).transpose();
          K.row(l) += tab.rule.weights[q] * (g * g.transpose()).reshaped().transpose();
        }
      stiffness_diagonal_ = std::move(K);
    }
    return stiffness_diagonal_;
  }

  /// The nodal traces of the preconditioner with each element's point matrices
  /// T_q (columns of T, Dim^2 per point, weights c_q included) replaced by
  /// w_q T-bar, T-bar = sum_q T_q / sum_q w_q: t_l = K_l : T-bar, exact where
  /// T_q / w_q is constant over the element. O(n) instead of O(n nq) per element.
  Eigen::MatrixXd averaged_traces(const Eigen::MatrixXd& T, int count) const {
    constexpr int D2 = dim * dim;
    const int nq = num_points();
    const double reference_volume = std::accumulate(tab_->rule.weights.begin(), tab_->rule.weights.end(), 0.0);
    Eigen::MatrixXd Tbar(D2, count);
    for (int b = 0; b < count; ++b)
      Tbar.col(b) = Eigen::Map<const Eigen::Matrix<double, D2, Eigen::Dynamic>>(T.col(b).data(), D2, nq).rowwise().sum() /
                    reference_volume;
    return reference_stiffness_diagonal() * Tbar;
  }

  static double sum_in_order(const std::vector<double>& v) {
    double s = 0.0;
    for (double x : v) s += x;
    return s;
  }

  // g[k] = sum over the incidences of free node k (element order) of the
  // element contributions stored at column e * n + local of Ge.
  void gather(const Eigen::Matrix<double, dim, Eigen::Dynamic>& Ge, Eigen::VectorXd& g) const {
    const int n = nodes_per_element();
    const int nf = num_free_nodes();
    g.setZero(num_dofs());
    HOM_PARALLEL_FOR(detail::useful_threads(threads_, nf, 4096))
    for (int k = 0; k < nf; ++k) {
      Eigen::Matrix<double, dim, 1> s = Eigen::Matrix<double, dim, 1>::Zero();
      for (const auto& inc : incidences(free_nodes_[k])) s += Ge.col(Eigen::Index(inc.element) * n + inc.local);
      g.template segment<dim>(dim * k) = s;
    }
  }

  void build_incidences() {
    const int nn = num_nodes();
    const int n = nodes_per_element();
    incidence_offsets_.assign(nn + 1, 0);
    for (Eigen::Index e = 0; e < elements_.cols(); ++e)
      for (int i = 0; i < n; ++i) ++incidence_offsets_[elements_(i, e) + 1];
    for (int k = 0; k < nn; ++k) incidence_offsets_[k + 1] += incidence_offsets_[k];
    incidences_.resize(incidence_offsets_[nn]);
    std::vector<int> fill(incidence_offsets_.begin(), incidence_offsets_.end() - 1);
    for (int e = 0; e < int(elements_.cols()); ++e)
      for (int i = 0; i < n; ++i) incidences_[fill[elements_(i, e)]++] = {e, i};
  }

  const HessianPattern& pattern() const {
    if (pattern_) return *pattern_;
    auto pat = std::make_unique<HessianPattern>();
    const int n = nodes_per_element();
    const int nf = num_free_nodes();
    // Free neighbours of every free node (nodes sharing an element), ascending.
    std::vector<std::vector<int>> nbr(nf);
    for (int k = 0; k < nf; ++k) {
      auto& list = nbr[k];
      for (const auto& inc : incidences(free_nodes_[k]))
        for (int i = 0; i < n; ++i) {
          const int fi = free_index_[elements_(i, inc.element)];
          if (fi >= 0) list.push_back(fi);
        }
      std::sort(list.begin(), list.end());
      list.erase(std::unique(list.begin(), list.end()), list.end());
    }
    SparseMatrix& M = pat->matrix;
    M.resize(num_dofs(), num_dofs());
    Eigen::VectorXi sizes(num_dofs());
    for (int k = 0; k < nf; ++k)
      for (int c = 0; c < dim; ++c) sizes[dim * k + c] = dim * int(nbr[k].size());
    M.reserve(sizes);
    for (int k = 0; k < nf; ++k)
      for (int c = 0; c < dim; ++c)
        for (int fi : nbr[k])
          for (int a = 0; a < dim; ++a) M.insert(dim * fi + a, dim * k + c) = 0.0;
    M.makeCompressed();
    pat->rank.assign(std::size_t(num_elements()) * n * n, -1);
    for (int e = 0; e < num_elements(); ++e)
      for (int j = 0; j < n; ++j) {
        const int fj = free_index_[elements_(j, e)];
        if (fj < 0) continue;
        for (int i = 0; i < n; ++i) {
          const int fi = free_index_[elements_(i, e)];
          if (fi < 0) continue;
          const auto it = std::lower_bound(nbr[fj].begin(), nbr[fj].end(), fi);
          pat->rank[std::size_t(e) * n * n + i + n * j] = int(it - nbr[fj].begin());
        }
      }
    // Element coloring: greedy first fit in element order.
    std::vector<int> color(num_elements(), -1);
    std::vector<int> stamp;
    for (int e = 0; e < num_elements(); ++e) {
      for (int i = 0; i < n; ++i)
        for (const auto& inc : incidences(elements_(i, e)))
          if (color[inc.element] >= 0) stamp[color[inc.element]] = e + 1;
      int c = 0;
      while (c < int(stamp.size()) && stamp[c] == e + 1) ++c;
      if (c == int(stamp.size())) {
        stamp.push_back(0);
        pat->colors.groups.emplace_back();
      }
      color[e] = c;
      pat->colors.groups[c].push_back(e);
    }
    pattern_ = std::move(pat);
    return *pattern_;
  }

  const Tabulation<Family>* tab_;
  bool sum_factorization_enabled_ = true;
  Coordinates x_;
  Connectivity elements_;
  std::vector<bool> free_;
  std::vector<Ideal> ideals_;
  Measure measure_;
  int threads_ = 1;
  double alpha_ = thesis_regularization_alpha;
  RegularizationScope scope_ = RegularizationScope::invalid_elements;
  std::vector<double> deltas_;
  std::vector<int> free_nodes_;
  std::vector<int> free_index_;  // -1 for fixed nodes (internal)
  std::vector<int> incidence_offsets_;
  std::vector<NodeIncidence> incidences_;
  mutable std::unique_ptr<HessianPattern> pattern_;
  mutable Eigen::VectorXd gradient_scale_;
  mutable Eigen::MatrixXd diagonal_basis_;  // diagonal_block_basis(tab), on first use
  mutable Eigen::MatrixXd stiffness_diagonal_;  // reference_stiffness_diagonal(), on first use
};

}  // namespace hom
