#pragma once
/// @file quadrature_policy.hpp
/// Quadrature exactness as a policy, and a thread-safe cache of rules.
///
/// Concept QuadraturePolicy: a stateless type Q with
///   - `template <ElementFamily F> static int exactness(int p)`: the degree a
///     rule must integrate exactly on F's reference element for elements of
///     polynomial degree p >= 1 (total degree on simplices, per-axis degree on
///     cubes, as gauss_rule reads it);
///   - `static constexpr std::string_view name`: for reports ("which rule a
///     table used").
/// Models: ThesisExactness, DefaultExactness, ReducedExactness.
///
/// Degree bookkeeping both models rely on. The integrands (the distortion of
/// eq 3.20 and the objective of eq 4.10) are rational in the Jacobian
/// Dphi, not polynomial, so no rule is exact for them; what a degree buys is
/// how finely det Dphi — the polynomial that decides validity — is sampled.
///   - simplex of degree p: Dphi has entries of total degree p - 1, so
///     det Dphi has total degree Dim (p - 1);
///   - cube of degree p (Q_p map): d phi / d x_i has degree p - 1 in x_i and p
///     in the other axes; each term of det Dphi takes one derivative per axis,
///     so det Dphi has per-axis degree (Dim - 1) p + (p - 1) = Dim p - 1.

#include <concepts>
#include <map>
#include <mutex>
#include <string_view>

#include "hom/element/family.hpp"
#include "hom/quadrature/gauss.hpp"
#include "hom/quadrature/quadrature_rule.hpp"

namespace hom {

template <class Q>
concept QuadraturePolicy = requires(int p) {
  { Q::template exactness<Simplex<2>>(p) } -> std::same_as<int>;
  { Q::template exactness<Simplex<3>>(p) } -> std::same_as<int>;
  { Q::template exactness<Cube<2>>(p) } -> std::same_as<int>;
  { Q::template exactness<Cube<3>>(p) } -> std::same_as<int>;
  { Q::name } -> std::convertible_to<std::string_view>;
};

/// The thesis's choice (sec 3.1.3, after remark 3.1): integrate polynomials of
/// degree 6p - 3 exactly on simplices of either dimension. The thesis uses
/// symmetric rules with (q+1)(q+2)/2 points (triangles) and (q+1)(q+2)(q+3)/6
/// points (tetrahedra), q = 3p - 2 (Huerta et al. 2012, 2013); hom's collapsed
/// Gauss–Jacobi rules of the same degree have (q+1)^Dim points (3p-1 per
/// direction), about 2x (triangle) and 6x (tetrahedron) more. The thesis does
/// not derive 6p - 3; it covers (det Dphi)^2, of total degree 2 Dim (p - 1)
/// <= 6p - 6, with margin.
///
/// Cubes (no thesis value): the analogous requirement, per-axis exactness for
/// (det Dphi)^2, whose per-axis degree is 2 (Dim p - 1); rounded up to the odd
/// degree a Gauss rule reaches anyway: 2 Dim p - 1 (quad 4p - 1, hex 6p - 1),
/// i.e. Dim p Gauss–Legendre points per axis. For hexahedra this is within 2 of
/// the simplex value 6p - 3.
struct ThesisExactness {
  static constexpr std::string_view name = "thesis (6p-3 simplex, 2*dim*p-1 per axis cube)";

  template <ElementFamily F>
  static int exactness(int p) {
    if constexpr (F::is_simplex)
      return 6 * p - 3;
    else
      return 2 * F::dim * p - 1;
  }
};

/// The default: exact for deg(det Dphi) + 2, i.e. one Gauss point per
/// direction more than integrating det Dphi (the element's volume) exactly
/// needs. Values: triangle 2p, tetrahedron 3p - 1, quadrilateral 2p + 1,
/// hexahedron 3p + 1 (so a bilinear quad already gets 2x2 points, not the
/// single centre point at which a tangled quad can look valid).
///
/// Why cheaper than the thesis: the integrand is not polynomial, so extra
/// degree does not make it exact, and cost grows with the cube of the points
/// per direction on tetrahedra and hexahedra. At p = 4 a tetrahedron gets 6^3 =
/// 216 points here against 11^3 = 1331 with ThesisExactness (and 286 in the
/// thesis's own symmetric rule); at p = 10, 15^3 = 3375 against 29^3 = 24389.
/// The point density still exceeds the degree of det Dphi in every direction.
/// Select ThesisExactness to reproduce the thesis's tables.
struct DefaultExactness {
  static constexpr std::string_view name = "default (deg det + 2)";

  template <ElementFamily F>
  static int exactness(int p) {
    if constexpr (F::is_simplex)
      return F::dim * (p - 1) + 2;
    else
      return F::dim * p - 1 + 2;
  }
};

/// A cheaper rule for optimizing (not for certifying validity): exact for
/// |Dphi|^2 + 2, the numerator of the shape measure (eq 3.2), i.e. degree 2p on
/// simplices (p + 1 Gauss-Jacobi points per direction) and 2p + 1 per axis on
/// cubes (p + 1 Gauss points per axis). A degree-p element then has about as
/// many points as nodes on tetrahedra ((p + 1)^3 against (p+1)(p+2)(p+3)/6
/// nodes): 216 against 512 (DefaultExactness) at p = 5, 1331 against 3375 at
/// p = 10, which makes every evaluation of the objective 2.4x cheaper. det Dphi
/// (degree Dim (p - 1)) is sampled more coarsely, so a configuration optimized
/// with it is verified with a richer rule afterwards (hom::optimize does).
struct ReducedExactness {
  static constexpr std::string_view name = "reduced (2p)";

  template <ElementFamily F>
  static int exactness(int p) {
    if constexpr (F::is_simplex)
      return 2 * p;
    else
      return 2 * p + 1;
  }
};

static_assert(QuadraturePolicy<ThesisExactness>);
static_assert(QuadraturePolicy<DefaultExactness>);
static_assert(QuadraturePolicy<ReducedExactness>);

/// The Gauss rule of the given exactness on F, built once per (F, exactness)
/// and shared; safe to call from several threads. The reference stays valid
/// for the life of the program.
template <ElementFamily F>
const QuadratureRule<F::dim>& cached_gauss_rule(int exactness) {
  static std::mutex mutex;
  static std::map<int, QuadratureRule<F::dim>> cache;  // std::map: references stay valid on insert
  const std::lock_guard<std::mutex> lock(mutex);
  auto it = cache.find(exactness);
  if (it == cache.end()) it = cache.emplace(exactness, gauss_rule<F>(exactness)).first;
  return it->second;
}

/// The rule policy Q prescribes for degree-p elements of family F (cached).
template <ElementFamily F, QuadraturePolicy Q = DefaultExactness>
const QuadratureRule<F::dim>& quadrature_for(int p) {
  return cached_gauss_rule<F>(Q::template exactness<F>(p));
}

}  // namespace hom
