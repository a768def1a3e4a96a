#pragma once
/// @file statistics.hpp
/// Mesh statistics in the thesis's table form (tables 3.2-3.4, 4.1-4.5):
/// Min, Max, Mean, Std.Dev. of a per-element value and #inv, the number of
/// invalid elements.

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace hom {

struct Statistics {
  int count = 0;
  double min = std::numeric_limits<double>::quiet_NaN();
  double max = std::numeric_limits<double>::quiet_NaN();
  double mean = std::numeric_limits<double>::quiet_NaN();
  double std_dev = std::numeric_limits<double>::quiet_NaN();  ///< population standard deviation
  int inverted = 0;
};

/// Statistics of `values`; `invalid[e]` marks the elements counted in #inv
/// (may be empty).
inline Statistics summarize(const std::vector<double>& values, const std::vector<bool>& invalid = {}) {
  Statistics s;
  s.count = static_cast<int>(values.size());
  for (bool b : invalid) s.inverted += b;
  if (values.empty()) return s;
  s.min = *std::min_element(values.begin(), values.end());
  s.max = *std::max_element(values.begin(), values.end());
  double sum = 0.0;
  for (double v : values) sum += v;
  s.mean = sum / s.count;
  double sq = 0.0;
  for (double v : values) sq += (v - s.mean) * (v - s.mean);
  s.std_dev = std::sqrt(sq / s.count);
  return s;
}

}  // namespace hom
