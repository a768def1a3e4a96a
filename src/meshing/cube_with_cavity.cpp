// The cube with a spherical cavity of thesis section 4.3.1 (see
// cube_with_cavity.hpp).

#include "cube_with_cavity.hpp"

#include <gmsh.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "gmsh_model.hpp"
#include "hom/geometry/plane.hpp"
#include "hom/geometry/sphere.hpp"
#include "meshing_error.hpp"

namespace hom::meshing {

CubeWithCavity cube_with_cavity(const CubeWithCavityOptions& o) {
  if (!(o.side > 0) || !(o.sphere_diameter > 0) || !(o.sphere_diameter < o.side))
    throw std::invalid_argument("cube_with_cavity: need 0 < sphere diameter < side");
  if (!(o.cube_size > 0) || !(o.sphere_size > 0))
    throw std::invalid_argument("cube_with_cavity: mesh sizes must be positive");
  const GmshSession session({o.verbose, 1, "the cube with a spherical cavity"});
  CubeWithCavity out;
  const double c = o.side / 2;
  out.center = Eigen::Vector3d(c, c, c);
  out.radius = o.sphere_diameter / 2;
  gmsh_call([&] {
    gmsh::model::add("hom_cube_with_cavity");
    gmsh::option::setNumber("General.NumThreads", 1);
    gmsh::option::setNumber("Mesh.RandomSeed", o.seed);
    gmsh::option::setNumber("Mesh.Algorithm", o.algorithm_2d);
    gmsh::option::setNumber("Mesh.Algorithm3D", o.algorithm_3d);
    gmsh::option::setNumber("Mesh.ElementOrder", 1);
    const int box = gmsh::model::occ::addBox(0, 0, 0, o.side, o.side, o.side);
    const int ball = gmsh::model::occ::addSphere(c, c, c, out.radius);
    gmsh::vectorpair result;
    std::vector<gmsh::vectorpair> result_map;
    gmsh::model::occ::cut({{3, box}}, {{3, ball}}, result, result_map);
    gmsh::model::occ::synchronize();
    if (result.size() != 1 || result[0].first != 3) throw std::runtime_error("gmsh: box minus sphere is not one volume");
    const int volume = result[0].second;

    // Mesh sizes at the model's points: the sphere's (its poles) and the cube's corners.
    gmsh::vectorpair points;
    gmsh::model::getEntities(points, 0);
    for (const auto& pt : points) {
      std::vector<double> x;
      gmsh::model::getValue(0, pt.second, {}, x);
      const double r = (Eigen::Vector3d(x[0], x[1], x[2]) - out.center).norm();
      gmsh::model::mesh::setSize({pt}, r < 2 * out.radius ? o.sphere_size : o.cube_size);
    }

    // Identify the surfaces: the sphere by type, the faces by their bounding box.
    gmsh::vectorpair surfaces;
    gmsh::model::getEntities(surfaces, 2);
    std::vector<int> walls;
    for (const auto& [d, tag] : surfaces) {
      std::string type;
      gmsh::model::getType(2, tag, type);
      if (type == "Sphere") {
        out.sphere_tag = tag;
        continue;
      }
      double x0, y0, z0, x1, y1, z1;
      gmsh::model::getBoundingBox(2, tag, x0, y0, z0, x1, y1, z1);
      const double lo[3] = {x0, y0, z0}, hi[3] = {x1, y1, z1};
      const double tol = 1e-6 * o.side;
      for (int a = 0; a < 3; ++a)
        if (hi[a] - lo[a] < tol) out.face_tags[2 * a + (lo[a] > c ? 1 : 0)] = tag;
      walls.push_back(tag);
    }
    if (out.sphere_tag == 0 || walls.size() != 6) throw std::runtime_error("gmsh: unexpected surfaces in box minus sphere");
    for (int t : out.face_tags)
      if (t == 0) throw std::runtime_error("gmsh: could not identify the six faces of the box");

    gmsh::model::setPhysicalName(2, gmsh::model::addPhysicalGroup(2, {out.sphere_tag}), "cavity");
    gmsh::model::setPhysicalName(2, gmsh::model::addPhysicalGroup(2, walls), "walls");
    gmsh::model::setPhysicalName(3, gmsh::model::addPhysicalGroup(3, {volume}), "domain");

    gmsh::model::mesh::generate(3);
  });
  out.mesh = linear_mesh_from_gmsh_model<Simplex<3>>("cube_with_cavity");
  out.geometry = analytic_geometry_from_gmsh_model();
  // The exact sphere and planes (not fitted).
  out.geometry.add_surface(out.sphere_tag, Sphere(out.center, out.radius));
  for (int a = 0; a < 3; ++a)
    for (int s = 0; s < 2; ++s) {
      Eigen::Vector3d origin = Eigen::Vector3d::Zero();
      origin[a] = s * o.side;
      out.geometry.add_surface(out.face_tags[2 * a + s], Plane(origin, (s ? 1.0 : -1.0) * Eigen::Vector3d::Unit(a)));
    }
  gmsh_call([] { gmsh::model::remove(); });
  return out;
}

}  // namespace hom::meshing
