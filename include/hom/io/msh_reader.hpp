#pragma once
/// @file msh_reader.hpp
/// Parser of Gmsh MSH files: version 4.1 (ASCII and binary) and 2.x (ASCII),
/// into MshData. Sections: $MeshFormat, $PhysicalNames, $Entities, $Nodes,
/// $Elements; others are skipped. Element types other than points and
/// complete Lagrange lines, triangles, quadrilaterals, tetrahedra and
/// hexahedra (gmsh_elements.hpp) are refused.
///
/// Checks done here (each a ParseError "FILE:LINE: what"): truncation,
/// malformed or non-finite numbers, counts that disagree with the data,
/// unsupported versions and element types, an element type in a block of
/// another dimension, missing $Nodes / $Elements. Checks that need the mesh
/// (missing or duplicate nodes, conformity, orientation) are in msh.hpp.

#include <cstdint>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <string>
#include <string_view>

#include "hom/io/detail/cursor.hpp"
#include "hom/io/msh_data.hpp"

namespace hom::io {

namespace detail {

class MshParser {
 public:
  MshParser(std::string_view content, std::string path) : c_(content, std::move(path)) {}

  MshData parse() {
    MshData d;
    d.path = c_.path();
    if (c_.at_end()) c_.fail("empty file");
    if (c_.token("file header") != "$MeshFormat") c_.fail("not a Gmsh MSH file (no $MeshFormat at the start)");
    read_format(d);
    bool have_nodes = false, have_elements = false, have_entities = false;
    while (!c_.at_end()) {
      const std::size_t line = c_.line();
      const auto t = c_.token("section");
      if (t.empty() || t[0] != '$') c_.fail("expected a section ($Name), got '" + Cursor::shorten(t) + "'");
      const std::string name(t.substr(1));
      if (name == "PhysicalNames") {
        read_physical_names(d);
      } else if (name == "Entities" && d.version_major == 4) {
        read_entities(d);
        have_entities = true;
      } else if (name == "Nodes") {
        if (have_nodes) c_.fail("second $Nodes section");
        if (d.version_major == 4)
          read_nodes4(d);
        else
          read_nodes2(d);
        have_nodes = true;
      } else if (name == "Elements") {
        if (have_elements) c_.fail("second $Elements section");
        if (d.version_major == 4)
          read_elements4(d);
        else
          read_elements2(d);
        have_elements = true;
      } else if (name == "MeshFormat") {
        c_.fail("second $MeshFormat section");
      } else if (name.rfind("End", 0) == 0) {
        c_.fail("'" + Cursor::shorten(t) + "' without its section");
      } else {
        if (!c_.skip_past("$End" + name)) c_.fail_at(line, "section $" + Cursor::shorten(name) + " is not terminated");
      }
    }
    if (!have_nodes) c_.fail("no $Nodes section");
    if (!have_elements) c_.fail("no $Elements section");
    if (d.version_major == 2 || !have_entities) build_entities_from_elements(d);
    return d;
  }

 private:
  void read_format(MshData& d) {
    const auto v = c_.token("$MeshFormat");
    if (v == "4.1") {
      d.version_major = 4;
      d.version_minor = 1;
    } else if (v == "2.2" || v == "2.1" || v == "2.0" || v == "2") {
      d.version_major = 2;
      d.version_minor = v.size() == 3 ? v[2] - '0' : 0;
    } else {
      c_.fail("MSH version " + Cursor::shorten(v) + " is not supported (hom reads 4.1 and 2.2)");
    }
    const int file_type = c_.integer<int>("$MeshFormat");
    const int data_size = c_.integer<int>("$MeshFormat");
    if (file_type != 0 && file_type != 1) c_.fail("file-type must be 0 (ASCII) or 1 (binary)");
    d.binary = file_type == 1;
    binary_ = d.binary;
    if (d.binary && d.version_major != 4) c_.fail("binary MSH 2 is not supported (use ASCII or MSH 4.1)");
    if (d.binary) {
      if (data_size != 8) c_.fail("binary data-size " + std::to_string(data_size) + " is not supported (need 8)");
      c_.end_of_header_line("$MeshFormat");
      const int one = c_.binary<int>("$MeshFormat");
      if (one != 1) c_.fail("binary file of the other endianness");
    }
    c_.expect("$EndMeshFormat", "$MeshFormat");
  }

