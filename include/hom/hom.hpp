#pragma once
/// @file hom.hpp
/// Everything header-only in hom (needs only Eigen and Boost.Math).
/// Compiled parts (OpenCASCADE, Gmsh, OpenMesh adapters) live in src/.

// Reference element: families, node layout, sub-element split.
#include "hom/element/family.hpp"
#include "hom/element/node_layout.hpp"
#include "hom/element/sub_elements.hpp"

// Node distributions, bases, quadrature.
#include "hom/basis/lagrange.hpp"
#include "hom/basis/lebesgue.hpp"
#include "hom/nodes/equispaced.hpp"
#include "hom/nodes/gauss_lobatto.hpp"
#include "hom/nodes/warp_blend.hpp"
#include "hom/quadrature/gauss.hpp"
#include "hom/quadrature/quadrature_policy.hpp"

// Distortion measures and quality (chapter 3).
#include "hom/measure/oddy_measure.hpp"
#include "hom/measure/regularization.hpp"
#include "hom/measure/shape_measure.hpp"
#include "hom/quality/element_quality.hpp"
#include "hom/quality/ideal.hpp"
#include "hom/quality/mesh_quality.hpp"
#include "hom/quality/statistics.hpp"

// Meshes, topology, elevation, files.
#include "hom/io/msh.hpp"
#include "hom/io/report.hpp"
#include "hom/io/vtu.hpp"
#include "hom/mesh/boundary_layer.hpp"
#include "hom/mesh/coloring.hpp"
#include "hom/mesh/elevate.hpp"
#include "hom/mesh/flat_corners.hpp"
#include "hom/mesh/mesh.hpp"
#include "hom/mesh/structured.hpp"
#include "hom/mesh/sub_mesh.hpp"
#include "hom/mesh/topology.hpp"

// Geometry of boundary entities (analytic curves and surfaces, the thesis's parameterizations).
#include "hom/geometry/circle.hpp"
#include "hom/geometry/curve_boundary.hpp"
#include "hom/geometry/cylinder.hpp"
#include "hom/geometry/geometry_model.hpp"
#include "hom/geometry/hyperbolic_paraboloid.hpp"
#include "hom/geometry/line.hpp"
#include "hom/geometry/plane.hpp"
#include "hom/geometry/sphere.hpp"
#include "hom/geometry/thesis_parameterizations.hpp"
#include "hom/geometry/torus.hpp"
// Certified validity (Bernstein bounds of det D phi).
#include "hom/quality/certify.hpp"
// Optimization (chapter 4, appendices B-C; boundary layers, section 6.3.3).
#include "hom/optimize/boundary_layer_pipeline.hpp"
#include "hom/optimize/certified.hpp"
#include "hom/optimize/continuation.hpp"
#include "hom/optimize/element_objective.hpp"
#include "hom/optimize/linear_formulation.hpp"
#include "hom/optimize/optimize.hpp"
// Meshes on parameterized surfaces (chapter 5).
#include "hom/surface/certified_surface.hpp"
#include "hom/surface/normal_jacobian_bernstein.hpp"
#include "hom/surface/optimize_boundary_face.hpp"
#include "hom/surface/optimize_surface.hpp"
#include "hom/surface/surface_continuation.hpp"
#include "hom/surface/surface_mesh_quality.hpp"
#include "hom/surface/unit_normal.hpp"
