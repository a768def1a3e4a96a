#pragma once
/// @file certify_options.hpp
/// The certification options `hom quality`, `hom optimize`, `hom curve` and
/// `hom boundary-layer` take alike: --certify, --certify-depth (subdivision
/// levels of quality/certify.hpp) and, for the commands that repair,
/// --certify-rounds (optimize/certified.hpp). One declaration, one check,
/// one copy into the optimizer's options, so the commands cannot drift apart.

#include <string>
#include <string_view>

#include <boost/program_options.hpp>

#include "command.hpp"
#include "hom/optimize/certified.hpp"
#include "hom/quality/certify.hpp"

namespace hom::tools {

struct CertifyCli {
  bool on = false;                                  ///< --certify
  int depth = CertifyOptions{}.max_depth;           ///< --certify-depth
  int rounds = CertifyRepairOptions{}.max_rounds;   ///< --certify-rounds

  static constexpr int max_depth = 20;  ///< 2^(20 Dim) children at most: beyond it nothing more is decided

  /// Declares --certify (its help `what`: what certifying means for the
  /// command), --certify-depth and, when `repair`, --certify-rounds.
  void declare(boost::program_options::options_description& opts, const char* what, bool repair = true) {
    namespace po = boost::program_options;
    opts.add_options()("certify", po::bool_switch(&on), what)  //
        ("certify-depth", po::value(&depth)->default_value(depth), "subdivision levels before an element is undecided (0..20)");
    if (repair)
      opts.add_options()("certify-rounds", po::value(&rounds)->default_value(rounds), "repair rounds at most (0: certify only)");
  }

  /// UsageError ("COMMAND: --certify-depth must be in 0..20, got 21") for a
  /// value out of range.
  void check(std::string_view command) const {
    const std::string c(command);
    if (depth < 0 || depth > max_depth)
      throw UsageError(c + ": --certify-depth must be in 0.." + std::to_string(max_depth) + ", got " + std::to_string(depth));
    if (rounds < 0) throw UsageError(c + ": --certify-rounds must be >= 0, got " + std::to_string(rounds));
  }

  /// Copies the settings into the options of an optimizer with a certify
  /// stage (OptimizeOptions, cad::CurveOptions).
  template <class Options>
  void apply_to(Options& o) const {
    o.certify = on;
    o.certify_depth = depth;
    o.certify_rounds = rounds;
  }
};

}  // namespace hom::tools