  void read_physical_names(MshData& d) {
    const auto n = c_.integer<long>("$PhysicalNames");
    if (n < 0) c_.fail("negative count in $PhysicalNames");
    for (long i = 0; i < n; ++i) {
      PhysicalGroup g;
      g.dim = c_.integer<int>("$PhysicalNames");
      if (g.dim < 0 || g.dim > 3) c_.fail("physical group dimension must be 0..3");
      g.tag = c_.integer<int>("$PhysicalNames");
      g.name = c_.quoted("$PhysicalNames");
      d.physical_names.push_back(std::move(g));
    }
    c_.expect("$EndPhysicalNames", "$PhysicalNames");
  }

  // --- MSH 4.1 ---------------------------------------------------------------
  std::size_t count(std::string_view ctx) {
    if (binary_) return c_.binary<std::uint64_t>(ctx);
    const auto v = c_.integer<long long>(ctx);
    if (v < 0) c_.fail("negative count in " + std::string(ctx));
    return static_cast<std::size_t>(v);
  }
  int integer(std::string_view ctx) { return binary_ ? c_.binary<int>(ctx) : c_.integer<int>(ctx); }
  std::int64_t tag(std::string_view ctx) {
    if (binary_) {
      const auto v = c_.binary<std::uint64_t>(ctx);
      if (v > std::uint64_t(std::numeric_limits<std::int64_t>::max())) c_.fail("tag out of range in " + std::string(ctx));
      return static_cast<std::int64_t>(v);
    }
    return c_.integer<std::int64_t>(ctx);
  }
  double real(std::string_view ctx) { return binary_ ? c_.binary_real(ctx) : c_.real(ctx); }
  // A count that claims more items than bytes left is corrupt: refuse it before
  // allocating anything for it.
  void plausible(std::size_t n, std::size_t min_bytes_each, std::string_view ctx) {
    if (min_bytes_each && n > c_.remaining() / min_bytes_each)
      c_.fail("count " + std::to_string(n) + " in " + std::string(ctx) +
              " exceeds what the rest of the file can hold: the file is truncated or the count is wrong");
  }
  void begin_binary(std::string_view ctx) {
    if (binary_) c_.end_of_header_line(ctx);
  }

  void read_entities(MshData& d) {
    constexpr std::string_view ctx = "$Entities";
    begin_binary(ctx);
    std::size_t n[4];
    for (auto& k : n) {
      k = count(ctx);
      plausible(k, 4, ctx);
    }
    for (int dim = 0; dim < 4; ++dim)
      for (std::size_t i = 0; i < n[dim]; ++i) {
        Entity en;
        en.id.dim = dim;
        en.id.tag = integer(ctx);
        const int nbox = dim == 0 ? 3 : 6;
        for (int k = 0; k < nbox; ++k) real(ctx);
        const std::size_t nphys = count(ctx);
        plausible(nphys, 2, ctx);
        for (std::size_t k = 0; k < nphys; ++k) en.physical_tags.push_back(integer(ctx));
        if (dim > 0) {
          const std::size_t nb = count(ctx);
          plausible(nb, 2, ctx);
          for (std::size_t k = 0; k < nb; ++k) en.boundary.push_back(integer(ctx));
        }
        d.entities.push_back(std::move(en));
      }
    c_.expect("$EndEntities", ctx);
  }

