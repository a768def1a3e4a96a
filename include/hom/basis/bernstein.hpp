#pragma once
/// @file bernstein.hpp
/// Bernstein (Bezier) polynomials on hom's reference elements, for bounding
/// polynomials over a whole element (quality/jacobian_bernstein.hpp,
/// quality/certify.hpp): a polynomial f = sum_i c_i B_i with B_i >= 0 and
/// sum_i B_i = 1 satisfies min_i c_i <= f <= max_i c_i on the element, and the
/// coefficients at the vertices are the values of f there.
///
/// Simplex<Dim>, total degree n: with barycentric coordinates
/// lambda_0 = 1 - sum_k xi_k, lambda_k = xi_k (k = 1..Dim) and the multi-index
/// alpha = (n - |l|, l_1, .., l_Dim) of lattice index l (|l| <= n, the same
/// integer barycentric weights as Simplex::vertex_weights),
///     B_l(xi) = n! / (alpha_0! .. alpha_Dim!) prod_k lambda_k^alpha_k.
/// Cube<Dim>, degree n_a along axis a (degrees may differ per axis, which the
/// derivatives and products of a tensor polynomial need): with t_a = (1 + xi_a) / 2,
///     B_l(xi) = prod_a C(n_a, l_a) t_a^l_a (1 - t_a)^(n_a - l_a).
/// The degree is a `std::array<int, Dim>` for both families; a simplex space
/// has the same total degree in every entry, so that "degree of a product =
/// sum of the degrees, entry by entry" holds for both.
///
/// Coefficient order ("compact" order): lattice indices by increasing box
/// index l_0 + (n_0 + 1)(l_1 + (n_1 + 1) l_2), i.e. axis 0 fastest, keeping
/// those in the element. The box index is linear in l, which is what makes the
/// product below a plain convolution with separable offsets.
///
/// Operations:
///   - values / evaluate at a point;
///   - LagrangeToBernstein<Family>: nodal values on any NodeSet -> Bernstein
///     coefficients of the same degree-p polynomial (one matrix per
///     (family, node set, p), built in long double; tensor cubes one 1D matrix);
///   - bernstein_product: exact product, B^m_a B^n_b = w_a w_b / w_{a+b} B^{m+n}_{a+b}
///     with w the multinomial (simplex) or binomial-product (cube) weights;
///   - bernstein_elevate: degree elevation (product with 1 = sum of the basis);
///   - bernstein_derivative: d/dxi_k, exact, one degree less;
///   - de Casteljau subdivision. Simplices are split by edge bisection: the
///     piece with the edge (a, b) split at its midpoint m gives the child with
///     b replaced by m and the child with a replaced by m; on every line of
///     coefficients in which only alpha_a and alpha_b vary this is the 1D de
///     Casteljau step at t = 1/2. Cubes are split along one axis at its
///     midpoint. (certify.hpp composes Dim bisections into one level of 2^Dim
///     children for both families.)

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>

#include "hom/element/family.hpp"
#include "hom/element/node_layout.hpp"
#include "hom/nodes/node_set.hpp"

namespace hom {

template <ElementFamily Family>
using BernsteinDegree = std::array<int, Family::dim>;

namespace detail {

/// C(n, k) as a double (exact while it fits in 53 bits: n <= 56).
inline double binomial(int n, int k) {
  if (k < 0 || k > n) return 0.0;
  k = std::min(k, n - k);
  double r = 1.0;
  for (int i = 1; i <= k; ++i) r = r * (n - k + i) / i;
  return std::round(r);
}

/// [sum(a), .., sum(a)] for simplices; the entry-wise degree for cubes.
template <ElementFamily Family>
BernsteinDegree<Family> uniform_degree(int n) {
  BernsteinDegree<Family> d;
  d.fill(n);
  return d;
}

}  // namespace detail

/// The Bernstein basis of one degree on Family's reference element.
template <ElementFamily Family>
class BernsteinSpace {
 public:
  static constexpr int dim = Family::dim;
  using Degree = BernsteinDegree<Family>;
  using Point = typename Family::Point;

