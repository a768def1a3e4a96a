// Ears of a linear 2D mesh from CAD (see ears.hpp).
#include "ears.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <span>
#include <unordered_map>
#include <utility>
#include <vector>

#include "hom/mesh/flat_corners.hpp"

namespace hom::cad {

namespace {

constexpr int gmsh_line = 1;
constexpr int gmsh_triangle = 2;
constexpr int gmsh_quad = 3;
constexpr int gmsh_tetrahedron = 4;

using Edge = std::pair<std::int64_t, std::int64_t>;
using Triangle = std::array<std::int64_t, 3>;
using Tetrahedron = std::array<std::int64_t, 4>;

Edge edge_key(std::int64_t a, std::int64_t b) { return a < b ? Edge{a, b} : Edge{b, a}; }

Triangle triangle_key(Triangle t) {
  std::sort(t.begin(), t.end());
  return t;
}

/// What both splits share: the curve of each boundary line, node lookup, new
/// nodes on a face, and the rebuilt element list.
class EarSplitter {
 public:
  EarSplitter(io::MshData& d, const FaceGeometry& faces) : d_(d), faces_(faces) {
    for (const auto& e : d.elements) {
      next_element_ = std::max(next_element_, e.tag + 1);
      if (e.type == gmsh_line && e.entity.dim == 1) {
        const auto n = d.nodes_of(e);
        curve_of_[edge_key(n[0], n[1])] = e.entity.tag;
      }
    }
    for (std::size_t i = 0; i < d.nodes.size(); ++i) {
      index_[d.nodes[i].tag] = i;
      next_node_ = std::max(next_node_, d.nodes[i].tag + 1);
    }
    for (const auto& e : d.elements)
      if (e.type == gmsh_tetrahedron && e.num_nodes == 4) {
        const auto n = d.nodes_of(e);
        const Tetrahedron t{n[0], n[1], n[2], n[3]};
        for (int apex = 0; apex < 4; ++apex) tetrahedra_on_[triangle_key(face_opposite(t, apex))].push_back(t);
      }
    elements_.reserve(d.elements.size());
  }

  /// The corner of the element with these corner nodes (in order around it)
  /// that is an ear's, or -1: both edges there on one curve, or on two curves
  /// that meet tangentially there (smooth_join). On one curve the corner is
  /// on it, or on its vertex if it is closed (a periodic curve is as smooth
  /// there as anywhere; at a kink the split only adds a node).
  template <std::size_t N>
  int ear_corner(const std::array<std::int64_t, N>& corners) const {
    for (std::size_t i = 0; i < N; ++i) {
      const std::int64_t prev = corners[(i + N - 1) % N], next = corners[(i + 1) % N];
      const auto before = curve_of_.find(edge_key(corners[i], prev));
      const auto after = curve_of_.find(edge_key(corners[i], next));
      if (before == curve_of_.end() || after == curve_of_.end()) continue;
      if (before->second == after->second || smooth_join(corners[i], before->second, prev, after->second, next))
        return int(i);
    }
    return -1;
  }

  /// Whether curves a and b, leaving corner node `at` towards nodes
  /// a_next and b_next, leave it in nearly opposite directions (within
  /// flat_corner_max_angle): their tangents there, each oriented along its
  /// edge of the element.
  bool smooth_join(std::int64_t at, int a, std::int64_t a_next, int b, std::int64_t b_next) const {
    if (!faces_.curve_tangent) return false;
    const Eigen::Vector3d x = position(at);
    auto leaving = [&](int curve, std::int64_t towards) -> Eigen::Vector3d {
      const Eigen::Vector3d t = faces_.curve_tangent(curve, x), chord = position(towards) - x;
      const double n = t.norm();
      if (!(n > 0.0)) return Eigen::Vector3d::Zero();
      return (t.dot(chord) < 0 ? -t : t) / n;
    };
    return leaving(a, a_next).dot(leaving(b, b_next)) <= -std::cos(flat_corner_max_angle);
  }

  Eigen::Vector3d position(std::int64_t tag) const {
    const auto& x = d_.nodes[index_.at(tag)].x;
    return Eigen::Vector3d(x[0], x[1], x[2]);
  }

  /// The projection of y onto face `face`: its (u, v) and its point.
  std::pair<Eigen::Vector2d, Eigen::Vector3d> on_face(int face, const Eigen::Vector3d& y) const {
    const Eigen::Vector2d uv = faces_.project(face, y);
    return {uv, faces_.evaluate(face, uv)};
  }

  /// A new node of face `face` at the projection of y, with its (u, v).
  std::int64_t face_node(int face, const Eigen::Vector3d& y) {
    const auto [uv, x] = on_face(face, y);
    return face_node(face, uv, x);
  }

