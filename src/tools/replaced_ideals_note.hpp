#pragma once
/// @file replaced_ideals_note.hpp
/// The line `hom quality` and `hom optimize` print when some elements are
/// measured against the equilateral element instead of their straight-sided
/// counterpart (straight_sided_or_regular in hom/quality/ideal.hpp): one
/// wording for both commands, true whether the vertices were tangled by hand
/// or slid on the CAD surface during curving.

#include <cstdio>

namespace hom::tools {

/// Prints the note when count > 0; prints nothing otherwise.
inline void print_replaced_ideals_note(int count) {
  if (count <= 0) return;
  std::printf("(%d elements measured against the equilateral element: their straight-sided counterparts are "
              "inverted or flat)\n",
              count);
}

}  // namespace hom::tools