  explicit BernsteinSpace(const Degree& n) : degree_(n) {
    for (int a = 0; a < dim; ++a) {
      if (n[a] < 0) throw std::invalid_argument("hom::BernsteinSpace: negative degree");
      if (Family::is_simplex && n[a] != n[0])
        throw std::invalid_argument("hom::BernsteinSpace: a simplex space has one total degree");
    }
    box_size_ = 1;
    for (int a = 0; a < dim; ++a) {
      stride_[a] = box_size_;
      box_size_ *= n[a] + 1;
    }
    compact_of_box_.assign(box_size_, -1);
    for (int b = 0; b < box_size_; ++b) {
      Lattice<dim> l;
      int r = b;
      for (int a = 0; a < dim; ++a) {
        l[a] = r % (n[a] + 1);
        r /= n[a] + 1;
      }
      if (!inside(l)) continue;
      compact_of_box_[b] = static_cast<int>(lattice_.size());
      lattice_.push_back(l);
      box_of_compact_.push_back(b);
      weight_.push_back(multinomial(l));
    }
  }

  const Degree& degree() const { return degree_; }
  /// Total degree (simplices) or the degree of axis 0 (cubes).
  int total_degree() const { return degree_[0]; }
  int size() const { return static_cast<int>(lattice_.size()); }
  const Lattice<dim>& lattice(int i) const { return lattice_[i]; }
  /// Compact index of lattice index l, or -1 when l is not in the space.
  int index_of(const Lattice<dim>& l) const {
    for (int a = 0; a < dim; ++a)
      if (l[a] < 0 || l[a] > degree_[a]) return -1;
    return compact_of_box_[box_index(l)];
  }
  /// w_i: n! / alpha! (simplex) or prod_a C(n_a, l_a) (cube), so B_i = w_i * monomial.
  double weight(int i) const { return weight_[i]; }

  /// The dense box {0..n_a} of lattice indices, in which the box index is linear.
  int box_size() const { return box_size_; }
  int box_index(const Lattice<dim>& l) const {
    int b = 0;
    for (int a = 0; a < dim; ++a) b += l[a] * stride_[a];
    return b;
  }
  int box_of(int i) const { return box_of_compact_[i]; }
  /// Box indices (in this space's box) of the lattice indices of `other`,
  /// which must fit in it: the offsets of a product's convolution.
  std::vector<int> box_offsets(const BernsteinSpace& other) const {
    std::vector<int> off(other.size());
    for (int i = 0; i < other.size(); ++i) {
      for (int a = 0; a < dim; ++a)
        if (other.lattice(i)[a] > degree_[a]) throw std::invalid_argument("hom::BernsteinSpace::box_offsets: too high a degree");
      off[i] = box_index(other.lattice(i));
    }
    return off;
  }

  /// Reference point of coefficient i (its "domain point": l / n on
  /// simplices, -1 + 2 l / n on cubes); the coefficient is near the value there.
  Point domain_point(int i) const {
    Point x;
    for (int a = 0; a < dim; ++a) {
      const double t = degree_[a] == 0 ? 0.5 : double(lattice_[i][a]) / degree_[a];
      x[a] = Family::is_simplex ? (degree_[a] == 0 ? 1.0 / (dim + 1) : t) : -1.0 + 2.0 * t;
    }
    return x;
  }

  /// Compact indices of the coefficients at the vertices, in Family's vertex order.
  std::array<int, Family::num_vertices> corners() const {
    std::array<int, Family::num_vertices> c{};
    for (int v = 0; v < Family::num_vertices; ++v) {
      Lattice<dim> l{};
      if constexpr (Family::is_simplex) {
        if (v > 0) l[v - 1] = degree_[0];
      } else {
        const auto corner = Family::vertex_corner(v);
        for (int a = 0; a < dim; ++a) l[a] = corner[a] * degree_[a];
      }
      c[v] = index_of(l);
    }
    return c;
  }

