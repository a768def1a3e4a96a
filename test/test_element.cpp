// Tests of the reference element families, the local node layout and the
// linear sub-element split (include/hom/element/).
#include <doctest/doctest.h>

#include <algorithm>
#include <map>
#include <set>

#include <Eigen/Dense>

#include "hom/element/node_layout.hpp"
#include "hom/element/sub_elements.hpp"

using namespace hom;

#define HOM_FAMILIES Simplex<2>, Simplex<3>, Cube<2>, Cube<3>

namespace {

long binomial(int n, int k) {
  long r = 1;
  for (int i = 1; i <= k; ++i) r = r * (n - k + i) / i;
  return r;
}

// Signed volume of a linear simplex or an (affine-parallelepiped) cube cell.
template <ElementFamily F>
double signed_volume(const std::vector<typename F::Point>& x) {
  constexpr int D = F::dim;
  Eigen::Matrix<double, D, D> J;
  if constexpr (F::is_simplex) {
    for (int k = 0; k < D; ++k) J.col(k) = x[k + 1] - x[0];
    return J.determinant() / (D == 2 ? 2.0 : 6.0);
  } else {
    J.col(0) = x[1] - x[0];
    J.col(1) = x[3] - x[0];
    if constexpr (D == 3) J.col(2) = x[4] - x[0];
    return J.determinant();
  }
}

}  // namespace

TEST_CASE_TEMPLATE("n_p matches appendix A and the lattice size", F, HOM_FAMILIES) {
  for (int p = 1; p <= 12; ++p) {
    const long expected = F::is_simplex ? binomial(p + F::dim, F::dim) : (F::dim == 2 ? (p + 1L) * (p + 1) : (p + 1L) * (p + 1) * (p + 1));
    CHECK(F::num_nodes(p) == expected);
    CHECK(NodeLayout<F>(p).size() == expected);
  }
  CHECK(Simplex<2>::num_nodes(3) == 10);
  CHECK(Simplex<3>::num_nodes(10) == 286);
  CHECK(Cube<3>::num_nodes(4) == 125);
}

TEST_CASE_TEMPLATE("vertex weights reproduce the equispaced point", F, HOM_FAMILIES) {
  for (int p = 1; p <= 6; ++p) {
    const NodeLayout<F> layout(p);
    const double scale = F::is_simplex ? p : std::pow(double(p), F::dim);
    for (const auto& l : layout.lattice()) {
      const auto w = F::vertex_weights(l, p);
      typename F::Point x = F::Point::Zero();
      int sum = 0;
      for (int v = 0; v < F::num_vertices; ++v) {
        CHECK(w[v] >= 0);
        x += w[v] * F::vertex(v);
        sum += w[v];
      }
      CHECK(sum == doctest::Approx(scale));
      CHECK((x / scale - F::equispaced_point(l, p)).norm() < 1e-14);
    }
  }
}

TEST_CASE_TEMPLATE("layout: vertices, edges, faces, interior in order, each node once", F, HOM_FAMILIES) {
  for (int p = 1; p <= 10; ++p) {
    const NodeLayout<F> layout(p);
    // Distinct lattice points, all inside.
    std::set<Lattice<F::dim>> seen(layout.lattice().begin(), layout.lattice().end());
    CHECK(int(seen.size()) == layout.size());
    for (int i = 0; i < layout.size(); ++i) {
      CHECK(F::in_lattice(layout.lattice(i), p));
      CHECK(layout.index_of(layout.lattice(i)) == i);
    }
    // Entity dimension never decreases along the layout.
    for (int i = 1; i < layout.size(); ++i) CHECK(layout.entity(i - 1).dim <= layout.entity(i).dim);
    for (int v = 0; v < F::num_vertices; ++v) {
      CHECK(layout.entity(v) == NodeEntity{0, v});
      CHECK(layout.lattice(v) == F::vertex_lattice(v, p));
    }
    // Counts per entity.
    const auto edges = F::edges();
    int counted = F::num_vertices;
    for (int e = 0; e < int(edges.size()); ++e) {
      CHECK(int(layout.edge_nodes(e).size()) == p - 1);
      counted += p - 1;
    }
    if constexpr (F::dim == 3) {
      const int per_face = F::is_simplex ? (p - 1) * (p - 2) / 2 : (p - 1) * (p - 1);
      for (int f = 0; f < int(F::faces().size()); ++f) CHECK(int(layout.face_nodes(f).size()) == per_face);
      counted += per_face * int(F::faces().size());
    }
    counted += int(layout.interior_nodes().size());
    CHECK(counted == layout.size());
  }
}

TEST_CASE_TEMPLATE("edge nodes run from the first vertex to the second, equally spaced", F, HOM_FAMILIES) {
  for (int p = 1; p <= 10; ++p) {
    const NodeLayout<F> layout(p);
    const auto edges = F::edges();
    for (int e = 0; e < int(edges.size()); ++e) {
      const auto nodes = layout.closed_edge_nodes(e);
      REQUIRE(int(nodes.size()) == p + 1);
      const auto a = F::vertex(edges[e][0]), b = F::vertex(edges[e][1]);
      for (int k = 0; k <= p; ++k) {
        const auto x = F::equispaced_point(layout.lattice(nodes[k]), p);
        CHECK((x - (a + (b - a) * double(k) / p)).norm() < 1e-14);
      }
    }
  }
}

