#pragma once
/// @file equispaced.hpp
/// Equispaced nodes: lattice index l sits at Family::equispaced_point(l, p)
/// (l / p on simplices, -1 + 2 l / p on cubes). Simple and exactly nested on
/// sub-entities, but the Lebesgue constant grows exponentially with p; use it
/// for low degrees, for file formats that store equispaced nodes, and as the
/// baseline the quasi-optimal sets are compared with (hom_reference_report).

#include <string_view>
#include <vector>

#include "hom/element/family.hpp"
#include "hom/element/node_layout.hpp"
#include "hom/nodes/node_set.hpp"

namespace hom {

struct Equispaced {
  static constexpr std::string_view name = "equispaced";

  template <ElementFamily F>
  static constexpr bool supports = true;

  template <ElementFamily F>
  static std::vector<typename F::Point> points(int p) {
    return node_layout<F>(p).equispaced_points();
  }
};

static_assert(NodeSet<Equispaced>);

}  // namespace hom