  /// B_i(x) for every i, in compact order (any Scalar: long double for tables).
  template <class Scalar = double>
  Eigen::Matrix<Scalar, Eigen::Dynamic, 1> values(const Point& x) const {
    // Powers of the barycentric (simplex) or of t, 1 - t (cube) coordinates.
    constexpr int nc = Family::is_simplex ? dim + 1 : 2 * dim;
    std::array<Scalar, nc> base;
    std::array<int, nc> top;
    if constexpr (Family::is_simplex) {
      Scalar l0 = 1;
      for (int a = 0; a < dim; ++a) {
        base[a + 1] = Scalar(x[a]);
        l0 -= Scalar(x[a]);
        top[a + 1] = degree_[0];
      }
      base[0] = l0;
      top[0] = degree_[0];
    } else {
      for (int a = 0; a < dim; ++a) {
        const Scalar t = (Scalar(1) + Scalar(x[a])) / 2;
        base[2 * a] = t;
        base[2 * a + 1] = Scalar(1) - t;
        top[2 * a] = top[2 * a + 1] = degree_[a];
      }
    }
    std::array<std::vector<Scalar>, nc> pw;
    for (int c = 0; c < nc; ++c) {
      pw[c].assign(top[c] + 1, Scalar(1));
      for (int k = 1; k <= top[c]; ++k) pw[c][k] = pw[c][k - 1] * base[c];
    }
    Eigen::Matrix<Scalar, Eigen::Dynamic, 1> v(size());
    for (int i = 0; i < size(); ++i) {
      const auto& l = lattice_[i];
      Scalar b = Scalar(weight_[i]);
      if constexpr (Family::is_simplex) {
        int s = 0;
        for (int a = 0; a < dim; ++a) {
          b *= pw[a + 1][l[a]];
          s += l[a];
        }
        b *= pw[0][degree_[0] - s];
      } else {
        for (int a = 0; a < dim; ++a) b *= pw[2 * a][l[a]] * pw[2 * a + 1][degree_[a] - l[a]];
      }
      v[i] = b;
    }
    return v;
  }

  /// sum_i c_i B_i(x).
  double evaluate(const Eigen::Ref<const Eigen::VectorXd>& c, const Point& x) const { return c.dot(values(x)); }

 private:
  bool inside(const Lattice<dim>& l) const {
    if constexpr (Family::is_simplex) {
      int s = 0;
      for (int a = 0; a < dim; ++a) s += l[a];
      return s <= degree_[0];
    } else {
      return true;
    }
  }

  double multinomial(const Lattice<dim>& l) const {
    double w = 1.0;
    if constexpr (Family::is_simplex) {
      int rest = degree_[0];  // n! / (alpha_0! .. alpha_Dim!) = prod_k C(rest_k, l_k)
      for (int a = 0; a < dim; ++a) {
        w *= detail::binomial(rest, l[a]);
        rest -= l[a];
      }
    } else {
      for (int a = 0; a < dim; ++a) w *= detail::binomial(degree_[a], l[a]);
    }
    return w;
  }

