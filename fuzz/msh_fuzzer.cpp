// libFuzzer target for the MSH reader (include/hom/io/msh_reader.hpp and the
// conversion to Mesh in msh.hpp). Build and run with fuzz/run.
//
// Properties checked on every input:
//   - parsing and conversion either succeed or throw hom::io::IoError (any
//     other exception, a crash or a sanitizer report is a bug);
//   - a mesh hom accepts can be written (MSH 4.1 ASCII and binary, 2.2) and
//     read back to the same connectivity.
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "hom/io/msh.hpp"

namespace {

template <hom::ElementFamily F, int SpaceDim>
void try_family(const hom::io::MshData& d) {
  using Mesh = hom::Mesh<F, hom::Equispaced, SpaceDim>;
  Mesh m;
  try {
    m = hom::io::to_mesh<F, hom::Equispaced, SpaceDim>(d);
  } catch (const hom::io::IoError&) {
    return;
  }
  hom::io::MshData back;
  try {
    back = hom::io::to_msh_data(m);
  } catch (const hom::io::IoError&) {
    return;  // e.g. nothing to write
  }
  for (int v = 0; v < 3; ++v) {
    const std::string s = v == 2 ? hom::io::detail::serialize_msh22(back) : hom::io::detail::serialize_msh41(back, v == 1);
    const auto again = hom::io::to_mesh<F, hom::Equispaced, SpaceDim>(hom::io::parse_msh(s, "rewritten.msh"));
    if (again.elements() != m.elements() || again.num_nodes() != m.num_nodes()) std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view content(reinterpret_cast<const char*>(data), size);
  hom::io::MshData d;
  try {
    d = hom::io::parse_msh(content, "fuzz.msh");
  } catch (const hom::io::IoError&) {
    return 0;
  }
  (void)hom::io::summarize(d);
  try_family<hom::Simplex<2>, 2>(d);
  try_family<hom::Simplex<2>, 3>(d);
  try_family<hom::Cube<2>, 2>(d);
  try_family<hom::Simplex<3>, 3>(d);
  try_family<hom::Cube<3>, 3>(d);
  return 0;
}
