#pragma once
/// @file lagrange.hpp
/// Nodal (Lagrange) shape functions N_j of degree p at a node set: the basis
/// of the representation map phi_P(xi) = sum_j x_j N_j(xi) (eq A.1, E.1),
/// with N_j(xi_i) = delta_ij and sum_j N_j = 1.
///
/// Built through the orthonormal basis psi (orthonormal.hpp): with the
/// Vandermonde matrix V(i, m) = psi_m(xi_i) at the nodes,
///
///   N(x) = V^{-T} psi(x),   grad N_j(x) = V^{-T} grad psi(x),
///
/// so evaluating at a point is one solve with the LU factors of V^T, computed
/// once at construction. On cubes whose nodes form a tensor grid (equispaced,
/// Gauss-Lobatto, warp & blend) the same polynomials are evaluated as products
/// of 1D Lagrange polynomials instead, O(n) per point rather than O(n^2);
/// `tensor_product()` says which path a basis takes. Going through an orthonormal basis (instead of
/// monomials) keeps V well conditioned: for warp & blend nodes its 2-norm
/// condition number stays in the hundreds at p = 10 (hom_reference_report),
/// and interpolation is accurate to round-off far beyond that.
///
/// Thread safety: a constructed basis is immutable; all methods are const and
/// may run concurrently. `lagrange_basis<F, N>(p)` shares one instance per
/// (family, node set, degree).

#include <array>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>
#include <Eigen/SVD>

#include "hom/basis/orthonormal.hpp"
#include "hom/basis/vandermonde.hpp"
#include "hom/element/family.hpp"
#include "hom/element/node_layout.hpp"
#include "hom/nodes/node_set.hpp"
#include "hom/nodes/warp_blend.hpp"

namespace hom {

template <ElementFamily Family, NodeSet Nodes = WarpBlend>
class LagrangeBasis {
 public:
  static constexpr int dim = Family::dim;
  using Point = typename Family::Point;
  using Modal = OrthonormalBasis<Family>;

  explicit LagrangeBasis(int p) : degree_(p) {
    if (p < 1) throw std::invalid_argument("hom::LagrangeBasis: degree must be >= 1, got " + std::to_string(p));
    nodes_ = Nodes::template points<Family>(p);
    if (int(nodes_.size()) != Family::num_nodes(p))
      throw std::logic_error("hom::LagrangeBasis: node set returned the wrong number of nodes");
    if constexpr (!Family::is_simplex) tensor_ = detect_tensor();
    if (!tensor_) lu_t_.compute(vandermonde<Family>(p, nodes_).transpose());
  }

  int degree() const { return degree_; }
  int size() const { return static_cast<int>(nodes_.size()); }
  const std::vector<Point>& nodes() const { return nodes_; }

  /// Whether the nodes form a tensor grid (cubes with equispaced or GLL nodes),
  /// in which case values and gradients use the 1D Lagrange polynomials.
  bool tensor_product() const { return tensor_; }

  /// V(i, m) = psi_m(xi_i) at the nodes (built on each call).
  Eigen::MatrixXd vandermonde_matrix() const { return vandermonde<Family>(degree_, nodes_); }

  /// #x by n: N_j(x_i).
  Eigen::MatrixXd values(const std::vector<Point>& x) const {
    const auto nx = static_cast<Eigen::Index>(x.size());
    if (tensor_) {
      Eigen::MatrixXd out(size(), nx);  // filled by columns, transposed at the end
      Axes1D ax;
      for (Eigen::Index i = 0; i < nx; ++i) {
        tabulate_axes<false>(x[i], ax);
        tensor_values(ax, out.col(i));
      }
      return out.transpose();
    }
    Eigen::MatrixXd psi(size(), nx);
    for (Eigen::Index i = 0; i < nx; ++i) Modal::evaluate(degree_, x[i], psi.col(i));
    return lu_t_.solve(psi).transpose();
  }

  /// [k](i, j) = d N_j / d xi_k at x_i, each #x by n.
  std::array<Eigen::MatrixXd, dim> gradients(const std::vector<Point>& x) const {
    const int n = size();
    const auto nx = static_cast<Eigen::Index>(x.size());
    // All Dim derivatives of all points as one block of columns.
    Eigen::MatrixXd dn(n, dim * nx);
    if (tensor_) {
      Axes1D ax;
      Eigen::Matrix<double, Eigen::Dynamic, dim> g(n, dim);
      for (Eigen::Index i = 0; i < nx; ++i) {
        tabulate_axes<true>(x[i], ax);
        tensor_gradient(ax, g);
        for (int k = 0; k < dim; ++k) dn.col(k * nx + i) = g.col(k);
      }
    } else {
      typename Modal::Gradient g(n, dim);
      for (Eigen::Index i = 0; i < nx; ++i) {
        Modal::gradient(degree_, x[i], g);
        for (int k = 0; k < dim; ++k) dn.col(k * nx + i) = g.col(k);
      }
      dn = lu_t_.solve(dn);
    }
    std::array<Eigen::MatrixXd, dim> out;
    for (int k = 0; k < dim; ++k) out[k] = dn.middleCols(k * nx, nx).transpose();
    return out;
  }

  /// N_j(x), j = 0..n-1.
  Eigen::VectorXd value(const Point& x) const {
    Eigen::VectorXd v(size());
    if (tensor_) {
      Axes1D ax;
      tabulate_axes<false>(x, ax);
      tensor_values(ax, v);
      return v;
    }
    Modal::evaluate(degree_, x, v);
    return lu_t_.solve(v);
  }