  Degree degree_;
  std::array<int, dim> stride_{};
  int box_size_ = 0;
  std::vector<Lattice<dim>> lattice_;
  std::vector<int> box_of_compact_, compact_of_box_;
  std::vector<double> weight_;
};

/// The shared space of degree n (built once; thread-safe; references stay valid).
template <ElementFamily Family>
const BernsteinSpace<Family>& bernstein_space(const BernsteinDegree<Family>& n) {
  static std::mutex mutex;
  static std::map<BernsteinDegree<Family>, std::unique_ptr<BernsteinSpace<Family>>> cache;
  const std::lock_guard lock(mutex);
  auto& slot = cache[n];
  if (!slot) slot = std::make_unique<BernsteinSpace<Family>>(n);
  return *slot;
}

/// The space of total degree n (simplex) or degree n along every axis (cube).
template <ElementFamily Family>
const BernsteinSpace<Family>& bernstein_space(int n) {
  return bernstein_space<Family>(detail::uniform_degree<Family>(n));
}

/// Degree of a product: entry-wise sum.
template <ElementFamily Family>
BernsteinDegree<Family> product_degree(const BernsteinDegree<Family>& a, const BernsteinDegree<Family>& b) {
  BernsteinDegree<Family> c;
  for (int k = 0; k < Family::dim; ++k) c[k] = a[k] + b[k];
  return c;
}

/// Degree of d/dxi_k: one less in total (simplex) or along axis k (cube).
template <ElementFamily Family>
BernsteinDegree<Family> derivative_degree(const BernsteinDegree<Family>& n, int k) {
  BernsteinDegree<Family> d = n;
  if constexpr (Family::is_simplex)
    for (auto& x : d) --x;
  else
    --d[k];
  return d;
}

namespace detail {

/// box[off_a[i] + off_b[j]] += sign * a[i] * b[j]: the product of two
/// polynomials in scaled form (coefficient times weight = monomial
/// coefficient), whose box indices add (bernstein.hpp, "compact order").
inline void scaled_convolve(const double* a, const std::vector<int>& off_a, const double* b,
                            const std::vector<int>& off_b, double sign, double* box) {
  const int nb = static_cast<int>(off_b.size());
  const int* ob = off_b.data();
  for (std::size_t i = 0; i < off_a.size(); ++i) {
    const double ai = sign * a[i];
    if (ai == 0.0) continue;
    double* base = box + off_a[i];
    for (int j = 0; j < nb; ++j) base[ob[j]] += ai * b[j];
  }
}

/// Scaled form: c_i * w_i.
template <ElementFamily Family>
Eigen::VectorXd scale(const BernsteinSpace<Family>& s, const Eigen::Ref<const Eigen::VectorXd>& c) {
  Eigen::VectorXd r(s.size());
  for (int i = 0; i < s.size(); ++i) r[i] = c[i] * s.weight(i);
  return r;
}

/// Back from a box of scaled coefficients to Bernstein coefficients.
template <ElementFamily Family>
Eigen::VectorXd unscale_box(const BernsteinSpace<Family>& s, const std::vector<double>& box) {
  Eigen::VectorXd r(s.size());
  for (int i = 0; i < s.size(); ++i) r[i] = box[s.box_of(i)] / s.weight(i);
  return r;
}

}  // namespace detail

/// Coefficients of f * g in the space of degree deg(f) + deg(g) (exact up to round-off).
template <ElementFamily Family>
Eigen::VectorXd bernstein_product(const BernsteinSpace<Family>& sa, const Eigen::Ref<const Eigen::VectorXd>& a,
                                  const BernsteinSpace<Family>& sb, const Eigen::Ref<const Eigen::VectorXd>& b) {
  const auto& sc = bernstein_space<Family>(product_degree<Family>(sa.degree(), sb.degree()));
  std::vector<double> box(sc.box_size(), 0.0);
  const Eigen::VectorXd as = detail::scale(sa, a), bs = detail::scale(sb, b);
  detail::scaled_convolve(as.data(), sc.box_offsets(sa), bs.data(), sc.box_offsets(sb), 1.0, box.data());
  return detail::unscale_box(sc, box);
}

/// The same polynomial in the space of degree deg + by (entry-wise).
template <ElementFamily Family>
Eigen::VectorXd bernstein_elevate(const BernsteinSpace<Family>& s, const Eigen::Ref<const Eigen::VectorXd>& c,
                                  const BernsteinDegree<Family>& by) {
  const auto& one = bernstein_space<Family>(by);
  return bernstein_product(s, c, one, Eigen::VectorXd::Ones(one.size()));
}

/// Coefficients of d f / d xi_k in the space of derivative_degree(deg, k).
/// Simplex: n (c_{l + e_k} - c_l) (lambda_k = xi_k, lambda_0 = 1 - sum xi);
/// cube: n_k / 2 (c_{l + e_k} - c_l) (t = (1 + xi) / 2).
template <ElementFamily Family>
Eigen::VectorXd bernstein_derivative(const BernsteinSpace<Family>& s, const Eigen::Ref<const Eigen::VectorXd>& c, int k) {
  const auto& sd = bernstein_space<Family>(derivative_degree<Family>(s.degree(), k));
  const double factor = Family::is_simplex ? s.degree()[k] : 0.5 * s.degree()[k];
  Eigen::VectorXd d(sd.size());
  for (int i = 0; i < sd.size(); ++i) {
    Lattice<Family::dim> l = sd.lattice(i);
    const double c0 = c[s.index_of(l)];
    ++l[k];
    d[i] = factor * (c[s.index_of(l)] - c0);
  }
  return d;
}

namespace detail {

/// 1D de Casteljau at t = 1/2 on c[0..s] (in place): afterwards `left` holds
/// the coefficients on [0, 1/2] and c those on [1/2, 1], both re-parameterized to [0, 1].
inline void de_casteljau_half(double* c, double* left, int s) {
  left[0] = c[0];
  for (int r = 1; r <= s; ++r) {
    for (int i = 0; i + r <= s; ++i) c[i] = 0.5 * (c[i] + c[i + 1]);
    left[r] = c[0];
  }
  // c[i] now holds c^{s-i}_i: the right piece's coefficient i.
}

}  // namespace detail

/// Splits a cube polynomial at xi_axis = 0: `lower` on xi_axis in [-1, 0],
/// `upper` on [0, 1], each re-parameterized to the reference cube.
template <int Dim>
void bernstein_bisect(const BernsteinSpace<Cube<Dim>>& s, const Eigen::Ref<const Eigen::VectorXd>& c, int axis,
                      Eigen::VectorXd& lower, Eigen::VectorXd& upper) {
  const int n = s.degree()[axis];
  lower.resize(s.size());
  upper = c;
  std::vector<double> line(n + 1), left(n + 1);
  Lattice<Dim> l{};
  for (int i = 0; i < s.size(); ++i) {
    if (s.lattice(i)[axis] != 0) continue;
    l = s.lattice(i);
    std::vector<int> idx(n + 1);
    for (int k = 0; k <= n; ++k) {
      l[axis] = k;
      idx[k] = s.index_of(l);
      line[k] = c[idx[k]];
    }
    detail::de_casteljau_half(line.data(), left.data(), n);
    for (int k = 0; k <= n; ++k) {
      lower[idx[k]] = left[k];
      upper[idx[k]] = line[k];
    }
  }
}

/// Splits a simplex polynomial at the midpoint m of the edge between its
/// barycentric vertices a and b (0..Dim; vertex 0 is the origin of the
/// reference simplex, vertex k the tip of e_k): `keep_a` is the piece with
/// vertex b replaced by m, `keep_b` the piece with vertex a replaced by m, both
/// in the barycentric coordinates of their own vertices (same slots).
template <int Dim>
void bernstein_bisect(const BernsteinSpace<Simplex<Dim>>& s, const Eigen::Ref<const Eigen::VectorXd>& c, int a, int b,
                      Eigen::VectorXd& keep_a, Eigen::VectorXd& keep_b) {
  if (a == b || a < 0 || b < 0 || a > Dim || b > Dim) throw std::invalid_argument("hom::bernstein_bisect: bad edge");
  const int n = s.degree()[0];
  keep_a.resize(s.size());
  keep_b.resize(s.size());
  // Barycentric multi-index of compact index i, and back.
  auto alpha_of = [&](int i) {
    std::array<int, Dim + 1> al{};
    al[0] = n;
    for (int k = 0; k < Dim; ++k) {
      al[k + 1] = s.lattice(i)[k];
      al[0] -= al[k + 1];
    }
    return al;
  };
  auto index_of_alpha = [&](const std::array<int, Dim + 1>& al) {
    Lattice<Dim> l;
    for (int k = 0; k < Dim; ++k) l[k] = al[k + 1];
    return s.index_of(l);
  };
  std::vector<double> line(n + 1), left(n + 1);
  std::vector<int> idx(n + 1);
  for (int i = 0; i < s.size(); ++i) {
    auto al = alpha_of(i);
    if (al[b] != 0) continue;  // one line per start (alpha_a = len, alpha_b = 0)
    const int len = al[a];
    for (int k = 0; k <= len; ++k) {
      al[a] = len - k;
      al[b] = k;
      idx[k] = index_of_alpha(al);
      line[k] = c[idx[k]];
    }
    detail::de_casteljau_half(line.data(), left.data(), len);
    for (int k = 0; k <= len; ++k) {
      keep_a[idx[k]] = left[k];   // alpha_b counts powers of the new vertex m
      keep_b[idx[k]] = line[k];   // alpha_a counts powers of m
    }
  }
}

/// Nodal values on a NodeSet -> Bernstein coefficients of the same degree-p
/// polynomial. Simplices: the inverse of M(i, j) = B_j(x_i) at the nodes,
/// built once and applied in long double (M's condition number grows with p;
/// long double keeps the conversion accurate to double round-off through
/// p = 10 and beyond). Cubes whose nodes form a tensor grid (every hom node set): the 1D
/// inverse along each axis; other cube node sets the dense inverse.
template <ElementFamily Family>
class LagrangeToBernstein {
 public:
  static constexpr int dim = Family::dim;
  using LDMatrix = Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic>;