  void read_nodes4(MshData& d) {
    constexpr std::string_view ctx = "$Nodes";
    begin_binary(ctx);
    skip_to_data();
    const std::size_t header_line = c_.line();
    const std::size_t blocks = count(ctx), total = count(ctx);
    const auto min_tag = static_cast<std::int64_t>(count(ctx)), max_tag = static_cast<std::int64_t>(count(ctx));
    plausible(blocks, 4, ctx);
    plausible(total, binary_ ? 32 : 8, ctx);
    d.nodes.reserve(total);
    std::size_t seen = 0;
    for (std::size_t b = 0; b < blocks; ++b) {
      skip_to_data();
      const std::size_t block_line = c_.line();
      const int edim = integer(ctx), etag = integer(ctx), parametric = integer(ctx);
      const std::size_t n = count(ctx);
      if (edim < 0 || edim > 3) c_.fail_at(block_line, "entity dimension " + std::to_string(edim) + " in $Nodes");
      if (parametric != 0 && parametric != 1) c_.fail_at(block_line, "parametric flag must be 0 or 1 in $Nodes");
      if (seen + n > total)
        c_.fail_at(block_line, "$Nodes blocks hold more nodes than the " + std::to_string(total) + " declared");
      plausible(n, binary_ ? 32 : 8, ctx);
      const int np = parametric ? edim : 0;
      const std::size_t first = d.nodes.size();
      for (std::size_t i = 0; i < n; ++i) {
        MshNode node;
        skip_to_data();
        node.line = c_.line();
        node.tag = tag(ctx);
        if (node.tag < 1 || (total > 0 && (node.tag < min_tag || node.tag > max_tag)))
          c_.fail("node tag " + std::to_string(node.tag) + " outside the declared range [" + std::to_string(min_tag) +
                  ", " + std::to_string(max_tag) + "]");
        node.entity = EntityId{edim, etag};
        node.num_params = np;
        d.nodes.push_back(node);
      }
      for (std::size_t i = 0; i < n; ++i) {
        MshNode& node = d.nodes[first + i];
        for (int k = 0; k < 3; ++k) node.x[k] = real(ctx);
        for (int k = 0; k < np; ++k) node.params[k] = real(ctx);
      }
      seen += n;
    }
    if (seen != total)
      c_.fail_at(header_line,
                 "$Nodes declares " + std::to_string(total) + " nodes but its blocks hold " + std::to_string(seen));
    c_.expect("$EndNodes", ctx);
  }

  void read_elements4(MshData& d) {
    constexpr std::string_view ctx = "$Elements";
    begin_binary(ctx);
    skip_to_data();
    const std::size_t header_line = c_.line();
    const std::size_t blocks = count(ctx), total = count(ctx);
    count(ctx);
    count(ctx);
    plausible(blocks, 4, ctx);
    plausible(total, binary_ ? 16 : 4, ctx);
    d.elements.reserve(total);
    std::size_t seen = 0;
    for (std::size_t b = 0; b < blocks; ++b) {
      skip_to_data();
      const std::size_t block_line = c_.line();
      const int edim = integer(ctx), etag = integer(ctx), type = integer(ctx);
      const std::size_t n = count(ctx);
      const auto info = gmsh_element_info(type);
      if (!info)
        c_.fail_at(block_line, "unsupported element type " + std::to_string(type) + " (" +
                                   gmsh_unsupported_type_name(type) +
                                   "); hom reads complete Lagrange lines, triangles, quadrilaterals, tetrahedra "
                                   "and hexahedra");
      if (edim != info->dim)
        c_.fail_at(block_line, "element type " + std::to_string(type) + " (" + std::string(shape_name(info->shape)) +
                                   ") in a block of entity dimension " + std::to_string(edim));
      if (seen + n > total)
        c_.fail_at(block_line, "$Elements blocks hold more elements than the " + std::to_string(total) + " declared");
      plausible(n, (binary_ ? 8 : 2) * std::size_t(info->num_nodes + 1), ctx);
      for (std::size_t i = 0; i < n; ++i) {
        MshElement e;
        skip_to_data();
        e.line = c_.line();
        e.tag = tag(ctx);
        e.type = type;
        e.entity = EntityId{edim, etag};
        e.first = d.element_nodes.size();
        e.num_nodes = info->num_nodes;
        for (int k = 0; k < info->num_nodes; ++k) d.element_nodes.push_back(tag(ctx));
        d.elements.push_back(e);
      }
      seen += n;
    }
    if (seen != total)
      c_.fail_at(header_line, "$Elements declares " + std::to_string(total) + " elements but its blocks hold " +
                                  std::to_string(seen));
    c_.expect("$EndElements", ctx);
  }

  // In ASCII, report the line an item starts on, not the previous line end.
  void skip_to_data() {
    if (!binary_) c_.skip_space();
  }

