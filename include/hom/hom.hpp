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
#include "hom/mesh/mesh.hpp"
#include "hom/mesh/structured.hpp"
#include "hom/mesh/sub_mesh.hpp"
#include "hom/mesh/topology.hpp"

// Optimization (chapter 4, appendices B-C).
#include "hom/optimize/element_objective.hpp"