  template <NodeSet Nodes>
  static LagrangeToBernstein build(int p) {
    LagrangeToBernstein t;
    t.degree_ = p;
    t.space_ = &bernstein_space<Family>(p);
    const auto nodes = Nodes::template points<Family>(p);
    const auto& layout = node_layout<Family>(p);
    t.position_.resize(nodes.size());
    for (std::size_t j = 0; j < nodes.size(); ++j) t.position_[j] = t.space_->index_of(layout.lattice(j));
    if constexpr (!Family::is_simplex) {
      // Tensor grid: node l at (r_0[l_0], .., r_{D-1}[l_{D-1}]).
      std::array<std::vector<double>, dim> r;
      for (int a = 0; a < dim; ++a) {
        Lattice<dim> l{};
        for (int k = 0; k <= p; ++k) {
          l[a] = k;
          r[a].push_back(nodes[layout.index_of(l)][a]);
        }
      }
      bool tensor = true;
      for (std::size_t j = 0; j < nodes.size(); ++j)
        for (int a = 0; a < dim; ++a) tensor = tensor && nodes[j][a] == r[a][layout.lattice(j)[a]];
      bool same_axes = true;
      for (int a = 1; a < dim; ++a) same_axes = same_axes && r[a] == r[0];
      if (tensor && same_axes) {
        using LD = Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic>;
        LD m(p + 1, p + 1);  // m(i, j) = C(p, j) t_i^j (1 - t_i)^(p - j), t_i = (1 + r_i) / 2
        for (int i = 0; i <= p; ++i) {
          const long double ti = (1.0L + r[0][i]) / 2;
          for (int j = 0; j <= p; ++j)
            m(i, j) = static_cast<long double>(detail::binomial(p, j)) * std::pow(ti, j) * std::pow(1.0L - ti, p - j);
        }
        t.inverse_1d_ = m.partialPivLu().inverse();
        t.tensor_ = true;
        return t;
      }
    }
    using LD = Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic>;
    const int n = t.space_->size();
    LD m(n, n);
    for (int i = 0; i < n; ++i) m.row(t.position_[i]) = t.space_->template values<long double>(nodes[i]).transpose();
    // m is indexed (compact position of node i, Bernstein j): b = m^{-1} f_compact.
    t.inverse_ = m.partialPivLu().inverse();
    return t;
  }

