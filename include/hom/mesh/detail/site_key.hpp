#pragma once
/// @file site_key.hpp
/// Mesh-wide identity of a high-order node site.
///
/// A node of a degree-p element with lattice index l lies on the sub-entity
/// spanned by the vertices with non-zero `Family::vertex_weights(l, p)`; the
/// sorted list of (global vertex id, weight) pairs over those vertices does
/// not depend on which element looks at the node (the weights are the
/// barycentric / multilinear coordinates scaled to integers, intrinsic to the
/// edge or face). So in a conforming mesh of one family two elements see the
/// same node exactly when they compute the same key. p-elevation creates shared
/// nodes once with it, the readers check conformity with it.

#include <array>
#include <cstddef>
#include <functional>
#include <utility>
#include <vector>

#include "hom/element/node_layout.hpp"

namespace hom::detail {

/// At most 8 vertices (hexahedron interior).
struct SiteKey {
  std::array<std::pair<int, int>, 8> entries{};
  int size = 0;

  friend bool operator==(const SiteKey& a, const SiteKey& b) {
    if (a.size != b.size) return false;
    for (int i = 0; i < a.size; ++i)
      if (a.entries[i] != b.entries[i]) return false;
    return true;
  }
};

struct SiteKeyHash {
  std::size_t operator()(const SiteKey& k) const noexcept {
    std::size_t h = 1469598103934665603ull;
    auto mix = [&h](std::size_t v) {
      h ^= v + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
    };
    for (int i = 0; i < k.size; ++i) {
      mix(static_cast<std::size_t>(k.entries[i].first));
      mix(static_cast<std::size_t>(k.entries[i].second));
    }
    return h;
  }
};

/// For every local node of a degree-p element: the (local vertex, weight)
/// pairs with non-zero weight. Tabulated once per element type.
template <ElementFamily Family>
std::vector<std::vector<std::pair<int, int>>> local_site_weights(int p) {
  const auto& layout = node_layout<Family>(p);
  std::vector<std::vector<std::pair<int, int>>> out(layout.size());
  for (int i = 0; i < layout.size(); ++i) {
    const auto w = Family::vertex_weights(layout.lattice(i), p);
    for (int v = 0; v < Family::num_vertices; ++v)
      if (w[v] != 0) out[i].push_back({v, w[v]});
  }
  return out;
}

/// Key of one site given the element's global vertex ids.
template <class VertexIds>
SiteKey site_key(const std::vector<std::pair<int, int>>& local, const VertexIds& vertex_ids) {
  SiteKey k;
  k.size = static_cast<int>(local.size());
  // Insertion sort: at most 8 entries.
  for (int i = 0; i < k.size; ++i) {
    const std::pair<int, int> x{static_cast<int>(vertex_ids[local[i].first]), local[i].second};
    int j = i;
    for (; j > 0 && x < k.entries[j - 1]; --j) k.entries[j] = k.entries[j - 1];
    k.entries[j] = x;
  }
  return k;
}

}  // namespace hom::detail
