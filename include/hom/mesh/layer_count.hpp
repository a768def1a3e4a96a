#pragma once
/// @file layer_count.hpp
/// Boundary layers given by their total height instead of their number
/// (issue 9, layer parameters: first height, growth ratio, and the number of
/// layers or the total height): the number of levels that reach a height,
/// as a mesher's layer-thickness control does.

#include <cmath>
#include <stdexcept>
#include <string>

namespace hom {

/// The fewest levels L whose heights h0, h0 g, ..., h0 g^(L-1) add up to at
/// least `total_height` (to a relative 1e-12, so that a total made of whole
/// levels gives exactly their number). The last level may overshoot: the
/// layer's top is then at h0 (g^L - 1) / (g - 1) (h0 L for g = 1).
/// Throws std::invalid_argument for h0 or the total not positive and finite,
/// g < 1, or more than `max_layers` levels.
inline int layers_for_total_height(double first_height, double growth, double total_height, int max_layers = 1000) {
  const auto bad = [](const std::string& what) {
    return std::invalid_argument("hom::layers_for_total_height: " + what);
  };
  if (!(first_height > 0.0) || !std::isfinite(first_height))
    throw bad("the first height must be positive and finite, got " + std::to_string(first_height));
  if (!(growth >= 1.0) || !std::isfinite(growth)) throw bad("the growth must be >= 1, got " + std::to_string(growth));
  if (!(total_height > 0.0) || !std::isfinite(total_height))
    throw bad("the total height must be positive and finite, got " + std::to_string(total_height));
  const double reach = total_height * (1.0 - 1e-12);
  double top = 0.0, level = first_height;
  for (int layers = 1; layers <= max_layers; ++layers) {
    top += level;
    if (top >= reach) return layers;
    level *= growth;
  }
  throw bad("more than " + std::to_string(max_layers) + " layers of first height " + std::to_string(first_height) +
            " and growth " + std::to_string(growth) + " are needed to reach " + std::to_string(total_height));
}

}  // namespace hom
