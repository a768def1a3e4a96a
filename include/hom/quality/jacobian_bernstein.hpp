#pragma once
/// @file jacobian_bernstein.hpp
/// The Jacobian determinant det D phi_P of a degree-p element as one
/// polynomial in Bernstein form, exactly (up to round-off), for bounding it
/// over the whole element (quality/certify.hpp).
///
/// Degrees. Each entry d x_i / d xi_k of D phi_P (eq A.1) has degree p - 1 on
/// a simplex; det is a sum of products of Dim entries, so it has total degree
/// Dim (p - 1). On a cube, d x_i / d xi_k has degree p - 1 along axis k and p
/// along the others; a term of det takes one entry from each column k, so
/// along every axis it has degree (p - 1) + (Dim - 1) p = Dim p - 1: a tensor
/// polynomial of degree Dim p - 1 per axis (for p = 10: 4060 coefficients on a
/// tetrahedron, 30^3 = 27000 on a hexahedron).
///
/// Construction (no interpolation system at the det's degree, whose
/// conditioning would grow with Dim p): the node coordinates go to Bernstein
/// form once (LagrangeToBernstein, tabulated per (family, node set, p)),
/// derivatives are exact differences of coefficients, and det is assembled
/// from exact Bernstein products in scaled (monomial-weight) form,
///     2D: det = J00 J11 - J01 J10,
///     3D: det = sum_k J(0, k) C(0, k),  C(0, k) = J(1, a) J(2, b) - J(1, b) J(2, a), (k, a, b) cyclic,
/// with one division by the weights at the end. The coordinates are taken
/// relative to the element's first vertex (det is translation invariant), so
/// far-from-origin meshes lose no digits.

#include <array>
#include <map>
#include <memory>
#include <mutex>
#include <vector>

#include <Eigen/Core>

#include "hom/basis/bernstein.hpp"
#include "hom/element/family.hpp"
#include "hom/nodes/node_set.hpp"

namespace hom {

/// Degree of det D phi_P for degree-p elements of Family.
template <ElementFamily Family>
BernsteinDegree<Family> jacobian_determinant_degree(int p) {
  return detail::uniform_degree<Family>(Family::is_simplex ? Family::dim * (p - 1) : Family::dim * p - 1);
}

/// Tables for (Family, node set, p): det D phi_P's Bernstein coefficients of
/// an element from its node coordinates. Immutable once built; thread-safe.
template <ElementFamily Family>
class JacobianBernstein {
 public:
  static constexpr int dim = Family::dim;
  using Nodes = Eigen::Matrix<double, dim, Eigen::Dynamic>;

  template <NodeSet NodeSetT>
  static JacobianBernstein build(int p) {
    JacobianBernstein t;
    t.degree_ = p;
    t.to_bernstein_ = &lagrange_to_bernstein<Family, NodeSetT>(p);
    const auto& sp = bernstein_space<Family>(p);
    t.det_ = &bernstein_space<Family>(jacobian_determinant_degree<Family>(p));
    for (int k = 0; k < dim; ++k) t.column_[k] = &bernstein_space<Family>(derivative_degree<Family>(sp.degree(), k));
    if constexpr (dim == 2) {
      t.det_offsets_[0] = t.det_->box_offsets(*t.column_[0]);
      t.det_offsets_[1] = t.det_->box_offsets(*t.column_[1]);
    } else {
      for (int k = 0; k < 3; ++k) {
        const int a = (k + 1) % 3, b = (k + 2) % 3;
        t.cofactor_[k] = &bernstein_space<Family>(product_degree<Family>(t.column_[a]->degree(), t.column_[b]->degree()));
        t.cof_offsets_[k][0] = t.cofactor_[k]->box_offsets(*t.column_[a]);
        t.cof_offsets_[k][1] = t.cofactor_[k]->box_offsets(*t.column_[b]);
        t.det_offsets_[k] = t.det_->box_offsets(*t.column_[k]);
        t.det_cof_offsets_[k] = t.det_->box_offsets(*t.cofactor_[k]);
      }
    }
    return t;
  }

  int degree() const { return degree_; }
  /// The Bernstein space of det D phi_P.
  const BernsteinSpace<Family>& space() const { return *det_; }

