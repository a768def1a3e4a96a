#pragma once
/// @file msh_writer.hpp
/// Writes MshData as Gmsh MSH 4.1 (ASCII or binary) or 2.2 (ASCII), through
/// a temporary file renamed at the end (error.hpp). Numbers are written in
/// the shortest form that reads back to the same double.
///
/// MSH 4.1: $Entities lists every entity the data holds or references, with
/// bounding boxes computed from the nodes on it and the nodes of its
/// elements; nodes are written in one block per entity (parametric when every
/// node of the block has parameters), elements in one block per (entity,
/// type). MSH 2.2: each element line carries the element's physical tag, or its
/// entity's first physical tag, or 0.

#include <charconv>
#include <cstdint>
#include <cstring>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

#include "hom/io/error.hpp"
#include "hom/io/msh_data.hpp"

namespace hom::io {

struct MshFormat {
  enum class Version { v41, v22 };
  Version version = Version::v41;
  bool binary = false;  ///< MSH 4.1 only
};

namespace detail {

class MshOut {
 public:
  explicit MshOut(bool binary) : binary_(binary) {}
  std::string& str() { return s_; }

  void text(std::string_view t) { s_.append(t); }
  void real(double v) {
    char buf[32];
    auto [p, ec] = std::to_chars(buf, buf + sizeof buf, v);
    s_.append(buf, p);
  }
  template <class Int>
  void integer(Int v) {
    char buf[24];
    auto [p, ec] = std::to_chars(buf, buf + sizeof buf, v);
    s_.append(buf, p);
  }
  template <class T>
  void raw(T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    s_.append(b, sizeof(T));
  }

  // Section-body values: binary, or ASCII followed by a separator.
  void count(std::size_t v, char sep = ' ') {
    if (binary_) {
      raw<std::uint64_t>(v);
    } else {
      integer(v);
      s_.push_back(sep);
    }
  }
  void int32(int v, char sep = ' ') {
    if (binary_) {
      raw<int>(v);
    } else {
      integer(v);
      s_.push_back(sep);
    }
  }
  void tag(std::int64_t v, char sep = ' ') {
    if (binary_) {
      raw<std::uint64_t>(static_cast<std::uint64_t>(v));
    } else {
      integer(v);
      s_.push_back(sep);
    }
  }
  void value(double v, char sep = ' ') {
    if (binary_) {
      raw<double>(v);
    } else {
      real(v);
      s_.push_back(sep);
    }
  }
  // End of an ASCII line: replace the trailing separator by a newline.
  void eol() {
    if (binary_) return;
    if (!s_.empty() && s_.back() == ' ')
      s_.back() = '\n';
    else
      s_.push_back('\n');
  }