  /// (j, k) = d N_j / d xi_k at x.
  Eigen::Matrix<double, Eigen::Dynamic, dim> gradient(const Point& x) const {
    Eigen::Matrix<double, Eigen::Dynamic, dim> g(size(), dim);
    if (tensor_) {
      Axes1D ax;
      tabulate_axes<true>(x, ax);
      tensor_gradient(ax, g);
      return g;
    }
    Modal::gradient(degree_, x, g);
    return lu_t_.solve(g);
  }

  /// 2-norm condition number of the nodal Vandermonde matrix, sigma_max /
  /// sigma_min (singular values only; JacobiSVD up to 128 nodes, the much
  /// faster divide-and-conquer BDCSVD beyond: 0.1 s instead of 1 s at n = 343).
  /// Computed on each call.
  double vandermonde_condition() const {
    const Eigen::MatrixXd v = vandermonde_matrix();
    Eigen::VectorXd s;
    if (size() <= 128)
      s = Eigen::JacobiSVD<Eigen::MatrixXd>(v).singularValues();
    else
      s = Eigen::BDCSVD<Eigen::MatrixXd>(v).singularValues();
    return s[0] / s[s.size() - 1];
  }

 private:
  // Tensor grids: node j with lattice index l is (r_0[l_0], ..., r_{D-1}[l_{D-1}])
  // and N_j(x) = prod_d L^d_{l_d}(x_d), the 1D Lagrange polynomials of the
  // points r_d. This is the same polynomial as V^{-T} psi (the interpolant in
  // Q_p is unique) at O(n) instead of O(n^2) cost per point, which matters on
  // hexahedra (n = 1331 at p = 10).
  struct Axes1D {
    std::array<Eigen::VectorXd, dim> l, dl;
  };

  bool detect_tensor() {
    const auto& layout = node_layout<Family>(degree_);
    const int p = degree_;
    for (int d = 0; d < dim; ++d) {
      r_[d].resize(p + 1);
      Lattice<dim> l{};
      for (int k = 0; k <= p; ++k) {
        l[d] = k;
        r_[d][k] = nodes_[layout.index_of(l)][d];
      }
    }
    lattice_.resize(size());
    for (int j = 0; j < size(); ++j) {
      lattice_[j] = layout.lattice(j);
      for (int d = 0; d < dim; ++d)
        if (nodes_[j][d] != r_[d][lattice_[j][d]]) return false;
    }
    for (int d = 0; d < dim; ++d) {
      den_[d].resize(p + 1);
      for (int k = 0; k <= p; ++k) {
        double den = 1.0;
        for (int m = 0; m <= p; ++m)
          if (m != k) den *= r_[d][k] - r_[d][m];
        den_[d][k] = 1.0 / den;
      }
    }
    return true;
  }

  // 1D Lagrange polynomials (and derivatives) of each axis at x, by products
  // (exact at the nodes; the product rule accumulates the derivative).
  template <bool WithDerivative>
  void tabulate_axes(const Point& x, Axes1D& ax) const {
    const int p = degree_;
    for (int d = 0; d < dim; ++d) {
      ax.l[d].resize(p + 1);
      if constexpr (WithDerivative) ax.dl[d].resize(p + 1);
      for (int k = 0; k <= p; ++k) {
        double prod = 1.0, dprod = 0.0;
        for (int m = 0; m <= p; ++m) {
          if (m == k) continue;
          const double a = x[d] - r_[d][m];
          if constexpr (WithDerivative) dprod = dprod * a + prod;
          prod *= a;
        }
        ax.l[d][k] = prod * den_[d][k];
        if constexpr (WithDerivative) ax.dl[d][k] = dprod * den_[d][k];
      }
    }
  }

  template <class Out>
  void tensor_values(const Axes1D& ax, Out&& out) const {
    for (int j = 0; j < size(); ++j) {
      double v = 1.0;
      for (int d = 0; d < dim; ++d) v *= ax.l[d][lattice_[j][d]];
      out[j] = v;
    }
  }

  void tensor_gradient(const Axes1D& ax, Eigen::Matrix<double, Eigen::Dynamic, dim>& g) const {
    for (int j = 0; j < size(); ++j)
      for (int k = 0; k < dim; ++k) {
        double v = 1.0;
        for (int d = 0; d < dim; ++d) v *= d == k ? ax.dl[d][lattice_[j][d]] : ax.l[d][lattice_[j][d]];
        g(j, k) = v;
      }
  }

  int degree_;
  std::vector<Point> nodes_;
  bool tensor_ = false;
  std::array<Eigen::VectorXd, dim> r_, den_;   // tensor grids: 1D points, 1 / prod (r_k - r_m)
  std::vector<Lattice<dim>> lattice_;          // tensor grids: lattice index of each node
  Eigen::PartialPivLU<Eigen::MatrixXd> lu_t_;  // otherwise: LU of V^T
};

/// The Lagrange basis of degree p on (F, N), built once and shared; safe to
/// call from several threads. The reference stays valid for the program's life.
template <ElementFamily F, NodeSet N = WarpBlend>
const LagrangeBasis<F, N>& lagrange_basis(int p) {
  static std::mutex mutex;
  static std::map<int, std::unique_ptr<LagrangeBasis<F, N>>> cache;
  const std::lock_guard<std::mutex> lock(mutex);
  auto& slot = cache[p];
  if (!slot) slot = std::make_unique<LagrangeBasis<F, N>>(p);
  return *slot;
}

}  // namespace hom
