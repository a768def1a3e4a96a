// bench/mesh_cut.hpp: planar cuts through curved tetrahedral meshes (the
// figures of bench_untangle, bench_smooth and bench_boundary_layer), checked
// against exact cross-section areas of analytic maps of the unit cube.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "../bench/mesh_cut.hpp"
#include "hom/measure/shape_measure.hpp"
#include "hom/mesh/elevate.hpp"
#include "hom/mesh/structured.hpp"
#include "hom/quadrature/quadrature_policy.hpp"
#include "hom/quality/mesh_quality.hpp"

namespace {

using TetMesh = hom::Mesh<hom::Simplex<3>>;

/// Shoelace area of a polygon given by its vertices in order.
double polygon_area(const std::vector<Eigen::Vector2d>& points) {
  double twice = 0.0;
  for (std::size_t k = 0; k < points.size(); ++k) {
    const auto& a = points[k];
    const auto& b = points[(k + 1) % points.size()];
    twice += a.x() * b.y() - a.y() * b.x();
  }
  return 0.5 * std::abs(twice);
}

double cut_area(const std::vector<hom::bench::CutPolygon>& polygons) {
  double area = 0.0;
  for (const auto& p : polygons) area += polygon_area(p.points);
  return area;
}

/// The degree-3 Kuhn mesh of the unit cube, 3 cells a side, with every node
/// moved by (x, y, z) -> (x (1 + a y^2), y, z): a cubic map, so each element's
/// degree-3 map is exactly its restriction, and every plane z = c cuts the
/// image in the region 0 <= x <= 1 + a y^2, 0 <= y <= 1, of area 1 + a / 3.
TetMesh bent_cube(double a) {
  TetMesh mesh = hom::elevate(hom::structured_mesh<hom::Simplex<3>>({3, 3, 3}), 3);
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    Eigen::Vector3d x = mesh.node(i);
    x.x() *= 1.0 + a * x.y() * x.y();
    mesh.node(i) = x;
  }
  return mesh;
}

const auto plane = hom::bench::CutPlane::normal_z(Eigen::Vector3d(0.0, 0.0, 0.52));

}  // namespace

TEST_CASE("mesh_cut: the cut of a straight-sided cube is its unit cross-section, each polygon in its element") {
  const TetMesh mesh = bent_cube(0.0);
  for (int n : {1, 6}) {
    CAPTURE(n);
    const auto polygons = hom::bench::cut_mesh(mesh, plane, n);
    REQUIRE(!polygons.empty());
    CHECK(cut_area(polygons) == doctest::Approx(1.0).epsilon(1e-12));
    for (const auto& p : polygons) {
      REQUIRE(p.points.size() >= 3);
      REQUIRE(p.points.size() <= 4);
      REQUIRE(p.element >= 0);
      REQUIRE(p.element < mesh.num_elements());
      // Straight-sided: the element's nodes span the plane's height.
      const Eigen::Matrix3Xd x = mesh.element_coordinates(p.element);
      CHECK(x.row(2).minCoeff() <= 0.52);
      CHECK(x.row(2).maxCoeff() >= 0.52);
    }
  }
}

TEST_CASE("mesh_cut: a curved boundary is followed to second order in the lattice spacing") {
  // The cut is phi_e's piecewise-linear interpolant on the degree-n lattice.
  // On the face x = 1 + a y^2 that interpolant of a convex function lies
  // outside it, so the area exceeds 1 + a / 3 by O((h / n)^2), h = 1/3.
  const double a = 0.3, exact = 1.0 + a / 3.0;
  const TetMesh mesh = bent_cube(a);
  const double coarse = cut_area(hom::bench::cut_mesh(mesh, plane, 1)) - exact;  // element vertices only
  const double fine = cut_area(hom::bench::cut_mesh(mesh, plane, 6)) - exact;
  CAPTURE(coarse);
  CAPTURE(fine);
  CHECK(coarse > 0.0);
  CHECK(fine > 0.0);
  CHECK(coarse <= a * std::pow(1.0 / 3.0, 2));
  CHECK(fine <= a * std::pow(1.0 / 18.0, 2));
  CHECK(fine < coarse / 12.0);  // (1/6)^2 = 1/36 asymptotically
}

TEST_CASE("mesh_cut: write_mid_z_cut_csv cuts through the bounding box's middle, also through lattice points") {
  // At z = 0.5 the degree-6 lattice of the 3-cell cube has points on the
  // plane (z = 9/18): the faces lying in it must be counted once.
  const TetMesh mesh = bent_cube(0.0);
  const auto quality = hom::mesh_quality(mesh, hom::ShapeMeasure{}, hom::IdealKind::straight_sided,
                                         hom::quadrature_for<hom::Simplex<3>, hom::DefaultExactness>(3));
  const auto path = std::filesystem::temp_directory_path() / "hom_test_mesh_cut.csv";
  hom::bench::write_mid_z_cut_csv(path.string(), mesh, quality);
  std::ifstream in(path);
  std::string line;
  REQUIRE(std::getline(in, line));
  CHECK(line == "element,polygon,x,y,quality,inverted,level");
  std::map<int, std::vector<Eigen::Vector2d>> polygons;
  int rows = 0;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    std::string field[7];
    for (auto& f : field) REQUIRE(std::getline(s, f, ','));
    polygons[std::stoi(field[1])].emplace_back(std::stod(field[2]), std::stod(field[3]));
    CHECK(std::stod(field[4]) == doctest::Approx(1.0));  // straight-sided against itself
    CHECK(field[5] == "0");
    CHECK(field[6] == "-1");
    ++rows;
  }
  std::filesystem::remove(path);
  REQUIRE(rows > 0);
  double area = 0.0;
  for (const auto& [k, points] : polygons) area += polygon_area(points);
  CHECK(area == doctest::Approx(1.0).epsilon(1e-9));
}
