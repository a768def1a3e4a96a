#pragma once
/// @file family.hpp
/// The ElementFamily concept: what hom needs to know about a reference element.
///
/// Models: Simplex<2> (triangle), Simplex<3> (tetrahedron), Cube<2>
/// (quadrilateral), Cube<3> (hexahedron).
///
/// Required:
///   - `dim`, `num_vertices`, `is_simplex`, `name`, `Point` (Eigen column of size dim);
///   - `num_nodes(p)`: n_p of appendix A;
///   - `reference_volume()`;
///   - `edges()` (ordered vertex pairs) and, in 3D, `faces()` (outward-oriented vertex tuples);
///   - `vertex(i)`, `vertex_lattice(i, p)`, `in_lattice(l, p)`;
///   - `vertex_weights(l, p)`: integer weights of the vertices at lattice node l;
///     two elements sharing a node give it the same (vertex, weight) pairs, which
///     is how meshes identify shared high-order nodes;
///   - `equispaced_point(l, p)`.

#include <concepts>

#include "hom/element/cube.hpp"
#include "hom/element/lattice.hpp"
#include "hom/element/simplex.hpp"

namespace hom {

template <class F>
concept ElementFamily = requires(int p, int i, const Lattice<F::dim>& l) {
  { F::dim } -> std::convertible_to<int>;
  { F::num_vertices } -> std::convertible_to<int>;
  { F::is_simplex } -> std::convertible_to<bool>;
  { F::num_nodes(p) } -> std::same_as<int>;
  { F::reference_volume() } -> std::same_as<double>;
  F::edges();
  { F::vertex(i) } -> std::same_as<typename F::Point>;
  { F::vertex_lattice(i, p) } -> std::same_as<Lattice<F::dim>>;
  { F::in_lattice(l, p) } -> std::same_as<bool>;
  F::vertex_weights(l, p);
  { F::equispaced_point(l, p) } -> std::same_as<typename F::Point>;
};

static_assert(ElementFamily<Simplex<2>>);
static_assert(ElementFamily<Simplex<3>>);
static_assert(ElementFamily<Cube<2>>);
static_assert(ElementFamily<Cube<3>>);

}  // namespace hom
