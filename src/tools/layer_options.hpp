#pragma once
/// @file layer_options.hpp
/// --bl-total H of `hom boundary-layer` and `hom curve`: the layers given by
/// their total height (hom/mesh/layer_count.hpp) instead of --bl-layers.

#include <stdexcept>
#include <string>
#include <string_view>

#include <boost/program_options.hpp>

#include "command.hpp"
#include "hom/mesh/layer_count.hpp"

namespace hom::tools {

/// With --bl-total in `vm`, the number of layers of first height `first` and
/// growth `growth` that reaches `total` (--bl-layers must then be left at its
/// default); otherwise `layers`. Bad values are UsageErrors of `command`.
inline int layers_from_options(std::string_view command, const boost::program_options::variables_map& vm, double first,
                               double growth, double total, int layers) {
  if (!vm.count("bl-total")) return layers;
  if (vm.count("bl-layers") && !vm["bl-layers"].defaulted())
    throw UsageError(std::string(command) + ": give --bl-layers or --bl-total, not both");
  try {
    return layers_for_total_height(first, growth, total);
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string(command) + ": --bl-total: " + e.what());
  }
}

}  // namespace hom::tools
