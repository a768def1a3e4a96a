#pragma once
/// @file sized_cube.hpp
/// The test geometry of thesis section 4.3.3 (tables 4.4, 4.5, figure 4.10):
/// a cube of side 5 meshed with linear tetrahedra of non-constant size,
/// 0.1 inside a spherical region of diameter 1 at the cube's centre and 2 on
/// the outer boundary. There is no cavity: the sphere only shapes the size
/// field (it is not a surface of the model), so every boundary face is
/// planar and the elevated mesh stays straight-sided.
///
/// Size field (a Gmsh size callback): h = inner_size for r <= R (r the
/// distance to the centre, R the sphere's radius); outside, along each ray
/// from the centre, h = inner_size + (outer_size - inner_size) t^grading with
/// t = (r - R) / (rho - R) and rho the distance from the centre to the cube's
/// boundary along that ray, so that h = outer_size on the whole boundary. The
/// thesis states the two sizes, not the law between them; the exponent sets
/// how fast the size grows. With Gmsh 4.8.4 and the defaults (grading 1.33)
/// the mesh has 7425 tetrahedra and 1256 vertices against the thesis's 7394
/// tetrahedra (linear grading, 1.0, gives about 5000).
///
/// Meshing is deterministic as in cube_with_cavity.hpp: one thread, fixed
/// random seed, fixed algorithms, no user configuration files. The six faces
/// are surface entities (tags in the result) with physical group "walls",
/// the volume has physical group "domain"; the geometry model holds the six
/// exact planes and the twelve edges' lines.

#include <array>

#include <Eigen/Core>

#include "hom/element/simplex.hpp"
#include "hom/geometry/geometry_model.hpp"
#include "hom/mesh/mesh.hpp"

namespace hom::meshing {

struct SizedCubeOptions {
  double side = 5.0;
  double sphere_diameter = 1.0;  ///< the refined region: a ball at the cube's centre
  double inner_size = 0.1;       ///< mesh size inside the ball
  double outer_size = 2.0;       ///< mesh size on the cube's boundary
  double grading = 1.33;         ///< exponent of the size law between them (see the file comment)
  int seed = 1;                  ///< Mesh.RandomSeed
  int algorithm_2d = 6;          ///< Mesh.Algorithm (6: Frontal-Delaunay)
  int algorithm_3d = 1;          ///< Mesh.Algorithm3D (1: Delaunay)
  bool verbose = false;
};

struct SizedCube {
  Mesh<Simplex<3>> mesh;                ///< linear, classified
  GeometryModel<3> geometry;            ///< the exact planes and lines
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  std::array<int, 6> face_tags{};       ///< surface entities of the faces x=0, x=side, y=0, y=side, z=0, z=side
};

/// The mesh size of the options' size field at x (exposed for tests).
double sized_cube_size(const SizedCubeOptions& options, const Eigen::Vector3d& x);

/// Builds and meshes the cube (opens and closes its own Gmsh session, or uses
/// the caller's; Gmsh options it changes are restored). Throws
/// std::invalid_argument on bad options, std::runtime_error if Gmsh fails.
SizedCube sized_cube(const SizedCubeOptions& options = {});

}  // namespace hom::meshing
