#pragma once
/// @file mesh_io.hpp
/// What the `hom` subcommands share for mesh files: choosing the Mesh type
/// that fits a file at run time, and writing a mesh in the format its file
/// name asks for.
///
///   const auto data = hom::io::read_msh_data(path);
///   hom::tools::with_mesh<hom::WarpBlend>(data, [&](auto& mesh) { ... });
///
/// The lambda is instantiated for triangles and quadrilaterals (planar, and
/// surfaces in 3D) and tetrahedra and hexahedra.

#include <string>
#include <utility>

#include "command.hpp"
#include "hom/io/msh.hpp"
#include "hom/io/vtu.hpp"

namespace hom::tools {

/// Builds the Mesh the file holds and calls f(mesh) (a mutable lvalue). The
/// family comes from the file's highest-dimensional elements; 2D meshes with
/// a node off z = 0 become surface meshes (SpaceDim = 3).
template <NodeSet Nodes, class F>
decltype(auto) with_mesh(const io::MshData& data, F&& f) {
  const auto s = io::summarize(data);
  if (s.top_shapes.size() > 1)
    throw io::IoError(data.path + ": the mesh mixes " + std::string(io::shape_name(s.top_shapes[0])) + " and " +
                      std::string(io::shape_name(s.top_shapes[1])) + " elements; hom needs one element family per mesh");
  if (s.dim < 2 || s.top_shapes.empty()) throw io::IoError(data.path + ": no triangles, quadrilaterals, tetrahedra or hexahedra");
  switch (s.top_shapes[0]) {
    case io::GmshShape::triangle:
      if (s.planar) {
        auto m = io::to_mesh<Simplex<2>, Nodes, 2>(data);
        return f(m);
      } else {
        auto m = io::to_mesh<Simplex<2>, Nodes, 3>(data);
        return f(m);
      }
    case io::GmshShape::quadrilateral:
      if (s.planar) {
        auto m = io::to_mesh<Cube<2>, Nodes, 2>(data);
        return f(m);
      } else {
        auto m = io::to_mesh<Cube<2>, Nodes, 3>(data);
        return f(m);
      }
    case io::GmshShape::tetrahedron: {
      auto m = io::to_mesh<Simplex<3>, Nodes, 3>(data);
      return f(m);
    }
    default: {
      auto m = io::to_mesh<Cube<3>, Nodes, 3>(data);
      return f(m);
    }
  }
}

/// Output chosen by the file name's extension and the options.
struct OutputFormat {
  enum class Kind { msh, vtu };
  Kind kind = Kind::msh;
  io::MshFormat msh;
  io::VtuOptions vtu;
};

inline bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

/// `msh_version` "4.1" or "2.2"; `binary` selects MSH 4.1 binary; `ascii` ASCII VTU.
inline OutputFormat output_format(const std::string& path, const std::string& msh_version, bool binary, bool ascii) {
  OutputFormat f;
  if (ends_with(path, ".vtu")) {
    f.kind = OutputFormat::Kind::vtu;
    if (binary && ascii) throw UsageError("--binary and --ascii exclude each other");
    f.vtu.encoding = ascii ? io::VtuOptions::Encoding::ascii : io::VtuOptions::Encoding::base64;
    return f;
  }
  if (!ends_with(path, ".msh")) throw UsageError("output '" + path + "': the file name must end in .msh or .vtu");
  if (msh_version == "4.1")
    f.msh.version = io::MshFormat::Version::v41;
  else if (msh_version == "2.2")
    f.msh.version = io::MshFormat::Version::v22;
  else
    throw UsageError("--msh-version must be 4.1 or 2.2, got '" + msh_version + "'");
  if (ascii && binary) throw UsageError("--binary and --ascii exclude each other");
  if (binary && f.msh.version == io::MshFormat::Version::v22) throw UsageError("MSH 2.2 output is ASCII only");
  f.msh.binary = binary;
  return f;
}

/// Node kinds as numbers, for a VTU point array: 0 free, 1 fixed, 2 on an entity.
template <class MeshT>
io::VtuField node_kind_field(const MeshT& m) {
  io::VtuField f{"node_kind", 1, {}};
  f.values.reserve(m.num_nodes());
  for (const auto& c : m.node_classes()) f.values.push_back(c.kind == NodeKind::free ? 0.0 : c.kind == NodeKind::fixed ? 1.0 : 2.0);
  return f;
}

/// Writes a mesh as MSH or VTU (with the node kinds and entity ids).
template <class MeshT>
void write_mesh(const std::string& path, const MeshT& m, const OutputFormat& f) {
  if (f.kind == OutputFormat::Kind::msh) {
    io::write_msh(path, m, f.msh);
  } else {
    io::VtuOptions o = f.vtu;
    o.interpolate_point_data = false;
    io::write_vtu(path, m, {node_kind_field(m)}, {}, o);
  }
}

}  // namespace hom::tools
