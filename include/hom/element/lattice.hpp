#pragma once
/// @file lattice.hpp
/// Integer lattice multi-indices that identify the nodes of a degree-p element
/// independently of the node distribution (equispaced, warp & blend,
/// Gauss-Lobatto): a node set maps a lattice index to reference coordinates.

#include <array>

namespace hom {

template <int Dim>
using Lattice = std::array<int, Dim>;

}  // namespace hom
