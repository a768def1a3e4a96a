// A minimal program using hom's header-only core: it builds a degree-3
// triangle mesh of the unit square, drags one interior node across its
// neighbours and counts the elements that this inverts (definition 3.6).
#include <iostream>

#include <hom/hom.hpp>

int main() {
  using Tri = hom::Simplex<2>;
  auto mesh = hom::elevate(hom::structured_mesh<Tri, hom::WarpBlend>({3, 3}, Eigen::Vector2d(0, 0), Eigen::Vector2d(1, 1)), 3);
  int moved = -1;
  for (int i = 0; i < mesh.num_nodes() && moved < 0; ++i)
    if (mesh.node_class(i).kind == hom::NodeKind::free && mesh.vertex_mask()[i]) moved = i;
  if (moved < 0) return 1;
  mesh.node(moved) += Eigen::Vector2d(0.4, 0.35);
  const auto rule = hom::quadrature_for<Tri, hom::DefaultExactness>(mesh.degree());
  const auto stats = hom::mesh_quality(mesh, hom::ShapeMeasure{}, hom::IdealKind::straight_sided, rule).quality_statistics();
  std::cout << "triangles p=3: " << stats.inverted << " of " << mesh.num_elements() << " inverted, min quality "
            << stats.min << "\n";
  return stats.inverted > 0 && stats.inverted < mesh.num_elements() ? 0 : 1;
}
