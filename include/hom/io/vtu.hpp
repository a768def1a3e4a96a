#pragma once
/// @file vtu.hpp
/// VTK XML unstructured grid (.vtu) output with Lagrange cells, so ParaView
/// draws curved elements (with its "Nonlinear Subdivision Level" setting).
///
///   hom::io::write_vtu("q.vtu", mesh, {{"quality", 1, q_per_node}}, {{"scaled_jacobian", 1, sj}});
///
/// Cells are VTK_LAGRANGE_TRIANGLE (69), _QUADRILATERAL (70), _TETRAHEDRON
/// (71) or _HEXAHEDRON (72) of the mesh's degree, with VTK's node order
/// (vtk_cells.hpp). VTK interpolates equispaced nodes, so the points are hom's
/// map evaluated at the equispaced reference nodes (one point per hom node,
/// same ids). Point data given per hom node is, by default, interpolated the
/// same way (the nodal field of the node set evaluated at the equispaced
/// nodes), so that VTK draws the same polynomial field; set
/// `interpolate_point_data = false` for flags and ids. Cell data has one
/// tuple per element. An "entity" cell array (the elements' entity tags) is
/// added unless the caller passes one.
///
/// Encodings: ASCII, or appended base64 binary (the default; UInt64 headers,
/// little-endian), file format version 2.2 (VTK 9's Lagrange hexahedron edge
/// order). The file is written to FILE.tmp and renamed (error.hpp).

#include <charconv>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include "hom/io/error.hpp"
#include "hom/io/vtk_cells.hpp"
#include "hom/mesh/mesh.hpp"
#include "hom/nodes/equispaced.hpp"

