#pragma once
/// @file mesh_cut.hpp
/// A planar cut through a curved tetrahedral mesh, for the figures of
/// bench_boundary_layer (issue 9): the polygons where a plane meets each
/// element's degree-p map phi_e, not its straight-sided vertices, so that the
/// curved layer elements show as they are.
///
/// An element whose nodes come near the plane is split into the linear
/// sub-tetrahedra of the equispaced degree-n lattice (element/sub_elements.hpp),
/// their vertices mapped through phi_e (the mesh's own Lagrange basis,
/// tabulated once at the lattice points), and each sub-tetrahedron is cut as a
/// linear one: nothing, a triangle or a convex quadrilateral. The cut is then
/// phi_e's piecewise-linear interpolant on the lattice, O((h / n)^2) off.
///
/// write_cut_csv writes one row per polygon vertex, read by
/// bench/plot_cut.py (and plot_boundary_layer.py, which uses it).

#include <algorithm>
#include <array>
#include <cstdio>
#include <iomanip>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "hom/element/node_layout.hpp"
#include "hom/element/simplex.hpp"
#include "hom/element/sub_elements.hpp"
#include "hom/io/error.hpp"
#include "hom/mesh/mesh.hpp"
#include "hom/quality/mesh_quality.hpp"

namespace hom::bench {

/// The plane through `origin` spanned by the orthonormal axes u and v; the
/// cut's points are written in (u, v) coordinates relative to `origin`.
struct CutPlane {
  Eigen::Vector3d origin, u, v, normal;

  CutPlane(const Eigen::Vector3d& o, const Eigen::Vector3d& axis_u, const Eigen::Vector3d& axis_v)
      : origin(o), u(axis_u.normalized()), v(axis_v.normalized()), normal(u.cross(v).normalized()) {}

  /// The plane z = origin.z, seen with x to the right and y up.
  static CutPlane normal_z(const Eigen::Vector3d& o) { return {o, Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY()}; }

  double height(const Eigen::Vector3d& x) const { return normal.dot(x - origin); }
  Eigen::Vector2d in_plane(const Eigen::Vector3d& x) const { return {u.dot(x - origin), v.dot(x - origin)}; }
};

/// One polygon of the cut (a triangle or a convex quadrilateral, vertices in
/// order around it), inside one element.
struct CutPolygon {
  int element = 0;
  std::vector<Eigen::Vector2d> points;
};

namespace detail {

/// Whether element e can meet the plane: its nodes' heights above it span 0.
/// The margin (a twentieth of the nodes' bounding box) is there because a
/// curved element may bulge past its nodes between them.
template <class Nodes>
bool near_plane(const Mesh<Simplex<3>, Nodes>& mesh, int e, const CutPlane& plane) {
  const Eigen::Matrix3Xd x = mesh.element_coordinates(e);
  const double margin = 0.05 * (x.rowwise().maxCoeff() - x.rowwise().minCoeff()).norm();
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (Eigen::Index i = 0; i < x.cols(); ++i) {
    const double h = plane.height(x.col(i));
    lo = std::min(lo, h);
    hi = std::max(hi, h);
  }
  return lo <= margin && hi >= -margin;
}

/// Where the plane crosses the lattice edge (a, b), whose ends lie on opposite
/// sides (heights d). Always computed from the smaller index, so that the
/// sub-tetrahedra sharing the edge get the same bits: the plot finds an
/// element's outline as the polygon edges that no other polygon of it shares.
inline Eigen::Vector3d crossing(int a, int b, const Eigen::Matrix3Xd& x, const Eigen::VectorXd& d) {
  if (a > b) std::swap(a, b);
  const double t = d[a] / (d[a] - d[b]);
  return x.col(a) + t * (x.col(b) - x.col(a));
}

/// The cut of the linear tetrahedron with lattice vertices s: empty, a
/// triangle (one vertex alone on its side) or a quadrilateral (two and two).
/// A vertex on the plane counts as below it, so a face lying in the plane is
/// cut once, by the tetrahedron above it, and not by both.
inline std::vector<Eigen::Vector3d> cut_tetrahedron(const std::array<int, 4>& s, const Eigen::Matrix3Xd& x,
                                                    const Eigen::VectorXd& d) {
  std::vector<int> above, below;
  for (int k : s) (d[k] > 0.0 ? above : below).push_back(k);
  auto at = [&](int a, int b) { return crossing(a, b, x, d); };
  if (above.empty() || below.empty()) return {};
  if (above.size() == 1) return {at(above[0], below[0]), at(above[0], below[1]), at(above[0], below[2])};
  if (below.size() == 1) return {at(below[0], above[0]), at(below[0], above[1]), at(below[0], above[2])};
  // Consecutive points share a vertex of the tetrahedron, so they are joined
  // by an edge of the section: the ring goes around the (convex) quadrilateral.
  return {at(above[0], below[0]), at(above[0], below[1]), at(above[1], below[1]), at(above[1], below[0])};
}

/// The lattice of degree n on the reference tetrahedron: its linear
/// sub-tetrahedra and a mesh basis tabulated at its points (#points x n_p),
/// so that phi_e at every point is one matrix product per element.
struct CutLattice {
  std::vector<SubElement<Simplex<3>>> sub;
  Eigen::MatrixXd basis;

