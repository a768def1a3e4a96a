#pragma once
/// @file certify.hpp
/// Certified validity: the sign of det D phi_P everywhere in an element, not
/// only at the quadrature points that the quality measure sees (proposition
/// 3.1 and remark 3.3 only say that q_E > 0 implies det > 0 at those points).
///
/// det D phi_P is a polynomial (jacobian_bernstein.hpp). In Bernstein form its
/// coefficients bound it, min c <= det <= max c, and the coefficients at the
/// vertices are values of det. Each element is examined piece by piece, the
/// piece with the smallest coefficient first:
///   - a piece whose coefficients are all > tol is valid;
///   - a vertex coefficient <= tol, or det <= tol at the domain point of the
///     piece's smallest coefficient, is an attained value: the element is
///     certified invalid there (`invalid_point`, reference coordinates);
///   - otherwise the piece is subdivided by de Casteljau into 2^Dim children
///     (cubes: every axis halved; simplices: Dim successive bisections of
///     the piece's longest edge in reference coordinates, so that both
///     families halve the diameter per level), unless it is at `max_depth`
///     levels, when it stays undecided.
/// Element status: certified_invalid as soon as an attained value is <= tol;
/// certified_valid when every piece is valid; undecided otherwise.
///
/// tol = zero_tolerance * max |c| of the element (default 1e-12): the
/// coefficients carry round-off of about 1e-15 relative to their largest
/// magnitude, so "valid" keeps a margin above it, and an attained value within
/// round-off of zero counts as det <= 0 (a degenerate element is invalid).
///
/// Certified scaled Jacobian. `min_scaled_jacobian` is a guaranteed lower
/// bound of ElementQuality::scaled_jacobian() (element_quality.hpp: min det /
/// max(|max det|, |min det|) sampled at the quadrature points and the nodes),
/// whatever points it samples, and of the continuous min det / max |det| over
/// the element:
///   - valid elements: m / M, with m = min over the final pieces of their
///     smallest coefficient (<= det everywhere) and M = max over them of their
///     largest (>= det everywhere);
///   - otherwise: max(-1, m / V), V = max |det| at the vertices (which are
///     nodes, so the sampled denominator is >= V), and -1 when V = 0.
/// The mesh's certified minimum scaled Jacobian is the minimum over elements.

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <queue>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "hom/basis/bernstein.hpp"
#include "hom/detail/parallel.hpp"
#include "hom/element/family.hpp"
#include "hom/mesh/mesh.hpp"
#include "hom/quality/jacobian_bernstein.hpp"

namespace hom {

enum class Certificate {
  certified_valid,    ///< det D phi_P > 0 everywhere in the element
  certified_invalid,  ///< det D phi_P <= 0 at `invalid_point`
  undecided,          ///< neither, within max_depth subdivision levels
};

inline std::string_view to_string(Certificate c) {
  switch (c) {
    case Certificate::certified_valid: return "certified valid";
    case Certificate::certified_invalid: return "certified invalid";
    case Certificate::undecided: return "undecided";
  }
  return "?";
}

/// Cell value of a status in VTU output: 0 valid, 1 undecided, 2 invalid (by severity).
inline double status_code(Certificate c) {
  return c == Certificate::certified_valid ? 0.0 : c == Certificate::undecided ? 1.0 : 2.0;
}

struct CertifyOptions {
  int max_depth = 5;              ///< subdivision levels (2^Dim children each) before "undecided"
  double zero_tolerance = 1e-12;  ///< relative to the element's max |coefficient| (see file comment)
  int threads = 0;                ///< mesh level; <= 0: OpenMP's default
};

template <ElementFamily Family>
struct ElementCertificate {
  using Point = typename Family::Point;
  Certificate status = Certificate::undecided;
  int depth = 0;   ///< deepest subdivision level of the final partition
  int pieces = 0;  ///< pieces of the final partition (1: decided without subdivision)
  std::optional<Point> invalid_point;  ///< reference coordinates where det <= tol was attained
  double invalid_value = std::numeric_limits<double>::quiet_NaN();  ///< det there
  /// Set when a piece stayed undecided at max_depth (always for undecided
  /// elements): the reference point of the smallest coefficient of the lowest
  /// such piece (its domain point), where det comes closest to 0 among the
  /// points examined; the optimizer's certify stage watches it (certified.hpp).
  std::optional<Point> weakest_point;
  double min_det_bound = 0.0;   ///< <= det D phi_P everywhere in the element
  double max_det_bound = 0.0;   ///< >= det D phi_P everywhere in the element
  double max_vertex_det = 0.0;  ///< max |det D phi_P| at the vertices (attained)
  double min_scaled_jacobian = -1.0;  ///< certified lower bound (file comment)
};

namespace detail {

/// A piece of the reference element with det's coefficients on it (in the
/// piece's own reference coordinates).
template <ElementFamily Family>
struct CertifyPiece {
  using Point = typename Family::Point;
  // Simplex: the piece's vertices; cube: corner lo = vertex(0), hi.
  std::array<Point, Family::is_simplex ? Family::dim + 1 : 2> geometry;
  Eigen::VectorXd c;
  int depth = 0;
  double min = 0.0, max = 0.0;

