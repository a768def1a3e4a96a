// The cube with a graded size field of thesis section 4.3.3 (see
// sized_cube.hpp).

#include "sized_cube.hpp"

#include <gmsh.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "gmsh_model.hpp"
#include "hom/geometry/plane.hpp"
#include "meshing_error.hpp"

namespace hom::meshing {

double sized_cube_size(const SizedCubeOptions& o, const Eigen::Vector3d& x) {
  const Eigen::Vector3d c = Eigen::Vector3d::Constant(o.side / 2);
  const Eigen::Vector3d d = x - c;
  const double r = d.norm(), radius = o.sphere_diameter / 2;
  if (r <= radius) return o.inner_size;
  // Along the ray from the centre through x the boundary is at rho = (side/2) r / |d|_inf.
  const double rho = (o.side / 2) * r / d.cwiseAbs().maxCoeff();
  const double t = std::clamp((r - radius) / (rho - radius), 0.0, 1.0);
  return o.inner_size + (o.outer_size - o.inner_size) * std::pow(t, o.grading);
}

SizedCube sized_cube(const SizedCubeOptions& o) {
  if (!(o.side > 0) || !(o.sphere_diameter > 0) || !(o.sphere_diameter < o.side))
    throw std::invalid_argument("sized_cube: need 0 < sphere diameter < side");
  if (!(o.inner_size > 0) || !(o.outer_size > 0) || !(o.grading > 0))
    throw std::invalid_argument("sized_cube: mesh sizes and grading must be positive");
  const GmshSession session({o.verbose, 1, "the sized cube"});
  SizedCube out;
  out.center = Eigen::Vector3d::Constant(o.side / 2);
  gmsh_call([&] {
    gmsh::model::add("hom_sized_cube");
    gmsh::option::setNumber("General.NumThreads", 1);
    gmsh::option::setNumber("Mesh.RandomSeed", o.seed);
    gmsh::option::setNumber("Mesh.Algorithm", o.algorithm_2d);
    gmsh::option::setNumber("Mesh.Algorithm3D", o.algorithm_3d);
    gmsh::option::setNumber("Mesh.ElementOrder", 1);
    const int box = gmsh::model::occ::addBox(0, 0, 0, o.side, o.side, o.side);
    gmsh::model::occ::synchronize();

    // Faces by their bounding box.
    gmsh::vectorpair surfaces;
    gmsh::model::getEntities(surfaces, 2);
    std::vector<int> walls;
    for (const auto& [d, tag] : surfaces) {
      double x0, y0, z0, x1, y1, z1;
      gmsh::model::getBoundingBox(2, tag, x0, y0, z0, x1, y1, z1);
      const double lo[3] = {x0, y0, z0}, hi[3] = {x1, y1, z1};
      for (int a = 0; a < 3; ++a)
        if (hi[a] - lo[a] < 1e-6 * o.side) out.face_tags[2 * a + (lo[a] > o.side / 2 ? 1 : 0)] = tag;
      walls.push_back(tag);
    }
    if (walls.size() != 6) throw std::runtime_error("gmsh: the box does not have six faces");
    for (int t : out.face_tags)
      if (t == 0) throw std::runtime_error("gmsh: could not identify the six faces of the box");
    gmsh::model::setPhysicalName(2, gmsh::model::addPhysicalGroup(2, walls), "walls");
    gmsh::model::setPhysicalName(3, gmsh::model::addPhysicalGroup(3, {box}), "domain");

    // The size field alone decides the size (no sizes from points, boundary or curvature).
    double from_points = 1, from_boundary = 1, from_curvature = 0;
    gmsh::option::getNumber("Mesh.MeshSizeFromPoints", from_points);
    gmsh::option::getNumber("Mesh.MeshSizeExtendFromBoundary", from_boundary);
    gmsh::option::getNumber("Mesh.MeshSizeFromCurvature", from_curvature);
    gmsh::option::setNumber("Mesh.MeshSizeFromPoints", 0);
    gmsh::option::setNumber("Mesh.MeshSizeExtendFromBoundary", 0);
    gmsh::option::setNumber("Mesh.MeshSizeFromCurvature", 0);
    gmsh::model::mesh::setSizeCallback(
        [o](int, int, double x, double y, double z) { return sized_cube_size(o, Eigen::Vector3d(x, y, z)); });
    gmsh::model::mesh::generate(3);
    gmsh::model::mesh::removeSizeCallback();
    gmsh::option::setNumber("Mesh.MeshSizeFromPoints", from_points);
    gmsh::option::setNumber("Mesh.MeshSizeExtendFromBoundary", from_boundary);
    gmsh::option::setNumber("Mesh.MeshSizeFromCurvature", from_curvature);
  });
  out.mesh = linear_mesh_from_gmsh_model<Simplex<3>>("sized_cube");
  out.geometry = analytic_geometry_from_gmsh_model();
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
