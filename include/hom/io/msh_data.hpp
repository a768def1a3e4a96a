#pragma once
/// @file msh_data.hpp
/// The contents of a Gmsh MSH file, independent of its version and encoding:
/// what msh_reader.hpp parses and msh_writer.hpp writes. `to_mesh` and
/// `to_msh_data` (msh.hpp) convert between it and hom's Mesh.

#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "hom/io/gmsh_elements.hpp"
#include "hom/mesh/mesh.hpp"

namespace hom::io {

struct MshNode {
  std::int64_t tag = 0;
  std::array<double, 3> x{};
  /// The entity of the node's block (MSH 4), none in MSH 2.
  std::optional<EntityId> entity;
  int num_params = 0;
  std::array<double, 3> params{};
  std::size_t line = 0;  ///< where it was read (0: not read from a file)
};

struct MshElement {
  std::int64_t tag = 0;
  int type = 0;
  /// dim from the type; tag from the block (MSH 4) or the elementary tag (MSH 2).
  EntityId entity;
  /// MSH 2: the physical tag of the element line (0 if none).
  int physical = 0;
  std::size_t first = 0;  ///< offset of its node tags in MshData::element_nodes
  int num_nodes = 0;
  std::size_t line = 0;
};

struct MshData {
  std::string path;  ///< for messages
  int version_major = 4;
  int version_minor = 1;
  bool binary = false;
  std::vector<PhysicalGroup> physical_names;
  /// $Entities (MSH 4); for MSH 2 built from the elements' elementary tags.
  std::vector<Entity> entities;
  std::vector<MshNode> nodes;
  std::vector<MshElement> elements;
  std::vector<std::int64_t> element_nodes;

  std::span<const std::int64_t> nodes_of(const MshElement& e) const { return {element_nodes.data() + e.first, std::size_t(e.num_nodes)}; }
};

/// What a file holds, for choosing the Mesh type to read it into.
struct MshSummary {
  std::map<int, std::size_t> type_counts;  ///< Gmsh type -> number of elements
  int dim = 0;                             ///< highest element dimension
  std::vector<GmshShape> top_shapes;       ///< shapes of dimension `dim` present
  std::vector<int> top_orders;             ///< orders of dimension `dim` present
  bool planar = true;                      ///< every node has z == 0
  std::array<double, 3> lo{}, hi{};        ///< bounding box of the nodes
};

inline MshSummary summarize(const MshData& d) {
  MshSummary s;
  for (const auto& e : d.elements) ++s.type_counts[e.type];
  for (const auto& [type, n] : s.type_counts)
    if (auto info = gmsh_element_info(type)) s.dim = std::max(s.dim, info->dim);
  for (const auto& [type, n] : s.type_counts)
    if (auto info = gmsh_element_info(type); info && info->dim == s.dim) {
      if (std::find(s.top_shapes.begin(), s.top_shapes.end(), info->shape) == s.top_shapes.end())
        s.top_shapes.push_back(info->shape);
      if (std::find(s.top_orders.begin(), s.top_orders.end(), info->order) == s.top_orders.end())
        s.top_orders.push_back(info->order);
    }
  bool first = true;
  for (const auto& n : d.nodes) {
    if (n.x[2] != 0.0) s.planar = false;
    for (int k = 0; k < 3; ++k) {
      s.lo[k] = first ? n.x[k] : std::min(s.lo[k], n.x[k]);
      s.hi[k] = first ? n.x[k] : std::max(s.hi[k], n.x[k]);
    }
    first = false;
  }
  return s;
}

}  // namespace hom::io