namespace hom::io {

/// A named data array: `components` values per point or cell, interleaved.
struct VtuField {
  std::string name;
  int components = 1;
  std::vector<double> values;
};

struct VtuOptions {
  enum class Encoding { ascii, base64 };
  Encoding encoding = Encoding::base64;
  bool interpolate_point_data = true;
  bool entity_ids = true;  ///< add the "entity" cell array
};

namespace detail {

inline void base64_append(std::string& out, const unsigned char* data, std::size_t n) {
  static constexpr char table[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::size_t i = 0;
  for (; i + 2 < n; i += 3) {
    const unsigned v = (unsigned(data[i]) << 16) | (unsigned(data[i + 1]) << 8) | data[i + 2];
    out.push_back(table[(v >> 18) & 63]);
    out.push_back(table[(v >> 12) & 63]);
    out.push_back(table[(v >> 6) & 63]);
    out.push_back(table[v & 63]);
  }
  if (i < n) {
    unsigned v = unsigned(data[i]) << 16;
    if (i + 1 < n) v |= unsigned(data[i + 1]) << 8;
    out.push_back(table[(v >> 18) & 63]);
    out.push_back(table[(v >> 12) & 63]);
    out.push_back(i + 1 < n ? table[(v >> 6) & 63] : '=');
    out.push_back('=');
  }
}

class VtuBuilder {
 public:
  explicit VtuBuilder(bool ascii) : ascii_(ascii) {}

  template <class T>
  void array(const std::string& name, int components, const std::vector<T>& v) {
    xml_ += "        <DataArray type=\"";
    xml_ += type_name<T>();
    xml_ += "\" Name=\"" + name + "\"";
    if (components != 1) xml_ += " NumberOfComponents=\"" + std::to_string(components) + "\"";
    if (ascii_) {
      xml_ += " format=\"ascii\">\n";
      std::size_t col = 0;
      for (const T& x : v) {
        char buf[32];
        auto [p, ec] = std::to_chars(buf, buf + sizeof buf, x);
        xml_.append(buf, p);
        xml_ += ++col % 12 == 0 ? '\n' : ' ';
      }
      xml_ += "\n        </DataArray>\n";
    } else {
      xml_ += " format=\"appended\" offset=\"" + std::to_string(appended_.size()) + "\"/>\n";
      // One base64 stream per array: the UInt64 byte count, then the data.
      const std::uint64_t bytes = v.size() * sizeof(T);
      std::string block(sizeof bytes + bytes, '\0');
      std::memcpy(block.data(), &bytes, sizeof bytes);
      if (bytes) std::memcpy(block.data() + sizeof bytes, v.data(), bytes);
      base64_append(appended_, reinterpret_cast<const unsigned char*>(block.data()), block.size());
    }
  }

  std::string& xml() { return xml_; }
  const std::string& appended() const { return appended_; }

 private:
  template <class T>
  static const char* type_name() {
    if constexpr (std::is_same_v<T, double>) return "Float64";
    if constexpr (std::is_same_v<T, std::int64_t>) return "Int64";
    if constexpr (std::is_same_v<T, std::int32_t>) return "Int32";
    if constexpr (std::is_same_v<T, std::uint8_t>) return "UInt8";
  }

  bool ascii_;
  std::string xml_;
  std::string appended_;
};

}  // namespace detail

/// Writes the mesh with optional point data (per hom node) and cell data (per
/// element). Throws IoError on a field of the wrong size or a write failure.
template <ElementFamily Family, NodeSet Nodes, int SpaceDim>
void write_vtu(const std::string& path, const Mesh<Family, Nodes, SpaceDim>& m,
               const std::vector<VtuField>& point_data = {}, const std::vector<VtuField>& cell_data = {},
               const VtuOptions& options = {}) {
  constexpr int nv = Family::num_vertices;
  const int p = m.degree();
  const int np = m.nodes_per_element();
  const int N = m.num_nodes(), E = m.num_elements();
  for (const auto& f : point_data)
    if (f.components < 1 || f.values.size() != std::size_t(f.components) * N)
      throw IoError(path + ": point data '" + f.name + "' needs " + std::to_string(f.components) + " x " +
                    std::to_string(N) + " values, got " + std::to_string(f.values.size()));
  for (const auto& f : cell_data)
    if (f.components < 1 || f.values.size() != std::size_t(f.components) * E)
      throw IoError(path + ": cell data '" + f.name + "' needs " + std::to_string(f.components) + " x " +
                    std::to_string(E) + " values, got " + std::to_string(f.values.size()));

  // Points (and interpolated point data) at the equispaced reference nodes.
  constexpr bool same_nodes = std::is_same_v<Nodes, Equispaced>;
  Eigen::MatrixXd B;
  if constexpr (!same_nodes) B = m.basis().values(node_layout<Family>(p).equispaced_points()).transpose();
  std::vector<double> points(3 * std::size_t(N), 0.0);
  std::vector<std::vector<double>> pdata(point_data.size());
  for (std::size_t k = 0; k < point_data.size(); ++k) pdata[k] = point_data[k].values;
  std::vector<char> done(N, 0);
  for (int e = 0; e < E; ++e) {
    const auto ids = m.element(e);
    Eigen::MatrixXd Xe = m.element_coordinates(e);
    if constexpr (!same_nodes) Xe = Xe * B;
    for (int i = 0; i < np; ++i) {
      const int n = ids[i];
      if (done[n]) continue;
      done[n] = 1;
      for (int a = 0; a < SpaceDim; ++a) points[3 * std::size_t(n) + a] = i < nv ? m.node(n)[a] : Xe(a, i);
      if (!same_nodes && options.interpolate_point_data && i >= nv)
        for (std::size_t k = 0; k < point_data.size(); ++k) {
          const auto& f = point_data[k];
          for (int c = 0; c < f.components; ++c) {
            double s = 0;
            for (int j = 0; j < np; ++j) s += B(j, i) * f.values[std::size_t(ids[j]) * f.components + c];
            pdata[k][std::size_t(n) * f.components + c] = s;
          }
        }
    }
  }

  const auto& perm = vtk_to_hom<Family>(p);
  std::vector<std::int64_t> connectivity, offsets;
  connectivity.reserve(std::size_t(E) * np);
  offsets.reserve(E);
  for (int e = 0; e < E; ++e) {
    for (int k = 0; k < np; ++k) connectivity.push_back(m.element(e)[perm[k]]);
    offsets.push_back(std::int64_t(e + 1) * np);
  }
  const std::vector<std::uint8_t> types(E, std::uint8_t(vtk_lagrange_cell_type<Family>));

  const bool ascii = options.encoding == VtuOptions::Encoding::ascii;
  detail::VtuBuilder b(ascii);
  auto& x = b.xml();
  x += "<?xml version=\"1.0\"?>\n";
  x += "<VTKFile type=\"UnstructuredGrid\" version=\"2.2\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n";
  x += "  <UnstructuredGrid>\n";
  x += "    <Piece NumberOfPoints=\"" + std::to_string(N) + "\" NumberOfCells=\"" + std::to_string(E) + "\">\n";
  x += "      <PointData>\n";
  for (std::size_t k = 0; k < point_data.size(); ++k) b.array(point_data[k].name, point_data[k].components, pdata[k]);
  x += "      </PointData>\n      <CellData>\n";
  bool has_entity = false;
  for (const auto& f : cell_data) {
    b.array(f.name, f.components, f.values);
    has_entity = has_entity || f.name == "entity";
  }
  if (options.entity_ids && !has_entity) {
    std::vector<std::int32_t> ent(m.element_entities().begin(), m.element_entities().end());
    b.array("entity", 1, ent);
  }
  x += "      </CellData>\n      <Points>\n";
  b.array("Points", 3, points);
  x += "      </Points>\n      <Cells>\n";
  b.array("connectivity", 1, connectivity);
  b.array("offsets", 1, offsets);
  b.array("types", 1, types);
  x += "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n";
  if (!ascii) {
    x += "  <AppendedData encoding=\"base64\">\n   _";
    x += b.appended();
    x += "\n  </AppendedData>\n";
  }
  x += "</VTKFile>\n";
  write_atomically(path, [&](std::FILE* f) { write_all(f, path, x.data(), x.size()); });
}

}  // namespace hom::io