TEST_CASE_TEMPLATE("faces are outward oriented and face nodes follow the face-local lattice", F, Simplex<3>, Cube<3>) {
  const typename F::Point centroid = [] {
    typename F::Point c = F::Point::Zero();
    for (int v = 0; v < F::num_vertices; ++v) c += F::vertex(v);
    return typename F::Point(c / F::num_vertices);
  }();
  const auto faces = F::faces();
  for (const auto& f : faces) {
    const auto a = F::vertex(f[0]), b = F::vertex(f[1]), c = F::vertex(f[int(f.size()) - 1]);
    // Normal by the right-hand rule through f0 -> f1 -> ... ; outward = away from the centroid.
    const Eigen::Vector3d n = F::is_simplex ? Eigen::Vector3d((b - a).cross(F::vertex(f[2]) - a)) : Eigen::Vector3d((b - a).cross(c - a));
    CHECK(n.dot(a - centroid) > 0);
  }
  for (int p = 1; p <= 8; ++p) {
    const NodeLayout<F> layout(p);
    for (int fi = 0; fi < int(faces.size()); ++fi) {
      const auto& f = faces[fi];
      const auto& nodes = layout.face_nodes(fi);
      // Face-local (s, t) is strictly increasing in (t, s) order and reproduces the
      // node position from the face's own vertices.
      std::array<int, 2> prev{-1, -1};
      for (int n : nodes) {
        const auto st = NodeLayout<F>::face_local(layout.lattice(n), fi, p);
        CHECK(std::array<int, 2>{st[1], st[0]} > prev);
        prev = {st[1], st[0]};
        const auto x = F::equispaced_point(layout.lattice(n), p);
        typename F::Point y;
        if constexpr (F::is_simplex) {
          y = F::vertex(f[0]) + (F::vertex(f[1]) - F::vertex(f[0])) * double(st[0]) / p +
              (F::vertex(f[2]) - F::vertex(f[0])) * double(st[1]) / p;
        } else {
          y = F::vertex(f[0]) + (F::vertex(f[1]) - F::vertex(f[0])) * double(st[0]) / p +
              (F::vertex(f[3]) - F::vertex(f[0])) * double(st[1]) / p;
        }
        CHECK((x - y).norm() < 1e-14);
      }
    }
  }
}

TEST_CASE_TEMPLATE("a shared face numbers its nodes identically from both elements", F, Simplex<3>, Cube<3>) {
  // Two elements sharing a face, glued by an affine reflection: the face's
  // interior nodes must be identified through their (global vertex, weight)
  // keys, and the face-local order must agree once the vertex order agrees.
  for (int p = 2; p <= 7; ++p) {
    const NodeLayout<F> layout(p);
    const auto faces = F::faces();
    for (int fi = 0; fi < int(faces.size()); ++fi) {
      const auto& f = faces[fi];
      const auto& nodes = layout.face_nodes(fi);
      // Key: weights on the face's vertices, listed in face order.
      std::map<std::vector<int>, int> by_key;
      for (int n : nodes) {
        const auto w = F::vertex_weights(layout.lattice(n), p);
        std::vector<int> key;
        for (int v : f) key.push_back(w[v]);
        by_key[key] = n;
        // No weight off the face.
        int off = 0;
        for (int v = 0; v < F::num_vertices; ++v)
          if (std::find(f.begin(), f.end(), v) == f.end()) off += w[v];
        CHECK(off == 0);
      }
      CHECK(by_key.size() == nodes.size());
    }
  }
}

TEST_CASE_TEMPLATE("linear sub-elements cover the element with positive orientation", F, HOM_FAMILIES) {
  for (int p = 1; p <= 10; ++p) {
    const auto subs = linear_sub_elements<F>(p);
    const int expected = F::dim == 2 ? p * p : p * p * p;
    CHECK(int(subs.size()) == expected);
    const auto& layout = node_layout<F>(p);
    double total = 0;
    std::set<std::vector<int>> distinct;
    for (const auto& s : subs) {
      std::vector<typename F::Point> x;
      for (int n : s) {
        REQUIRE(n >= 0);
        REQUIRE(n < layout.size());
        x.push_back(F::equispaced_point(layout.lattice(n), p));
      }
      const double v = signed_volume<F>(x);
      CHECK(v > 0);
      total += v;
      std::vector<int> sorted(s.begin(), s.end());
      std::sort(sorted.begin(), sorted.end());
      distinct.insert(sorted);
    }
    CHECK(total == doctest::Approx(F::reference_volume()).epsilon(1e-12));
    CHECK(int(distinct.size()) == expected);
  }
}

TEST_CASE("tetrahedral split cells do not overlap: every interior sample lies in exactly one") {
  // Volumes summing to the element's does not rule out overlap plus gaps; count
  // containment of random points.
  const int p = 4;
  const auto subs = linear_sub_elements<Simplex<3>>(p);
  const auto& layout = node_layout<Simplex<3>>(p);
  std::srand(7);
  for (int trial = 0; trial < 400; ++trial) {
    Eigen::Vector3d y = Eigen::Vector3d::Random().cwiseAbs();
    if (y.sum() >= 1) continue;
    int containing = 0;
    for (const auto& s : subs) {
      Eigen::Matrix3d J;
      const auto x0 = Simplex<3>::equispaced_point(layout.lattice(s[0]), p);
      for (int k = 0; k < 3; ++k) J.col(k) = Simplex<3>::equispaced_point(layout.lattice(s[k + 1]), p) - x0;
      const Eigen::Vector3d b = J.partialPivLu().solve(y - x0);
      if (b.minCoeff() > -1e-12 && b.sum() < 1 + 1e-12) ++containing;
    }
    CHECK(containing == 1);
  }
}
