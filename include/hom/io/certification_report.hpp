#pragma once
/// @file certification_report.hpp
/// How the tools (`hom optimize --certify`, `hom curve --certify`,
/// `hom boundary-layer`) and the harnesses tell the outcome of the certify
/// stage (optimize/certified.hpp): a few lines of text and the JSON keys of
/// `hom quality --certify` plus the stage's own (DESIGN.md).

#include <cmath>
#include <cstdio>
#include <string>

#include "hom/io/json.hpp"
#include "hom/optimize/certified.hpp"

namespace hom::io {

/// Writes the outcome to `out` (the tools' standard output by default): the
/// counts after optimization, the repair rounds, the final counts and, when
/// some element is not certified valid, the first ten of them and why the
/// repair stopped.
inline void print_certification(const CertificationOutcome& c, int max_depth, std::FILE* out = stdout) {
  std::fprintf(out, "certified (Bernstein bounds of det D phi_P, subdivision depth <= %d%s):\n", max_depth,
               c.on_surface ? ", each surface element against its nodes' interpolated surface normals" : "");
  std::fprintf(out, "  after optimization: %d certified valid, %d certified invalid, %d undecided\n", c.initial_valid,
               c.initial_invalid, c.initial_undecided);
  if (c.rounds > 0) {
    int iterations = 0;
    for (const auto& r : c.repairs) iterations += r.iterations;
    std::fprintf(out, "  repair: %d round%s (%d iterations, %d sentinel points), stopped on %s, %.3f s%s\n", c.rounds,
                 c.rounds == 1 ? "" : "s", iterations, c.sentinel_points, std::string(to_string(c.reason)).c_str(),
                 c.time_s, c.restored ? "; no fewer uncertified elements, so the optimized mesh is kept" : "");
  }
  std::fprintf(out, "  final: %d certified valid, %d certified invalid, %d undecided", c.valid, c.invalid, c.undecided);
  if (!c.on_surface) std::fprintf(out, "; certified min scaled Jacobian >= %.4f", c.min_scaled_jacobian);
  std::fprintf(out, "\n");
  if (!c.certified()) {
    std::fprintf(out, "  NOT CERTIFIED: elements");
    for (std::size_t k = 0; k < c.uncertified.size() && k < 10; ++k) std::fprintf(out, " %d", c.uncertified[k]);
    std::fprintf(out, "%s (%s)\n", c.uncertified.size() > 10 ? " ..." : "", std::string(to_string(c.reason)).c_str());
  }
}

/// Adds the certificate's keys to a report case. A surface mesh's bound is of
/// g = (x_xi x x_eta) . n, not of its scaled Jacobian, so it has no
/// certified_min_scaled_jacobian.
inline void add_certification(Json& c, const CertificationOutcome& o, int max_depth) {
  c.set("certified_valid", o.valid).set("certified_invalid", o.invalid).set("undecided", o.undecided);
  if (!o.on_surface && std::isfinite(o.min_scaled_jacobian))
    c.set("certified_min_scaled_jacobian", o.min_scaled_jacobian);
  c.set("certify_max_depth", max_depth)
      .set("certify_rounds", o.rounds)
      .set("certify_stop_reason", std::string(to_string(o.reason)))
      .set("certify_restored", o.restored)
      .set("certify_time_s", o.time_s)
      .set("initial_certified_valid", o.initial_valid)
      .set("initial_certified_invalid", o.initial_invalid)
      .set("initial_undecided", o.initial_undecided);
}

}  // namespace hom::io