  /// A new node of face `face` at x, of parameters uv.
  std::int64_t face_node(int face, const Eigen::Vector2d& uv, const Eigen::Vector3d& x) {
    io::MshNode node;
    node.tag = next_node_++;
    node.x = {x[0], x[1], x[2]};
    node.entity = EntityId{2, face};
    node.num_params = 2;
    node.params = {uv[0], uv[1], 0.0};
    index_[node.tag] = d_.nodes.size();
    d_.nodes.push_back(node);
    return node.tag;
  }

  /// Appends an element like `e` with these nodes; the first piece of a
  /// split element keeps its tag, the others get new ones.
  void add(io::MshElement e, std::span<const std::int64_t> nodes, bool new_tag = false) {
    if (new_tag) e.tag = next_element_++;
    e.first = element_nodes_.size();
    e.num_nodes = int(nodes.size());
    element_nodes_.insert(element_nodes_.end(), nodes.begin(), nodes.end());
    elements_.push_back(e);
  }

  /// Records that the boundary triangle with these corners was split at
  /// node `centre`: the tetrahedron on it is split there too (finish).
  void split_face_at(const Triangle& corners, std::int64_t centre) { face_centres_[triangle_key(corners)] = centre; }

  /// Whether splitting the tetrahedra on the triangle with these corners at
  /// point c keeps every piece's orientation: c is on the inner side of each
  /// plane through the apex and an edge of the triangle. The projection onto
  /// a curved face moves c off the triangle's plane, and towards the apex it
  /// can cross those planes where the face bends more than the tetrahedron
  /// is tall.
  bool pieces_keep_orientation(const Triangle& corners, const Eigen::Vector3d& c) const {
    const auto on = tetrahedra_on_.find(triangle_key(corners));
    if (on == tetrahedra_on_.end()) return true;
    for (const Tetrahedron& t : on->second) {
      std::array<Eigen::Vector3d, 4> x;
      for (int i = 0; i < 4; ++i) x[i] = position(t[i]);
      const double whole = signed_volume(x);
      for (int i = 0; i < 4; ++i) {
        if (std::find(corners.begin(), corners.end(), t[i]) == corners.end()) continue;
        auto piece = x;
        piece[i] = c;
        if (!(signed_volume(piece) / whole > 0.0)) return false;
      }
    }
    return true;
  }

  /// Replaces d's elements with those added, each tetrahedron on a split
  /// boundary triangle split at that triangle's new node.
  void finish() {
    if (!face_centres_.empty()) split_tetrahedra();
    d_.elements = std::move(elements_);
    d_.element_nodes = std::move(element_nodes_);
  }

 private:
  io::MshData& d_;
  const FaceGeometry& faces_;
  std::map<Edge, int> curve_of_;
  std::unordered_map<std::int64_t, std::size_t> index_;
  std::int64_t next_node_ = 0, next_element_ = 0;
  std::vector<io::MshElement> elements_;
  std::vector<std::int64_t> element_nodes_;
  std::map<Triangle, std::int64_t> face_centres_;
  std::map<Triangle, std::vector<Tetrahedron>> tetrahedra_on_;  // by face, before any split

  static double signed_volume(const std::array<Eigen::Vector3d, 4>& x) {
    return (x[1] - x[0]).dot((x[2] - x[0]).cross(x[3] - x[0]));
  }

  static Triangle face_opposite(const Tetrahedron& t, int apex) {
    Triangle face{};
    for (int i = 0, k = 0; i < 4; ++i)
      if (i != apex) face[k++] = t[i];
    return face;
  }

  /// The new node of a split triangle among the faces of tetrahedron t, and
  /// the local index of the vertex opposite it; {-1, -1} if none.
  std::pair<std::int64_t, int> split_face_of(const Tetrahedron& t) const {
    for (int apex = 0; apex < 4; ++apex)
      if (const auto c = face_centres_.find(triangle_key(face_opposite(t, apex))); c != face_centres_.end())
        return {c->second, apex};
    return {-1, -1};
  }