  void bounds() {
    min = c.minCoeff();
    max = c.maxCoeff();
  }
  /// The reference-element point of local (piece) reference coordinates x.
  Point to_reference(const Point& x) const {
    if constexpr (Family::is_simplex) {
      Point r = geometry[0] * (1.0 - x.sum());
      for (int k = 0; k < Family::dim; ++k) r += geometry[k + 1] * x[k];
      return r;
    } else {
      return geometry[0] + (geometry[1] - geometry[0]).cwiseProduct((x.array() + 1.0).matrix() / 2.0);
    }
  }
  /// Reference location of the piece's vertex v (Family's vertex order).
  Point vertex(int v) const { return to_reference(Family::vertex(v)); }
};

template <ElementFamily Family>
struct PieceOrder {
  bool operator()(const CertifyPiece<Family>& a, const CertifyPiece<Family>& b) const { return a.min > b.min; }
};

/// One level: 2^Dim children of `p`.
template <ElementFamily Family>
std::vector<CertifyPiece<Family>> subdivide(const BernsteinSpace<Family>& s, const CertifyPiece<Family>& p) {
  constexpr int D = Family::dim;
  std::vector<CertifyPiece<Family>> cur{p}, next;
  for (int r = 0; r < D; ++r) {
    next.clear();
    for (const auto& q : cur) {
      CertifyPiece<Family> lo = q, hi = q;
      if constexpr (Family::is_simplex) {
        int a = 0, b = 1;
        double longest = -1.0;
        for (int i = 0; i <= D; ++i)
          for (int j = i + 1; j <= D; ++j) {
            const double len = (q.geometry[i] - q.geometry[j]).squaredNorm();
            if (len > longest * (1.0 + 1e-12)) {
              longest = len;
              a = i;
              b = j;
            }
          }
        bernstein_bisect(s, q.c, a, b, lo.c, hi.c);
        const typename Family::Point m = 0.5 * (q.geometry[a] + q.geometry[b]);
        lo.geometry[b] = m;
        hi.geometry[a] = m;
      } else {
        bernstein_bisect(s, q.c, r, lo.c, hi.c);
        const double mid = 0.5 * (q.geometry[0][r] + q.geometry[1][r]);
        lo.geometry[1][r] = mid;
        hi.geometry[0][r] = mid;
      }
      next.push_back(std::move(lo));
      next.push_back(std::move(hi));
    }
    std::swap(cur, next);
  }
  for (auto& q : cur) {
    q.depth = p.depth + 1;
    q.bounds();
  }
  return cur;
}

}  // namespace detail

/// Certifies one element from det's Bernstein coefficients `c` (in `s`,
/// from JacobianBernstein::coefficients).
template <ElementFamily Family>
ElementCertificate<Family> certify_coefficients(const BernsteinSpace<Family>& s, Eigen::VectorXd c,
                                                const CertifyOptions& o = {}) {
  using Piece = detail::CertifyPiece<Family>;
  ElementCertificate<Family> r;
  const auto corners = s.corners();
  Piece root;
  if constexpr (Family::is_simplex)
    for (int v = 0; v <= Family::dim; ++v) root.geometry[v] = Family::vertex(v);
  else
    root.geometry = {Family::vertex(0), -Family::vertex(0)};
  root.c = std::move(c);
  root.bounds();
  const double tol = o.zero_tolerance * std::max(std::abs(root.min), std::abs(root.max));
  for (int v : corners) r.max_vertex_det = std::max(r.max_vertex_det, std::abs(root.c[v]));

  std::priority_queue<Piece, std::vector<Piece>, detail::PieceOrder<Family>> queue;
  std::vector<Piece> undecided;  // pieces at max_depth with a coefficient <= tol
  queue.push(std::move(root));
  bool all_valid = false;
  while (!queue.empty()) {
    if (queue.top().min > tol) {  // every remaining piece is valid
      all_valid = true;
      break;
    }
    Piece q = queue.top();
    queue.pop();
    // Attained values: the vertices, then the domain point of the smallest coefficient.
    for (int v = 0; v < Family::num_vertices && !r.invalid_point; ++v)
      if (q.c[corners[v]] <= tol) {
        r.invalid_point = q.vertex(v);
        r.invalid_value = q.c[corners[v]];
      }
    std::optional<typename Family::Point> lowest;  // reference point of the smallest coefficient
    if (!r.invalid_point) {
      Eigen::Index imin;
      q.c.minCoeff(&imin);
      const auto x = s.domain_point(static_cast<int>(imin));
      const double value = s.evaluate(q.c, x);
      lowest = q.to_reference(x);
      if (value <= tol) {
        r.invalid_point = lowest;
        r.invalid_value = value;
      }
    }
    if (r.invalid_point) {
      queue.push(std::move(q));  // keep it in the partition for the bounds below
      break;
    }
    if (q.depth >= o.max_depth) {
      if (!r.weakest_point) r.weakest_point = lowest;  // pieces leave the queue lowest first
      undecided.push_back(std::move(q));
      continue;
    }
    for (auto& child : detail::subdivide(s, q)) queue.push(std::move(child));
  }

  // Bounds over the final partition (the queue and the undecided pieces).
  r.min_det_bound = std::numeric_limits<double>::infinity();
  r.max_det_bound = -std::numeric_limits<double>::infinity();
  auto take = [&](const Piece& q) {
    ++r.pieces;
    r.depth = std::max(r.depth, q.depth);
    r.min_det_bound = std::min(r.min_det_bound, q.min);
    r.max_det_bound = std::max(r.max_det_bound, q.max);
  };
  for (const auto& q : undecided) take(q);
  while (!queue.empty()) {
    take(queue.top());
    queue.pop();
  }
  if (r.invalid_point)
    r.status = Certificate::certified_invalid;
  else if (all_valid && undecided.empty())
    r.status = Certificate::certified_valid;
  else
    r.status = Certificate::undecided;
  if (r.min_det_bound > 0.0)
    r.min_scaled_jacobian = r.min_det_bound / r.max_det_bound;
  else
    r.min_scaled_jacobian = r.max_vertex_det > 0.0 ? std::max(-1.0, r.min_det_bound / r.max_vertex_det) : -1.0;
  return r;
}

/// Certifies one element with node coordinates X (Dim x n_p, layout order).
template <ElementFamily Family>
ElementCertificate<Family> certify_element(const JacobianBernstein<Family>& jb,
                                           const Eigen::Ref<const Eigen::Matrix<double, Family::dim, Eigen::Dynamic>>& X,
                                           const CertifyOptions& o = {}) {
  return certify_coefficients<Family>(jb.space(), jb.coefficients(X), o);
}

template <ElementFamily Family>
struct MeshCertificate {
  std::vector<ElementCertificate<Family>> elements;
  int valid = 0, invalid = 0, undecided = 0;
  int max_depth = 0;  ///< deepest level any element needed
  /// Certified lower bound of every element's scaled Jacobian (+inf for an empty mesh).
  double min_scaled_jacobian = std::numeric_limits<double>::infinity();

