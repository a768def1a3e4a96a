// The boundary-layer pipeline (include/hom/optimize/boundary_layer_pipeline.hpp)
// on the thesis's case of section 6.3.3.1, scaled down: a sphere of diameter
// 1 inside a box (src/meshing/cube_with_cavity, Gmsh), the exact sphere as
// the wall, p = 2, a few layers. Every stage has the template's element
// count, the smoothed linear and the final curved meshes are valid, and the
// final wall nodes lie on the sphere.

#include <doctest/doctest.h>

#include <cstdio>
#include <cstdlib>

#include "../src/meshing/cube_with_cavity.hpp"
#include "hom/geometry/sphere.hpp"
#include "hom/optimize/boundary_layer_pipeline.hpp"

TEST_CASE("boundary layer pipeline: sphere of diameter 1 in a box, p = 2") {
  hom::meshing::CubeWithCavityOptions mo;
  mo.side = 2.0;
  mo.cube_size = 0.8;
  mo.sphere_size = 0.3;
  const auto cav = hom::meshing::cube_with_cavity(mo);
  const auto& in = cav.mesh;
  hom::GeometryModel<3> wall;
  wall.add_surface(cav.sphere_tag, hom::Sphere(cav.center, cav.radius));

  hom::BoundaryLayerPipelineOptions o;
  o.layer = {.first_height = 0.01, .growth = 2.0, .layers = 2};
  o.p = 2;
  // A valid result is the point here, not full convergence (keeps the test short).
  o.high_order_optimize.iterations_after_valid = 1;
  // Valid means det > 0 at the nodes too (BoundaryLayerPipelineResult::valid):
  // stage (e) stopped one iteration after its quadrature points were valid
  // leaves a fold at a corner node (min scaled Jacobian -0.026), which
  // certify-and-repair finds and mends.
  o.high_order_optimize.certify = true;
  if (std::getenv("HOM_TEST_VERBOSE")) {  // progress of a slow run
    o.linear_optimize.verbose = o.high_order_optimize.verbose = true;
    o.progress = [](const std::string& stage) { std::fprintf(stderr, "stage %s done\n", stage.c_str()); };
  }
  const auto r = hom::boundary_layer_pipeline<3>(in, {cav.sphere_tag}, wall, o);

  int T = 0;
  for (const auto& f : in.boundary_facets()) T += f.entity_tag == cav.sphere_tag;
  REQUIRE(r.stages.size() == 5);
  CHECK(r.layer.num_wall_facets == T);
  for (int s = 1; s < 5; ++s) CHECK(r.stages[s].elements == in.num_elements() + T * (12 * 1 + 7));
  for (const auto& s : r.stages)
    std::printf("%-9s p=%d elems=%6d nodes=%6d min=%.3f max=%.3f mean=%.3f std=%.3f inv=%d minSJ=%.3f it=%d t=%.2fs\n",
                s.name.c_str(), s.p, s.elements, s.nodes, s.quality.min, s.quality.max, s.quality.mean, s.quality.std_dev,
                s.quality.inverted, s.scaled_jacobian.min, s.iterations, s.time_s);
  CHECK(r.stages[2].quality.inverted == 0);
  CHECK(r.stages[4].quality.inverted == 0);
  CHECK(r.stages[4].quality.min > 0.0);
  CHECK(r.valid);
  CHECK(r.stages[4].scaled_jacobian.min > 0.0);
  REQUIRE(r.certification.has_value());
  CHECK(r.certification->certified());
  CHECK(r.certification->valid == r.stages[4].elements);
  // The final wall: every node of a wall facet on the sphere.
  for (const auto& f : r.mesh.boundary_facets())
    if (f.entity_tag == cav.sphere_tag)
      for (int n : r.mesh.facet_node_ids(f))
        CHECK((r.mesh.node(n) - cav.center).norm() == doctest::Approx(cav.radius).epsilon(1e-10));
}