  /// A tetrahedron on a split boundary triangle becomes three: in its node
  /// order, each of the triangle's corners in turn replaced by the new node
  /// c, so each keeps the orientation (c lies on the triangle: the piece's
  /// volume is c's barycentric coordinate times the whole). A piece that
  /// holds a second split triangle is split again.
  void split_tetrahedra() {
    std::vector<io::MshElement> elements = std::move(elements_);
    std::vector<std::int64_t> nodes = std::move(element_nodes_);
    elements_.clear();
    element_nodes_.clear();
    for (const auto& e : elements) {
      std::vector<Tetrahedron> pending;
      if (e.type == gmsh_tetrahedron && e.num_nodes == 4)
        pending.push_back({nodes[e.first], nodes[e.first + 1], nodes[e.first + 2], nodes[e.first + 3]});
      else
        add(e, std::span<const std::int64_t>(nodes.data() + e.first, std::size_t(e.num_nodes)));
      bool first = true;
      while (!pending.empty()) {
        const auto t = pending.back();
        pending.pop_back();
        const auto [centre, apex] = split_face_of(t);
        if (centre < 0) {
          add(e, t, !first);
          first = false;
          continue;
        }
        for (int i = 0; i < 4; ++i)
          if (i != apex) {
            auto piece = t;
            piece[i] = centre;
            pending.push_back(piece);
          }
      }
    }
  }
};

/// Runs split(splitter, element, corners, ear corner) on every ear of type `type` (N
/// corners) on a face, keeps the other elements; returns the ears split
/// (split returns false where it kept the ear).
template <std::size_t N, class Split>
int split_ears(io::MshData& d, const FaceGeometry& faces, int type, Split&& split) {
  EarSplitter s(d, faces);
  int ears = 0;
  for (const auto& e : d.elements) {
    const auto n = d.nodes_of(e);
    int ear = -1;
    std::array<std::int64_t, N> corners{};
    if (e.type == type && e.entity.dim == 2) {
      std::copy(n.begin(), n.end(), corners.begin());
      ear = s.ear_corner(corners);
    }
    if (ear < 0) {
      s.add(e, n);
      continue;
    }
    ears += split(s, e, corners, ear);
  }
  s.finish();
  return ears;
}

/// A quadrilateral ear into five: inner corners halfway to the centre, on
/// the face, the ear corner's a quarter of the way (it is nearly on the line
/// of its two neighbours, so halfway would put the inner quad's corner on
/// the line of theirs); the four around the inner quad, each on one of the
/// ear's edges, then the inner one, all with the ear's winding.
bool split_quad_ear(EarSplitter& s, const io::MshElement& e, const std::array<std::int64_t, 4>& q, int ear) {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (auto t : q) centre += 0.25 * s.position(t);
  std::array<std::int64_t, 4> inner{};
  for (int i = 0; i < 4; ++i) {
    const double to_centre = i == ear ? 0.25 : 0.5;
    inner[i] = s.face_node(e.entity.tag, s.position(q[i]) + to_centre * (centre - s.position(q[i])));
  }
  for (int i = 0; i < 4; ++i) {
    const std::array<std::int64_t, 4> around{q[i], q[(i + 1) % 4], inner[(i + 1) % 4], inner[i]};
    s.add(e, around, i > 0);
  }
  s.add(e, inner, true);
  return true;
}

/// A triangle ear into three around its centre, projected onto the face
/// (and the tetrahedron on it, if any, into three at the same node), unless
/// a piece of that tetrahedron would come out inverted: the ear is kept.
bool split_triangle_ear(EarSplitter& s, const io::MshElement& e, const std::array<std::int64_t, 3>& t, int) {
  const Eigen::Vector3d centre = (s.position(t[0]) + s.position(t[1]) + s.position(t[2])) / 3;
  const auto [uv, x] = s.on_face(e.entity.tag, centre);
  if (!s.pieces_keep_orientation(t, x)) {
    s.add(e, t);
    return false;
  }
  const std::int64_t c = s.face_node(e.entity.tag, uv, x);
  s.split_face_at(t, c);
  for (int i = 0; i < 3; ++i) {
    const std::array<std::int64_t, 3> piece{t[i], t[(i + 1) % 3], c};
    s.add(e, piece, i > 0);
  }
  return true;
}

}  // namespace

FaceGeometry face_geometry(const GeometryModel<3>& geometry) {
  return {[&geometry](int f, const Eigen::Vector3d& x) { return geometry.surface(f)->project(x); },
          [&geometry](int f, const Eigen::Vector2d& uv) { return geometry.surface(f)->evaluate(uv); },
          [&geometry](int c, const Eigen::Vector3d& x) -> Eigen::Vector3d {
            const auto* curve = geometry.curve(c);
            return curve ? curve->derivative(curve->project(x)) : Eigen::Vector3d::Zero();
          }};
}

int split_quad_ears(io::MshData& d, const FaceGeometry& faces) {
  return split_ears<4>(d, faces, gmsh_quad, split_quad_ear);
}

int split_triangle_ears(io::MshData& d, const FaceGeometry& faces) {
  return split_ears<3>(d, faces, gmsh_triangle, split_triangle_ear);
}

}  // namespace hom::cad