  /// status_code of each element (VTU cell data).
  std::vector<double> status_codes() const {
    std::vector<double> s;
    s.reserve(elements.size());
    for (const auto& e : elements) s.push_back(status_code(e.status));
    return s;
  }
};

/// Certifies every element of a planar or volume mesh, in parallel.
template <ElementFamily Family, NodeSet Nodes>
MeshCertificate<Family> certify_mesh(const Mesh<Family, Nodes, Family::dim>& mesh, const CertifyOptions& o = {}) {
  const auto& jb = jacobian_bernstein<Family, Nodes>(mesh.degree());
  MeshCertificate<Family> r;
  const int ne = mesh.num_elements();
  r.elements.resize(ne);
  const detail::SerialEigenScope serial;
  const int threads = detail::useful_threads(detail::resolve_threads(o.threads), ne, 4);
  HOM_PARALLEL_FOR_DYNAMIC(threads)
  for (int e = 0; e < ne; ++e) r.elements[e] = certify_element<Family>(jb, mesh.element_coordinates(e), o);
  for (const auto& c : r.elements) {
    r.valid += c.status == Certificate::certified_valid;
    r.invalid += c.status == Certificate::certified_invalid;
    r.undecided += c.status == Certificate::undecided;
    r.max_depth = std::max(r.max_depth, c.depth);
    r.min_scaled_jacobian = std::min(r.min_scaled_jacobian, c.min_scaled_jacobian);
  }
  return r;
}

}  // namespace hom
