// Tests of the node sets (include/hom/nodes/): every model on every family it
// supports, degrees 1..10.
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <vector>

#include <Eigen/Dense>

#include "hom/element/node_layout.hpp"
#include "hom/nodes/equispaced.hpp"
#include "hom/nodes/gauss_lobatto.hpp"
#include "hom/nodes/node_set.hpp"
#include "hom/nodes/warp_blend.hpp"
#include "hom/quadrature/gauss_jacobi.hpp"

using namespace hom;

#define HOM_FAMILIES Simplex<2>, Simplex<3>, Cube<2>, Cube<3>

static_assert(NodeSet<Equispaced> && NodeSet<WarpBlend> && NodeSet<GaussLobatto>);
static_assert(NodeSetFor<GaussLobatto, Cube<2>> && !NodeSetFor<GaussLobatto, Simplex<3>>);

namespace {

constexpr int max_p = 10;

// Calls f.template operator()<N>() for every node set N that supports F.
template <ElementFamily F, class Fn>
void for_each_node_set(Fn&& f) {
  f.template operator()<Equispaced>();
  f.template operator()<WarpBlend>();
  if constexpr (GaussLobatto::supports<F>) f.template operator()<GaussLobatto>();
}

// Vertex ids of face f (3D) or of the element (2D).
template <ElementFamily F>
std::vector<int> face_vertices(int f) {
  if constexpr (F::dim == 3) {
    const auto fv = F::faces()[f];
    return std::vector<int>(fv.begin(), fv.end());
  } else {
    (void)f;
    std::vector<int> v(F::num_vertices);
    std::iota(v.begin(), v.end(), 0);
    return v;
  }
}

// Is x in the closed reference element (tolerance tol)?
template <ElementFamily F>
bool inside(const typename F::Point& x, double tol) {
  if constexpr (F::is_simplex)
    return x.minCoeff() >= -tol && x.sum() <= 1.0 + tol;
  else
    return x.cwiseAbs().maxCoeff() <= 1.0 + tol;
}

// Distance from x to the line through a and b, and the line parameter.
template <class P>
std::pair<double, double> line_distance(const P& x, const P& a, const P& b) {
  const P d = b - a;
  const double t = (x - a).dot(d) / d.squaredNorm();
  return {(x - a - t * d).norm(), t};
}

// Distance from x to the plane through three points.
inline double plane_distance(const Eigen::Vector3d& x, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                             const Eigen::Vector3d& c) {
  const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
  return std::abs((x - a).dot(n));
}

// Distances of x (inside the element) to each facet's hyperplane, in
// barycentric / coordinate units.
template <ElementFamily F>
std::vector<double> facet_distances(const typename F::Point& x) {
  std::vector<double> d;
  if constexpr (F::is_simplex) {
    d.push_back(std::abs(1.0 - x.sum()));
    for (int k = 0; k < F::dim; ++k) d.push_back(std::abs(x[k]));
  } else {
    for (int k = 0; k < F::dim; ++k) {
      d.push_back(std::abs(1.0 + x[k]));
      d.push_back(std::abs(1.0 - x[k]));
    }
  }
  return d;
}

}  // namespace

TEST_CASE_TEMPLATE("node sets: count, containment, vertices, distinct nodes", F, HOM_FAMILIES) {
  for_each_node_set<F>([]<class N>() {
    for (int p = 1; p <= max_p; ++p) {
      CAPTURE(N::name);
      CAPTURE(p);
      const auto x = N::template points<F>(p);
      REQUIRE(int(x.size()) == F::num_nodes(p));
      for (const auto& xi : x) CHECK(inside<F>(xi, 1e-14));
      for (int v = 0; v < F::num_vertices; ++v) CHECK((x[v] - F::vertex(v)).norm() == 0.0);
      // Distinct: the closest pair is a fair fraction of the equispaced spacing
      // divided by p (GLL spacing near the ends is ~ 1/p^2).
      const double h = F::is_simplex ? 1.0 / p : 2.0 / p;
      double dmin = 1e300;
      for (std::size_t i = 0; i < x.size(); ++i)
        for (std::size_t j = i + 1; j < x.size(); ++j) dmin = std::min(dmin, (x[i] - x[j]).norm());
      CHECK(dmin > 0.1 * h / p);
    }
  });
}