  /// Bernstein coefficients of det D phi_P of the element with node
  /// coordinates X (Dim x n_p, hom's layout order), compact order of space().
  Eigen::VectorXd coefficients(const Eigen::Ref<const Nodes>& X) const {
    const Nodes Xc = X.colwise() - X.col(0);
    const Eigen::MatrixXd P = to_bernstein_->apply(Xc);
    const auto& sp = to_bernstein_->space();
    // Scaled Bernstein coefficients of column k of D phi_P: dim rows.
    std::array<Eigen::MatrixXd, dim> G;
    for (int k = 0; k < dim; ++k) {
      G[k].resize(dim, column_[k]->size());
      for (int i = 0; i < dim; ++i) {
        const Eigen::VectorXd d = bernstein_derivative(sp, P.row(i).transpose(), k);
        G[k].row(i) = detail::scale(*column_[k], d).transpose();
      }
    }
    std::vector<double> box(det_->box_size(), 0.0);
    auto row = [](const Eigen::MatrixXd& m, int i) {
      return Eigen::VectorXd(m.row(i).transpose());
    };
    if constexpr (dim == 2) {
      const Eigen::VectorXd j00 = row(G[0], 0), j10 = row(G[0], 1), j01 = row(G[1], 0), j11 = row(G[1], 1);
      detail::scaled_convolve(j00.data(), det_offsets_[0], j11.data(), det_offsets_[1], 1.0, box.data());
      detail::scaled_convolve(j10.data(), det_offsets_[0], j01.data(), det_offsets_[1], -1.0, box.data());
    } else {
      for (int k = 0; k < 3; ++k) {
        const int a = (k + 1) % 3, b = (k + 2) % 3;
        const auto& sc = *cofactor_[k];
        std::vector<double> cbox(sc.box_size(), 0.0);
        const Eigen::VectorXd j1a = row(G[a], 1), j2b = row(G[b], 2), j1b = row(G[b], 1), j2a = row(G[a], 2);
        detail::scaled_convolve(j1a.data(), cof_offsets_[k][0], j2b.data(), cof_offsets_[k][1], 1.0, cbox.data());
        detail::scaled_convolve(j2a.data(), cof_offsets_[k][0], j1b.data(), cof_offsets_[k][1], -1.0, cbox.data());
        Eigen::VectorXd cof(sc.size());
        for (int i = 0; i < sc.size(); ++i) cof[i] = cbox[sc.box_of(i)];
        const Eigen::VectorXd j0k = row(G[k], 0);
        detail::scaled_convolve(cof.data(), det_cof_offsets_[k], j0k.data(), det_offsets_[k], 1.0, box.data());
      }
    }
    return detail::unscale_box(*det_, box);
  }

 private:
  int degree_ = 0;
  const LagrangeToBernstein<Family>* to_bernstein_ = nullptr;
  const BernsteinSpace<Family>* det_ = nullptr;
  std::array<const BernsteinSpace<Family>*, dim> column_{};
  std::array<std::vector<int>, dim> det_offsets_;
  // 3D only: cofactors C(0, k).
  std::array<const BernsteinSpace<Family>*, dim> cofactor_{};
  std::array<std::array<std::vector<int>, 2>, dim> cof_offsets_;
  std::array<std::vector<int>, dim> det_cof_offsets_;
};

/// The shared tables for (Family, Nodes, p) (built once; thread-safe).
template <ElementFamily Family, NodeSet Nodes>
const JacobianBernstein<Family>& jacobian_bernstein(int p) {
  static std::mutex mutex;
  static std::map<int, std::unique_ptr<JacobianBernstein<Family>>> cache;
  const std::lock_guard lock(mutex);
  auto& slot = cache[p];
  if (!slot) slot = std::make_unique<JacobianBernstein<Family>>(JacobianBernstein<Family>::template build<Nodes>(p));
  return *slot;
}

/// Bernstein coefficients of det D phi_P of one element.
template <ElementFamily Family, NodeSet Nodes>
Eigen::VectorXd jacobian_determinant_bernstein(int p, const Eigen::Ref<const Eigen::Matrix<double, Family::dim, Eigen::Dynamic>>& X) {
  return jacobian_bernstein<Family, Nodes>(p).coefficients(X);
}

}  // namespace hom