  // --- MSH 2 -------------------------------------------------------------------
  void read_nodes2(MshData& d) {
    constexpr std::string_view ctx = "$Nodes";
    const auto n = c_.integer<long long>(ctx);
    if (n < 0) c_.fail("negative count in $Nodes");
    plausible(std::size_t(n), 8, ctx);
    d.nodes.reserve(n);
    for (long long i = 0; i < n; ++i) {
      MshNode node;
      skip_to_data();
      node.line = c_.line();
      const auto t = c_.token(ctx);
      if (t.rfind("$End", 0) == 0)
        c_.fail("$Nodes declares " + std::to_string(n) + " nodes but holds " + std::to_string(i));
      auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), node.tag);
      if (ec != std::errc() || ptr != t.data() + t.size() || node.tag < 1)
        c_.fail("expected a node tag in $Nodes, got '" + Cursor::shorten(t) + "'");
      for (int k = 0; k < 3; ++k) node.x[k] = c_.real(ctx);
      d.nodes.push_back(node);
    }
    const auto end = c_.token(ctx);
    if (end != "$EndNodes") c_.fail("$Nodes holds more than the " + std::to_string(n) + " nodes declared");
  }

  void read_elements2(MshData& d) {
    constexpr std::string_view ctx = "$Elements";
    const auto n = c_.integer<long long>(ctx);
    if (n < 0) c_.fail("negative count in $Elements");
    plausible(std::size_t(n), 8, ctx);
    d.elements.reserve(n);
    for (long long i = 0; i < n; ++i) {
      MshElement e;
      skip_to_data();
      e.line = c_.line();
      const auto t = c_.token(ctx);
      if (t.rfind("$End", 0) == 0)
        c_.fail("$Elements declares " + std::to_string(n) + " elements but holds " + std::to_string(i));
      auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), e.tag);
      if (ec != std::errc() || ptr != t.data() + t.size())
        c_.fail("expected an element tag in $Elements, got '" + Cursor::shorten(t) + "'");
      e.type = c_.integer<int>(ctx);
      const auto info = gmsh_element_info(e.type);
      if (!info)
        c_.fail("unsupported element type " + std::to_string(e.type) + " (" + gmsh_unsupported_type_name(e.type) +
                "); hom reads complete Lagrange lines, triangles, quadrilaterals, tetrahedra and hexahedra");
      const int ntags = c_.integer<int>(ctx);
      if (ntags < 0 || ntags > 64) c_.fail("implausible number of tags " + std::to_string(ntags));
      int tags[2] = {0, 0};
      for (int k = 0; k < ntags; ++k) {
        const int v = c_.integer<int>(ctx);
        if (k < 2) tags[k] = v;
      }
      e.physical = tags[0];
      e.entity = EntityId{info->dim, tags[1]};
      e.first = d.element_nodes.size();
      e.num_nodes = info->num_nodes;
      for (int k = 0; k < info->num_nodes; ++k) d.element_nodes.push_back(c_.integer<std::int64_t>(ctx));
      d.elements.push_back(e);
    }
    const auto end = c_.token(ctx);
    if (end != "$EndElements") c_.fail("$Elements holds more than the " + std::to_string(n) + " elements declared");
  }

  // MSH 2 (and MSH 4 without $Entities): one entity per (dim, elementary tag),
  // with the physical tags its elements carry.
  static void build_entities_from_elements(MshData& d) {
    std::map<EntityId, std::set<int>> phys;
    for (const auto& e : d.elements) {
      auto& s = phys[e.entity];
      if (e.physical != 0) s.insert(e.physical);
    }
    for (const auto& [id, tags] : phys) {
      bool known = false;
      for (const auto& en : d.entities) known = known || en.id == id;
      if (known) continue;
      Entity en;
      en.id = id;
      en.physical_tags.assign(tags.begin(), tags.end());
      d.entities.push_back(std::move(en));
    }
  }

  Cursor c_;
  bool binary_ = false;
};

}  // namespace detail

/// Parses MSH content held in memory; `path` is used in messages.
inline MshData parse_msh(std::string_view content, const std::string& path) {
  return detail::MshParser(content, path).parse();
}

/// Reads and parses an MSH file.
inline MshData read_msh_data(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path + ": cannot open for reading");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw IoError(path + ": read error");
  const std::string content = std::move(ss).str();
  return parse_msh(content, path);
}

}  // namespace hom::io