  int degree() const { return degree_; }
  const BernsteinSpace<Family>& space() const { return *space_; }

  /// F (rows x n, one column per node in hom's layout order) -> rows x size()
  /// Bernstein coefficients, compact order.
  Eigen::MatrixXd apply(const Eigen::Ref<const Eigen::MatrixXd>& f) const {
    // In long double: the inverse has entries of both signs much larger than
    // one at high p (equispaced nodes above all), and a double product would
    // lose their ratio's worth of digits in every coefficient.
    const int n = space_->size();
    LDMatrix g(f.rows(), n);
    for (int j = 0; j < n; ++j) g.col(position_[j]) = f.col(j).template cast<long double>();
    if (!tensor_) return LDMatrix(g * inverse_.transpose()).template cast<double>();
    // Along each axis: lines of p + 1 values, stride (p + 1)^a.
    const int p1 = degree_ + 1;
    Eigen::Matrix<long double, Eigen::Dynamic, 1> line(p1), out(p1);
    int stride = 1;
    for (int a = 0; a < dim; ++a, stride *= p1)
      for (Eigen::Index r = 0; r < g.rows(); ++r)
        for (int start = 0; start < n; ++start) {
          if ((start / stride) % p1 != 0) continue;
          for (int k = 0; k < p1; ++k) line[k] = g(r, start + k * stride);
          out.noalias() = inverse_1d_ * line;
          for (int k = 0; k < p1; ++k) g(r, start + k * stride) = out[k];
        }
    return g.template cast<double>();
  }

 private:
  int degree_ = 0;
  const BernsteinSpace<Family>* space_ = nullptr;
  std::vector<int> position_;  // compact Bernstein position of each layout node
  bool tensor_ = false;
  LDMatrix inverse_, inverse_1d_;
};

/// The shared conversion for (Family, Nodes, p) (built once; thread-safe).
template <ElementFamily Family, NodeSet Nodes>
const LagrangeToBernstein<Family>& lagrange_to_bernstein(int p) {
  static std::mutex mutex;
  static std::map<int, std::unique_ptr<LagrangeToBernstein<Family>>> cache;
  const std::lock_guard lock(mutex);
  auto& slot = cache[p];
  if (!slot) slot = std::make_unique<LagrangeToBernstein<Family>>(LagrangeToBernstein<Family>::template build<Nodes>(p));
  return *slot;
}

}  // namespace hom