 private:
  bool binary_;
  std::string s_;
};

struct EntityBox {
  std::array<double, 3> lo{}, hi{};
  bool empty = true;
  void add(const std::array<double, 3>& x) {
    for (int k = 0; k < 3; ++k) {
      lo[k] = empty ? x[k] : std::min(lo[k], x[k]);
      hi[k] = empty ? x[k] : std::max(hi[k], x[k]);
    }
    empty = false;
  }
};

inline void write_physical_names(MshOut& o, const MshData& d) {
  if (d.physical_names.empty()) return;
  o.text("$PhysicalNames\n");
  o.integer(d.physical_names.size());
  o.text("\n");
  for (const auto& g : d.physical_names) {
    o.integer(g.dim);
    o.text(" ");
    o.integer(g.tag);
    o.text(" \"" + g.name + "\"\n");
  }
  o.text("$EndPhysicalNames\n");
}

inline std::string serialize_msh41(const MshData& d, bool binary) {
  MshOut o(binary);
  o.text(binary ? "$MeshFormat\n4.1 1 8\n" : "$MeshFormat\n4.1 0 8\n");
  if (binary) {
    o.raw<int>(1);
    o.text("\n");
  }
  o.text("$EndMeshFormat\n");
  write_physical_names(o, d);

  std::unordered_map<std::int64_t, std::size_t> node_index;
  node_index.reserve(d.nodes.size());
  for (std::size_t i = 0; i < d.nodes.size(); ++i) node_index.emplace(d.nodes[i].tag, i);

  // Every entity held or referenced, with its box.
  std::map<EntityId, const Entity*> listed;
  for (const auto& en : d.entities) listed.emplace(en.id, &en);
  std::map<EntityId, EntityBox> boxes;
  for (const auto& [id, en] : listed) boxes[id];
  for (const auto& n : d.nodes)
    if (n.entity) boxes[*n.entity].add(n.x);
  for (const auto& e : d.elements) {
    auto& box = boxes[e.entity];
    for (auto t : d.nodes_of(e))
      if (auto it = node_index.find(t); it != node_index.end()) box.add(d.nodes[it->second].x);
  }
  std::array<std::vector<EntityId>, 4> by_dim;
  for (const auto& [id, box] : boxes)
    if (id.dim >= 0 && id.dim <= 3) by_dim[id.dim].push_back(id);

  o.text("$Entities\n");
  for (int dim = 0; dim < 4; ++dim) o.count(by_dim[dim].size());
  o.eol();
  for (int dim = 0; dim < 4; ++dim)
    for (const auto& id : by_dim[dim]) {
      const auto& box = boxes[id];
      const Entity* en = listed.count(id) ? listed[id] : nullptr;
      o.int32(id.tag);
      for (int k = 0; k < 3; ++k) o.value(box.lo[k]);
      if (dim > 0)
        for (int k = 0; k < 3; ++k) o.value(box.hi[k]);
      const std::vector<int> none;
      const auto& phys = en ? en->physical_tags : none;
      o.count(phys.size());
      for (int t : phys) o.int32(t);
      if (dim > 0) {
        std::vector<int> bound;
        if (en)
          for (int b : en->boundary)
            if (boxes.count(EntityId{dim - 1, std::abs(b)})) bound.push_back(b);
        o.count(bound.size());
        for (int b : bound) o.int32(b);
      }
      o.eol();
    }
  if (binary) o.text("\n");
  o.text("$EndEntities\n");

  // Nodes, one block per entity.
  std::map<EntityId, std::vector<std::size_t>> node_blocks;
  for (std::size_t i = 0; i < d.nodes.size(); ++i) {
    if (!d.nodes[i].entity) throw IoError(d.path + ": node " + std::to_string(d.nodes[i].tag) + " has no entity");
    node_blocks[*d.nodes[i].entity].push_back(i);
  }
  std::int64_t min_tag = 0, max_tag = 0;
  for (std::size_t i = 0; i < d.nodes.size(); ++i) {
    min_tag = i == 0 ? d.nodes[i].tag : std::min(min_tag, d.nodes[i].tag);
    max_tag = i == 0 ? d.nodes[i].tag : std::max(max_tag, d.nodes[i].tag);
  }
  o.text("$Nodes\n");
  o.count(node_blocks.size());
  o.count(d.nodes.size());
  o.count(std::size_t(min_tag));
  o.count(std::size_t(max_tag));
  o.eol();
  for (const auto& [id, list] : node_blocks) {
    bool parametric = id.dim > 0 && id.dim < 3;
    for (auto i : list) parametric = parametric && d.nodes[i].num_params == id.dim;
    o.int32(id.dim);
    o.int32(id.tag);
    o.int32(parametric ? 1 : 0);
    o.count(list.size());
    o.eol();
    for (auto i : list) {
      o.tag(d.nodes[i].tag);
      o.eol();
    }
    for (auto i : list) {
      for (int k = 0; k < 3; ++k) o.value(d.nodes[i].x[k]);
      if (parametric)
        for (int k = 0; k < id.dim; ++k) o.value(d.nodes[i].params[k]);
      o.eol();
    }
  }
  if (binary) o.text("\n");
  o.text("$EndNodes\n");

  // Elements, one block per (entity, type), blocks in order of appearance.
  std::vector<std::pair<std::pair<EntityId, int>, std::vector<std::size_t>>> blocks;
  std::map<std::pair<EntityId, int>, std::size_t> block_of;
  std::int64_t emin = 0, emax = 0;
  for (std::size_t i = 0; i < d.elements.size(); ++i) {
    const auto& e = d.elements[i];
    const auto key = std::pair{e.entity, e.type};
    auto [it, inserted] = block_of.try_emplace(key, blocks.size());
    if (inserted) blocks.push_back({key, {}});
    blocks[it->second].second.push_back(i);
    emin = i == 0 ? e.tag : std::min(emin, e.tag);
    emax = i == 0 ? e.tag : std::max(emax, e.tag);
  }
  o.text("$Elements\n");
  o.count(blocks.size());
  o.count(d.elements.size());
  o.count(std::size_t(emin));
  o.count(std::size_t(emax));
  o.eol();
  for (const auto& [key, list] : blocks) {
    o.int32(key.first.dim);
    o.int32(key.first.tag);
    o.int32(key.second);
    o.count(list.size());
    o.eol();
    for (auto i : list) {
      const auto& e = d.elements[i];
      o.tag(e.tag);
      for (auto t : d.nodes_of(e)) o.tag(t);
      o.eol();
    }
  }
  if (binary) o.text("\n");
  o.text("$EndElements\n");
  return std::move(o.str());
}

inline std::string serialize_msh22(const MshData& d) {
  MshOut o(false);
  o.text("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n");
  write_physical_names(o, d);
  std::map<EntityId, int> first_physical;
  for (const auto& en : d.entities)
    if (!en.physical_tags.empty()) first_physical[en.id] = en.physical_tags.front();
  o.text("$Nodes\n");
  o.integer(d.nodes.size());
  o.text("\n");
  for (const auto& n : d.nodes) {
    o.tag(n.tag);
    for (int k = 0; k < 3; ++k) o.value(n.x[k]);
    o.eol();
  }
  o.text("$EndNodes\n$Elements\n");
  o.integer(d.elements.size());
  o.text("\n");
  for (const auto& e : d.elements) {
    o.tag(e.tag);
    o.int32(e.type);
    o.int32(2);
    int phys = e.physical;
    if (phys == 0)
      if (auto it = first_physical.find(e.entity); it != first_physical.end()) phys = it->second;
    o.int32(phys);
    o.int32(e.entity.tag);
    for (auto t : d.nodes_of(e)) o.tag(t);
    o.eol();
  }
  o.text("$EndElements\n");
  return std::move(o.str());
}

}  // namespace detail

/// Writes `d` to `path` in the given format (atomically).
inline void write_msh_data(const std::string& path, const MshData& d, const MshFormat& format = {}) {
  if (format.binary && format.version == MshFormat::Version::v22)
    throw IoError(path + ": binary MSH 2.2 is not supported (use MSH 4.1 for binary output)");
  const std::string s = format.version == MshFormat::Version::v41 ? detail::serialize_msh41(d, format.binary)
                                                                  : detail::serialize_msh22(d);
  write_atomically(path, [&](std::FILE* f) { write_all(f, path, s.data(), s.size()); });
}

}  // namespace hom::io
