#pragma once
/// @file node_set.hpp
/// The NodeSet concept: where the nodes of a degree-p reference element sit.
///
/// hom identifies nodes by lattice index (element/node_layout.hpp); a node set
/// maps every lattice index to reference coordinates. The geometric map of an
/// element is one polynomial (eq A.1) whatever the node set, but its nodal
/// values, the conditioning of its Vandermonde matrix and its Lebesgue
/// constant depend on it (the thesis uses a quasi-optimal set, appendix A).
///
/// Required of a model N:
///   - `static constexpr std::string_view name`;
///   - `template <ElementFamily F> static constexpr bool supports`: whether N
///     defines nodes on family F;
///   - `template <ElementFamily F> static std::vector<typename F::Point> points(int p)`:
///     the reference coordinates of every node in hom's NodeLayout order,
///     i.e. points[i] belongs to node_layout<F>(p).lattice(i). Calling it for
///     an unsupported family is a compile-time error with a message.
///
/// Models:
///   - Equispaced   (nodes/equispaced.hpp):    all families; Family::equispaced_point.
///   - WarpBlend    (nodes/warp_blend.hpp):    Warburton's warp & blend nodes on
///                  simplices (optimised alpha), tensor Gauss-Lobatto on cubes.
///   - GaussLobatto (nodes/gauss_lobatto.hpp): cubes only, tensor Gauss-Lobatto-Legendre.
///
/// Contract every model meets (test/test_nodes.cpp): n_p distinct nodes, all in
/// the closed element; vertices at the vertices; a node of an edge or face
/// lies on it; an edge's nodes depend only on the edge (so two elements
/// sharing an edge agree on its nodes), mirror-symmetric to round-off.

#include <concepts>
#include <string_view>
#include <vector>

#include "hom/element/family.hpp"

namespace hom {

template <class N>
concept NodeSet = requires(int p) {
  { N::name } -> std::convertible_to<std::string_view>;
  { N::template supports<Simplex<2>> } -> std::convertible_to<bool>;
  { N::template supports<Cube<3>> } -> std::convertible_to<bool>;
  // Checks the declaration only: the body (and its static_assert for
  // unsupported families) is instantiated when a family is actually used.
  { N::template points<Simplex<2>>(p) } -> std::same_as<std::vector<Simplex<2>::Point>>;
  { N::template points<Cube<3>>(p) } -> std::same_as<std::vector<Cube<3>::Point>>;
};

/// N defines nodes on family F.
template <class N, class F>
concept NodeSetFor = NodeSet<N> && ElementFamily<F> && N::template supports<F>;

}  // namespace hom
