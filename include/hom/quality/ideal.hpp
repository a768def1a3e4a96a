#pragma once
/// @file ideal.hpp
/// Ideal elements E^I (thesis section 3.1.2): the straight-sided element each
/// physical element is measured against, through phi_E = phi_P o phi_I^{-1}
/// (eq 3.17, appendix A eq A.2).
///
/// An ideal is straight-sided, so it is determined by its vertices: phi_I is
/// affine on simplices and multilinear on cubes. `IdealMesh` stores one set of
/// vertices per element, which covers the three kinds of ideal a user needs:
///   - straight-sided (relative, the default): each element's own vertices,
///     i.e. its straight-sided high-order counterpart;
///   - regular (absolute): the equilateral triangle / regular tetrahedron of
///     unit edge, or the unit square / cube, for every element;
///   - affine per element: a user-given matrix A_e, ideal = A_e (reference
///     element) - for example a stretched boundary-layer element.

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "hom/element/family.hpp"

namespace hom {

template <ElementFamily Family>
using IdealVertices = Eigen::Matrix<double, Family::dim, Family::num_vertices>;

/// Gradients (num_vertices x dim) of the vertex (linear / multilinear) shape
/// functions at reference point xi.
template <ElementFamily Family>
Eigen::Matrix<double, Family::num_vertices, Family::dim> vertex_shape_gradients(const typename Family::Point& xi) {
  constexpr int D = Family::dim;
  Eigen::Matrix<double, Family::num_vertices, D> g;
  if constexpr (Family::is_simplex) {
    g.row(0).setConstant(-1.0);
    g.template bottomRows<D>().setIdentity();
  } else {
    // L_v(xi) = prod_a (1 + s_a xi_a) / 2 with s_a = +-1 the vertex's corner sign.
    for (int v = 0; v < Family::num_vertices; ++v) {
      const auto c = Family::vertex_corner(v);
      for (int k = 0; k < D; ++k) {
        double d = 1.0;
        for (int a = 0; a < D; ++a) {
          const double s = c[a] ? 1.0 : -1.0;
          d *= a == k ? s / 2.0 : (1.0 + s * xi[a]) / 2.0;
        }
        g(v, k) = d;
      }
    }
  }
  return g;
}

/// D phi_I at reference point xi for the ideal with vertices `v`.
template <ElementFamily Family>
Eigen::Matrix<double, Family::dim, Family::dim> ideal_jacobian(const IdealVertices<Family>& v,
                                                                 const typename Family::Point& xi) {
  return v * vertex_shape_gradients<Family>(xi);
}

/// Vertices of the regular element of unit edge (equilateral triangle, regular
/// tetrahedron, unit square, unit cube), positively oriented.
template <ElementFamily Family>
IdealVertices<Family> regular_ideal_vertices() {
  constexpr int D = Family::dim;
  IdealVertices<Family> v;
  if constexpr (Family::is_simplex && D == 2) {
    v << 0.0, 1.0, 0.5,  //
        0.0, 0.0, std::sqrt(3.0) / 2.0;
  } else if constexpr (Family::is_simplex && D == 3) {
    v << 0.0, 1.0, 0.5, 0.5,                              //
        0.0, 0.0, std::sqrt(3.0) / 2.0, std::sqrt(3.0) / 6.0,  //
        0.0, 0.0, 0.0, std::sqrt(2.0 / 3.0);
  } else {
    for (int i = 0; i < Family::num_vertices; ++i) v.col(i) = (Family::vertex(i).array() + 1.0) / 2.0;
  }
  return v;
}

/// Whether phi_I is orientation-preserving: det D phi_I > 0 at every vertex,
/// relative to the element's size (remark 3.1: the ideal must be valid, or
/// phi_E = phi_P o phi_I^{-1} inverts a valid physical element). phi_I is
/// affine on simplices, so one determinant decides; on cubes the corner
/// determinants are the usual criterion (exact for quadrilaterals).
template <ElementFamily Family>
bool valid_ideal(const IdealVertices<Family>& v) {
  constexpr int D = Family::dim;
  double diameter = 0.0;
  for (int i = 0; i < Family::num_vertices; ++i)
    for (int j = i + 1; j < Family::num_vertices; ++j) diameter = std::max(diameter, (v.col(i) - v.col(j)).norm());
  const double flat = 1e-12 * std::pow(diameter, D);  // below this the element is flat to rounding
  for (int i = 0; i < Family::num_vertices; ++i)
    if (!(ideal_jacobian<Family>(v, Family::vertex(i)).determinant() > flat)) return false;
  return true;
}

/// v itself when it is a valid ideal; otherwise the regular element of the
/// same root-mean-square size, centred at v's centroid. A mesh whose vertex
/// nodes were moved (curved onto CAD, untangled) can hold elements whose
/// straight-sided counterpart is inverted or flat while the curved element is
/// valid; those are measured against the regular element instead (section 3.1.2).
template <ElementFamily Family>
IdealVertices<Family> straight_sided_or_regular(const IdealVertices<Family>& v) {
  if (valid_ideal<Family>(v)) return v;
  const IdealVertices<Family> r = regular_ideal_vertices<Family>();
  const auto rms_radius = [](const IdealVertices<Family>& w) {
    return std::sqrt((w.colwise() - w.rowwise().mean()).colwise().squaredNorm().mean());
  };
  const double size = rms_radius(v);
  const double scale = size > 0 && std::isfinite(size) ? size / rms_radius(r) : 1.0;
  return ((r.colwise() - r.rowwise().mean()) * scale).colwise() + v.rowwise().mean();
}

/// One straight-sided ideal element per mesh element.
template <ElementFamily Family>
class IdealMesh {
 public:
  IdealMesh() = default;
  explicit IdealMesh(std::vector<IdealVertices<Family>> vertices) : vertices_(std::move(vertices)) {}

  int size() const { return static_cast<int>(vertices_.size()); }
  const IdealVertices<Family>& vertices(int e) const { return vertices_[e]; }
  IdealVertices<Family>& vertices(int e) { return vertices_[e]; }

  /// The same regular element for each of n elements (absolute ideal).
  static IdealMesh regular(int n) { return IdealMesh(std::vector<IdealVertices<Family>>(n, regular_ideal_vertices<Family>())); }

  /// Ideal_e = A_e (reference element): user-given affine ideals.
  static IdealMesh affine(const std::vector<Eigen::Matrix<double, Family::dim, Family::dim>>& A) {
    std::vector<IdealVertices<Family>> v(A.size());
    for (std::size_t e = 0; e < A.size(); ++e) {
      if (!(A[e].determinant() > 0))
        throw std::invalid_argument("hom::IdealMesh::affine: ideal of element " + std::to_string(e) +
                                    " is degenerate or inverted (det A <= 0)");
      for (int i = 0; i < Family::num_vertices; ++i) v[e].col(i) = A[e] * Family::vertex(i);
    }
    return IdealMesh(std::move(v));
  }

 private:
  std::vector<IdealVertices<Family>> vertices_;
};

/// Which ideal a quality evaluation or an optimization measures against.
enum class IdealKind {
  straight_sided,  ///< relative: each element's straight-sided counterpart (default)
  regular,         ///< absolute: equilateral / regular element
};

inline IdealKind parse_ideal_kind(const std::string& s) {
  if (s == "straight" || s == "straight-sided" || s == "relative") return IdealKind::straight_sided;
  if (s == "equilateral" || s == "regular" || s == "absolute") return IdealKind::regular;
  throw std::invalid_argument("unknown ideal '" + s + "' (expected straight or equilateral)");
}

}  // namespace hom
