#pragma once
/// @file repair_patch.hpp
/// The bookkeeping of a certify-and-repair round (optimize/certified.hpp for
/// volume and planar meshes, surface/certified_surface.hpp for surface
/// meshes): the elements of each node, the sentinel points a round watches,
/// whether a fold can be mended by the free nodes, the rings of elements
/// around the failing ones and the round's local problem.

#include <algorithm>
#include <vector>

#include <Eigen/Core>

#include "hom/basis/lagrange.hpp"
#include "hom/element/family.hpp"
#include "hom/nodes/node_set.hpp"
#include "hom/quality/certify.hpp"

namespace hom::detail {

/// The elements of each node, in compressed rows: node k's elements are
/// element[offset[k]] ... element[offset[k + 1] - 1], ascending.
struct NodeElements {
  std::vector<int> offset, element;

  template <class Connectivity>
  NodeElements(const Connectivity& conn, int num_nodes) : offset(num_nodes + 1, 0) {
    const int ne = int(conn.cols()), npe = int(conn.rows());
    for (int e = 0; e < ne; ++e)
      for (int i = 0; i < npe; ++i) ++offset[conn(i, e) + 1];
    for (int k = 0; k < num_nodes; ++k) offset[k + 1] += offset[k];
    element.resize(offset[num_nodes]);
    std::vector<int> fill(offset.begin(), offset.end() - 1);
    for (int e = 0; e < ne; ++e)
      for (int i = 0; i < npe; ++i) element[fill[conn(i, e)]++] = e;
  }
};

/// The reference points a repair round adds to the quadrature rule: the
/// element's vertices from the first round on (a corner fold is invisible to
/// every interior quadrature point), then the points where certification
/// found det <= 0 or came closest to it, each once.
template <ElementFamily Family>
class SentinelPoints {
 public:
  using Point = typename Family::Point;

  SentinelPoints() {
    for (int v = 0; v < Family::num_vertices; ++v) points_.push_back(Family::vertex(v));
  }
  void add(const Point& x) {
    for (const auto& s : points_)
      if ((s - x).squaredNorm() <= 1e-24) return;
    points_.push_back(x);
  }
  /// Adds the invalid and weakest points of a certificate.
  void add(const ElementCertificate<Family>& c) {
    if (c.invalid_point) add(*c.invalid_point);
    if (c.weakest_point) add(*c.weakest_point);
  }
  const std::vector<Point>& points() const { return points_; }
  std::size_t size() const { return points_.size(); }

 private:
  std::vector<Point> points_;
};

/// Whether det at the certified-invalid point of element e depends on a free
/// node: det at a point reads only the nodes whose shape functions have a
/// non-zero gradient there, so a fold where all of them are held stays
/// whatever the optimizer does. True when no invalid point is known.
template <ElementFamily Family, NodeSet Nodes, class Connectivity, class FreeMask>
bool fold_depends_on_free_node(int p, const ElementCertificate<Family>& c, const Connectivity& conn, int e,
                               const FreeMask& free) {
  if (!c.invalid_point) return true;
  const Eigen::MatrixXd g = lagrange_basis<Family, Nodes>(p).gradient(*c.invalid_point);  // n x dim
  const double scale = g.rowwise().norm().maxCoeff();
  for (Eigen::Index i = 0; i < conn.rows(); ++i)
    if (free[conn(i, e)] && g.row(i).norm() > 1e-12 * scale) return true;
  return false;
}

/// Element rings around `seeds`: level[e] = 0 for a seed, r for an element
/// sharing a node with one of level r - 1 (r <= rings), -1 beyond.
template <class Connectivity>
std::vector<int> element_rings(const Connectivity& conn, const NodeElements& by_node, const std::vector<int>& seeds,
                               int rings) {
  std::vector<int> level(conn.cols(), -1);
  std::vector<int> frontier = seeds;
  for (int e : seeds) level[e] = 0;
  for (int r = 1; r <= rings; ++r) {
    std::vector<int> next;
    for (int e : frontier)
      for (Eigen::Index i = 0; i < conn.rows(); ++i) {
        const int node = conn(i, e);
        for (int k = by_node.offset[node]; k < by_node.offset[node + 1]; ++k)
          if (level[by_node.element[k]] < 0) {
            level[by_node.element[k]] = r;
            next.push_back(by_node.element[k]);
          }
      }
    frontier = std::move(next);
  }
  return level;
}

/// A repair round's local problem: the free nodes of the elements within
/// `rings` element rings of the failing ones, and every element with such a
/// node (the rest of the mesh is held), numbered locally.
struct RepairPatch {
  std::vector<int> elements;    ///< the problem's mesh elements, ascending
  std::vector<int> nodes;       ///< the mesh node of each local node
  std::vector<bool> free;       ///< whether each local node moves
  std::vector<double> weight;   ///< pull-back weight of each local node: 1 - ring / (rings + 1)
  Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic> connectivity;  ///< local, one column per element
  int num_free = 0;
};

template <class Connectivity, class FreeMask>
RepairPatch repair_patch(const Connectivity& conn, int num_nodes, const NodeElements& by_node,
                         const std::vector<int>& failing, int rings, const FreeMask& mesh_free) {
  const int ne = int(conn.cols()), npe = int(conn.rows());
  const std::vector<int> level = element_rings(conn, by_node, failing, rings);
  std::vector<char> free_node(num_nodes, 0), in_problem(ne, 0);
  std::vector<int> node_level(num_nodes, rings + 1);
  RepairPatch patch;
  for (int e = 0; e < ne; ++e)
    if (level[e] >= 0)
      for (int i = 0; i < npe; ++i) {
        const int node = conn(i, e);
        node_level[node] = std::min(node_level[node], level[e]);
        if (mesh_free[node] && !free_node[node]) {
          free_node[node] = 1;
          ++patch.num_free;
          for (int k = by_node.offset[node]; k < by_node.offset[node + 1]; ++k) in_problem[by_node.element[k]] = 1;
        }
      }
  std::vector<int> local(num_nodes, -1);
  for (int e = 0; e < ne; ++e)
    if (in_problem[e]) {
      patch.elements.push_back(e);
      for (int i = 0; i < npe; ++i)
        if (local[conn(i, e)] < 0) {
          local[conn(i, e)] = int(patch.nodes.size());
          patch.nodes.push_back(conn(i, e));
        }
    }
  for (int node : patch.nodes) {
    patch.free.push_back(free_node[node] != 0);
    patch.weight.push_back(1.0 - double(node_level[node]) / double(rings + 1));
  }
  patch.connectivity.resize(npe, Eigen::Index(patch.elements.size()));
  for (std::size_t b = 0; b < patch.elements.size(); ++b)
    for (int i = 0; i < npe; ++i) patch.connectivity(i, Eigen::Index(b)) = local[conn(i, patch.elements[b])];
  return patch;
}

/// The elements not certified valid (`any`: whether there is one) and, of
/// those, the ones whose fold depends on a free node (the returned list).
template <ElementFamily Family, NodeSet Nodes, class Connectivity, class FreeMask>
std::vector<int> repairable_elements(int p, const std::vector<ElementCertificate<Family>>& cert,
                                     const Connectivity& conn, const FreeMask& free, bool& any) {
  std::vector<int> failing;
  any = false;
  for (int e = 0; e < int(cert.size()); ++e)
    if (cert[e].status != Certificate::certified_valid) {
      any = true;
      if (fold_depends_on_free_node<Family, Nodes>(p, cert[e], conn, e, free)) failing.push_back(e);
    }
  return failing;
}

}  // namespace hom::detail