TEST_CASE_TEMPLATE("node sets: nodes lie on their vertex, edge, face or interior", F, HOM_FAMILIES) {
  for_each_node_set<F>([]<class N>() {
    for (int p = 1; p <= max_p; ++p) {
      CAPTURE(N::name);
      CAPTURE(p);
      const auto& layout = node_layout<F>(p);
      const auto x = N::template points<F>(p);
      const auto edges = F::edges();
      for (int e = 0; e < int(edges.size()); ++e) {
        const auto a = F::vertex(edges[e][0]), b = F::vertex(edges[e][1]);
        const auto nodes = layout.closed_edge_nodes(e);
        double last = -1.0;
        for (int n : nodes) {
          const auto [dist, t] = line_distance(x[n], a, b);
          CHECK(dist <= 1e-14);
          CHECK(t > last);  // monotone from the first vertex to the second
          last = t;
        }
        CHECK(std::abs(last - 1.0) <= 1e-15);
      }
      if constexpr (F::dim == 3) {
        const auto faces = F::faces();
        for (int f = 0; f < int(faces.size()); ++f) {
          const auto fv = face_vertices<F>(f);
          for (int n : layout.face_nodes(f))
            CHECK(plane_distance(x[n], F::vertex(fv[0]), F::vertex(fv[1]), F::vertex(fv[2])) <= 1e-14);
        }
      }
      // A node of a d-dimensional entity lies on exactly Dim - d facets of the
      // element (to round-off) and clearly away from the others.
      for (int n = 0; n < layout.size(); ++n) {
        const auto dist = facet_distances<F>(x[n]);
        int on = 0, near = 0;
        for (double d : dist) {
          on += d <= 1e-14;
          near += d > 1e-14 && d < 1e-3;
        }
        CHECK(on == F::dim - layout.entity(n).dim);
        CHECK(near == 0);
      }
    }
  });
}

TEST_CASE_TEMPLATE("node sets: an edge's nodes are the same seen from both ends", F, HOM_FAMILIES) {
  for_each_node_set<F>([]<class N>() {
    for (int p = 1; p <= max_p; ++p) {
      CAPTURE(N::name);
      CAPTURE(p);
      const auto& layout = node_layout<F>(p);
      const auto x = N::template points<F>(p);
      const auto edges = F::edges();
      for (int e = 0; e < int(edges.size()); ++e) {
        const auto a = F::vertex(edges[e][0]), b = F::vertex(edges[e][1]);
        const auto nodes = layout.closed_edge_nodes(e);
        for (int k = 0; k <= p; ++k) {
          // Mirror through the edge midpoint: a + b - x.
          const typename F::Point mirrored = a + b - x[nodes[p - k]];
          CHECK((x[nodes[k]] - mirrored).cwiseAbs().maxCoeff() <= 1e-15);
        }
      }
    }
  });
}

namespace {

// All symmetries of the reference element, each as a map on lattice indices
// and the matching affine map on points.
template <ElementFamily F>
struct Symmetry {
  std::array<int, F::num_vertices> perm{};  // simplex: vertex i -> perm[i]
  std::array<int, F::dim> axes{};           // cube: new axis d takes old axis axes[d]
  std::array<bool, F::dim> flip{};          // cube: then reflect new axis d

  Lattice<F::dim> map(const Lattice<F::dim>& l, int p) const {
    Lattice<F::dim> out{};
    if constexpr (F::is_simplex) {
      const auto w = F::vertex_weights(l, p);
      std::array<int, F::num_vertices> wn{};
      for (int i = 0; i < F::num_vertices; ++i) wn[perm[i]] = w[i];
      for (int d = 0; d < F::dim; ++d) out[d] = wn[d + 1];
    } else {
      for (int d = 0; d < F::dim; ++d) out[d] = flip[d] ? p - l[axes[d]] : l[axes[d]];
    }
    return out;
  }

  typename F::Point map(const typename F::Point& x) const {
    typename F::Point y;
    if constexpr (F::is_simplex) {
      std::array<double, F::num_vertices> lam{}, ln{};
      lam[0] = 1.0 - x.sum();
      for (int d = 0; d < F::dim; ++d) lam[d + 1] = x[d];
      for (int i = 0; i < F::num_vertices; ++i) ln[perm[i]] = lam[i];
      for (int d = 0; d < F::dim; ++d) y[d] = ln[d + 1];
    } else {
      for (int d = 0; d < F::dim; ++d) y[d] = flip[d] ? -x[axes[d]] : x[axes[d]];
    }
    return y;
  }
};

template <ElementFamily F>
std::vector<Symmetry<F>> symmetries() {
  std::vector<Symmetry<F>> out;
  if constexpr (F::is_simplex) {
    std::array<int, F::num_vertices> perm{};
    std::iota(perm.begin(), perm.end(), 0);
    do {
      Symmetry<F> s;
      s.perm = perm;
      out.push_back(s);
    } while (std::next_permutation(perm.begin(), perm.end()));
  } else {
    std::array<int, F::dim> axes{};
    std::iota(axes.begin(), axes.end(), 0);
    do {
      for (int mask = 0; mask < (1 << F::dim); ++mask) {
        Symmetry<F> s;
        s.axes = axes;
        for (int d = 0; d < F::dim; ++d) s.flip[d] = (mask >> d) & 1;
        out.push_back(s);
      }
    } while (std::next_permutation(axes.begin(), axes.end()));
  }
  return out;
}

}  // namespace

