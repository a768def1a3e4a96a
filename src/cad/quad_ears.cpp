// Quadrilateral ears of a linear 2D mesh (see quad_ears.hpp).
#include "quad_ears.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <span>
#include <unordered_map>
#include <utility>
#include <vector>

namespace hom::cad {

namespace {

constexpr int gmsh_line = 1;
constexpr int gmsh_quad = 3;

using Edge = std::pair<std::int64_t, std::int64_t>;

Edge edge_key(std::int64_t a, std::int64_t b) { return a < b ? Edge{a, b} : Edge{b, a}; }

}  // namespace

int split_quad_ears(io::MshData& d, const FaceGeometry& faces) {
  // The curve each boundary line lies on.
  std::map<Edge, int> curve_of;
  for (const auto& e : d.elements)
    if (e.type == gmsh_line && e.entity.dim == 1) {
      const auto n = d.nodes_of(e);
      curve_of[edge_key(n[0], n[1])] = e.entity.tag;
    }
  std::unordered_map<std::int64_t, std::size_t> index;
  std::int64_t next_node = 0, next_element = 0;
  for (std::size_t i = 0; i < d.nodes.size(); ++i) {
    index[d.nodes[i].tag] = i;
    next_node = std::max(next_node, d.nodes[i].tag + 1);
  }
  for (const auto& e : d.elements) next_element = std::max(next_element, e.tag + 1);
  auto position = [&](std::int64_t tag) {
    const auto& x = d.nodes[index.at(tag)].x;
    return Eigen::Vector3d(x[0], x[1], x[2]);
  };
  // The corner of `q` that is an ear's, or -1.
  auto ear_corner = [&](const std::array<std::int64_t, 4>& q) {
    for (int i = 0; i < 4; ++i) {
      const auto& node = d.nodes[index.at(q[i])];
      if (!node.entity || node.entity->dim != 1) continue;
      const auto before = curve_of.find(edge_key(q[i], q[(i + 3) % 4]));
      const auto after = curve_of.find(edge_key(q[i], q[(i + 1) % 4]));
      if (before != curve_of.end() && after != curve_of.end() && before->second == node.entity->tag &&
          after->second == node.entity->tag)
        return i;
    }
    return -1;
  };

  std::vector<io::MshElement> elements;
  std::vector<std::int64_t> element_nodes;
  elements.reserve(d.elements.size());
  int split = 0;
  auto add = [&](io::MshElement e, std::span<const std::int64_t> nodes) {
    e.first = element_nodes.size();
    e.num_nodes = int(nodes.size());
    element_nodes.insert(element_nodes.end(), nodes.begin(), nodes.end());
    elements.push_back(e);
  };
  for (const auto& e : d.elements) {
    const auto n = d.nodes_of(e);
    std::array<std::int64_t, 4> q{};
    if (e.type == gmsh_quad && e.entity.dim == 2) std::copy(n.begin(), n.end(), q.begin());
    const int ear = e.type == gmsh_quad && e.entity.dim == 2 ? ear_corner(q) : -1;
    if (ear < 0) {
      add(e, n);
      continue;
    }
    // Inner corners halfway to the centre, on the face; the ear corner's a
    // quarter of the way: it is (nearly) on the line of its two neighbours,
    // so halfway would put the inner quad's corner on the line of theirs.
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (auto t : q) centre += 0.25 * position(t);
    std::array<std::int64_t, 4> inner{};
    for (int i = 0; i < 4; ++i) {
      const double to_centre = i == ear ? 0.25 : 0.5;
      const Eigen::Vector3d y = position(q[i]) + to_centre * (centre - position(q[i]));
      const Eigen::Vector2d uv = faces.project(e.entity.tag, y);
      const Eigen::Vector3d x = faces.evaluate(e.entity.tag, uv);
      io::MshNode node;
      node.tag = next_node++;
      node.x = {x[0], x[1], x[2]};
      node.entity = EntityId{2, e.entity.tag};
      node.num_params = 2;
      node.params = {uv[0], uv[1], 0.0};
      index[node.tag] = d.nodes.size();
      d.nodes.push_back(node);
      inner[i] = node.tag;
    }
    // The four around the inner quad, each on one of the ear's edges, then
    // the inner one; all with the ear's winding.
    io::MshElement k = e;
    for (int i = 0; i < 4; ++i) {
      const int j = (i + 1) % 4;
      const std::array<std::int64_t, 4> around{q[i], q[j], inner[j], inner[i]};
      add(k, around);
      k.tag = next_element++;
    }
    add(k, inner);
    ++split;
  }
  d.elements = std::move(elements);
  d.element_nodes = std::move(element_nodes);
  return split;
}

}  // namespace hom::cad