  template <class Nodes>
  CutLattice(const Mesh<Simplex<3>, Nodes>& mesh, int n)
      : sub(linear_sub_elements<Simplex<3>>(n)), basis(mesh.basis().values(node_layout<Simplex<3>>(n).equispaced_points())) {}
};

template <class Nodes>
void cut_element(const Mesh<Simplex<3>, Nodes>& mesh, int e, const CutPlane& plane, const CutLattice& lattice,
                 std::vector<CutPolygon>& out) {
  const Eigen::Matrix3Xd x = mesh.element_coordinates(e) * lattice.basis.transpose();
  Eigen::VectorXd d(x.cols());
  for (Eigen::Index i = 0; i < x.cols(); ++i) d[i] = plane.height(x.col(i));
  for (const auto& s : lattice.sub) {
    const auto points = cut_tetrahedron(s, x, d);
    if (points.empty()) continue;
    CutPolygon poly{e, {}};
    for (const auto& p : points) poly.points.push_back(plane.in_plane(p));
    out.push_back(std::move(poly));
  }
}

}  // namespace detail

/// The lattice degree the harnesses cut with: 2p sub-intervals per edge, so that
/// the piecewise-linear cut sits within a small fraction of the curving from the
/// true one (test_mesh_cut measures the error's second order).
inline int cut_lattice_degree(int mesh_degree) { return std::max(2, 2 * mesh_degree); }

/// The cut of the curved mesh by `plane`, every element near it split into the
/// sub-tetrahedra of the degree-n lattice (n >= 2p keeps the piecewise-linear
/// error well below the curving).
template <class Nodes>
std::vector<CutPolygon> cut_mesh(const Mesh<Simplex<3>, Nodes>& mesh, const CutPlane& plane, int n) {
  const detail::CutLattice lattice(mesh, n);
  std::vector<CutPolygon> out;
  for (int e = 0; e < mesh.num_elements(); ++e)
    if (detail::near_plane(mesh, e, plane)) detail::cut_element(mesh, e, plane, lattice, out);
  return out;
}

/// The cut as CSV, one row per polygon vertex: element, polygon, in-plane x
/// and y, and the element's quality, inverted flag (quality is 0 for an
/// inverted element, which the flag tells apart from a merely poor one) and
/// layer level (-1 outside the layer). Ten significant digits: enough for a
/// first layer 1e-4 thick, and equal points stay equal text.
inline void write_cut_csv(const std::string& path, const std::vector<CutPolygon>& polygons, const MeshQuality& quality,
                          const std::vector<std::optional<int>>& level) {
  std::ostringstream s;
  s << std::setprecision(10) << "element,polygon,x,y,quality,inverted,level\n";
  for (std::size_t k = 0; k < polygons.size(); ++k) {
    const int e = polygons[k].element;
    const auto& q = quality.elements[e];
    for (const auto& p : polygons[k].points)
      s << e << ',' << k << ',' << p[0] << ',' << p[1] << ',' << q.quality << ',' << (q.valid ? 0 : 1) << ','
        << (level[e] ? *level[e] : -1) << '\n';
  }
  const std::string text = s.str();
  io::write_atomically(path, [&](std::FILE* f) { io::write_all(f, path, text.data(), text.size()); });
}

/// The cut of `mesh` by the plane z through the middle of its bounding box
/// (the cavity's centre of the cube meshes of tables 4.1, 4.2), on the
/// cut_lattice_degree lattice, written by write_cut_csv with no layer levels.
template <class Nodes>
void write_mid_z_cut_csv(const std::string& path, const Mesh<Simplex<3>, Nodes>& mesh, const MeshQuality& quality) {
  const Eigen::Vector3d centre = 0.5 * (mesh.nodes().rowwise().minCoeff() + mesh.nodes().rowwise().maxCoeff());
  const auto polygons = cut_mesh(mesh, CutPlane::normal_z(centre), cut_lattice_degree(mesh.degree()));
  write_cut_csv(path, polygons, quality, std::vector<std::optional<int>>(mesh.num_elements()));
}

}  // namespace hom::bench