TEST_CASE_TEMPLATE("node sets: invariant under the element's symmetry group", F, HOM_FAMILIES) {
  const auto syms = symmetries<F>();
  CHECK(syms.size() == (F::is_simplex ? (F::dim == 2 ? 6u : 24u) : (F::dim == 2 ? 8u : 48u)));
  for_each_node_set<F>([&]<class N>() {
    for (int p = 1; p <= max_p; ++p) {
      CAPTURE(N::name);
      CAPTURE(p);
      const auto& layout = node_layout<F>(p);
      const auto x = N::template points<F>(p);
      double worst = 0.0;
      for (const auto& s : syms)
        for (int n = 0; n < layout.size(); ++n) {
          const int m = layout.index_of(s.map(layout.lattice(n), p));
          REQUIRE(m >= 0);
          worst = std::max(worst, (s.map(x[n]) - x[m]).cwiseAbs().maxCoeff());
        }
      CHECK(worst <= 1e-14);
    }
  });
}

TEST_CASE_TEMPLATE("warp & blend: edge nodes are the GLL points of the edge", F, HOM_FAMILIES) {
  for (int p = 1; p <= max_p; ++p) {
    CAPTURE(p);
    const auto& layout = node_layout<F>(p);
    const auto x = WarpBlend::points<F>(p);
    const Eigen::VectorXd r = gauss_lobatto_legendre(p + 1).points;  // independent of the node code
    const auto edges = F::edges();
    for (int e = 0; e < int(edges.size()); ++e) {
      const auto a = F::vertex(edges[e][0]), b = F::vertex(edges[e][1]);
      const auto nodes = layout.closed_edge_nodes(e);
      for (int k = 0; k <= p; ++k) {
        const typename F::Point expected = a + 0.5 * (1.0 + r[k]) * (b - a);
        CHECK((x[nodes[k]] - expected).cwiseAbs().maxCoeff() <= 1e-14);
      }
    }
  }
}

TEST_CASE_TEMPLATE("cubes: WarpBlend and GaussLobatto are the tensor GLL nodes", F, Cube<2>, Cube<3>) {
  for (int p = 1; p <= max_p; ++p) {
    const auto& layout = node_layout<F>(p);
    const Eigen::VectorXd r = gauss_lobatto_legendre(p + 1).points;
    const auto wb = WarpBlend::points<F>(p);
    const auto gl = GaussLobatto::points<F>(p);
    for (int n = 0; n < layout.size(); ++n) {
      typename F::Point expected;
      for (int d = 0; d < F::dim; ++d) expected[d] = r[layout.lattice(n)[d]];
      CHECK((gl[n] - expected).cwiseAbs().maxCoeff() <= 1e-15);
      CHECK((wb[n] - gl[n]).norm() == 0.0);
    }
  }
}

TEST_CASE_TEMPLATE("equispaced nodes are Family::equispaced_point in layout order", F, HOM_FAMILIES) {
  for (int p = 1; p <= max_p; ++p) {
    const auto& layout = node_layout<F>(p);
    const auto x = Equispaced::points<F>(p);
    for (int n = 0; n < layout.size(); ++n) CHECK((x[n] - F::equispaced_point(layout.lattice(n), p)).norm() == 0.0);
  }
}

TEST_CASE_TEMPLATE("warp & blend on simplices: reduces to equispaced for p <= 2, moves nodes for p >= 3", F,
                   Simplex<2>, Simplex<3>) {
  for (int p = 1; p <= max_p; ++p) {
    CAPTURE(p);
    const auto eq = Equispaced::points<F>(p);
    const auto wb = WarpBlend::points<F>(p);
    double moved = 0.0;
    for (std::size_t n = 0; n < eq.size(); ++n) moved = std::max(moved, (eq[n] - wb[n]).norm());
    // GLL and equispaced points coincide for p <= 2 only.
    if (p <= 2)
      CHECK(moved <= 1e-15);
    else
      CHECK(moved > 1e-3);
    // The blending parameter only changes nodes off the edges.
    if (p >= 3) {
      const auto wb0 = WarpBlend::points<F>(p, 0.0);
      const auto& layout = node_layout<F>(p);
      for (int n = 0; n < layout.size(); ++n)
        if (layout.entity(n).dim <= 1) CHECK((wb0[n] - wb[n]).norm() == 0.0);
    }
  }
}

TEST_CASE("warp & blend alpha tables") {
  // Published values (Warburton 2006; Hesthaven & Warburton, Nodes2D / Nodes3D).
  CHECK(warp_blend_alpha_triangle(3) == doctest::Approx(1.4152));
  CHECK(warp_blend_alpha_triangle(10) == doctest::Approx(1.4773));
  CHECK(warp_blend_alpha_triangle(15) == doctest::Approx(1.6258));
  CHECK(warp_blend_alpha_triangle(16) == doctest::Approx(5.0 / 3.0));
  CHECK(warp_blend_alpha_tetrahedron(3) == 0.0);
  CHECK(warp_blend_alpha_tetrahedron(5) == doctest::Approx(1.1332));
  CHECK(warp_blend_alpha_tetrahedron(10) == doctest::Approx(1.10153));
  CHECK(warp_blend_alpha_tetrahedron(15) == doctest::Approx(0.9655));
}
