#pragma once
/// @file gmsh_peer_report.hpp
/// How the harnesses report a run of Gmsh's high-order optimizer
/// (src/meshing/gmsh_peer.hpp) beside hom's, so that bench_untangle and
/// bench_curve label, print and store it alike: its label, its status line
/// and its JSON entry, which carries hom's statistics of Gmsh's result (the
/// same quality call as hom's own rows) when it finished.

#include <cstdio>
#include <string>

#include "gmsh_peer.hpp"
#include "hom/io/report.hpp"
#include "hom/quality/statistics.hpp"

namespace hom::bench {

/// "gmsh 4.8.4 (Mesh.HighOrderOptimize = 1)".
inline std::string gmsh_peer_label(const meshing::PeerResult& r) {
  return "gmsh " + (r.version.empty() ? std::string("?") : r.version) + " (Mesh.HighOrderOptimize = " +
         std::to_string(r.mode) + ")";
}

/// One line after the peer's run, indented by `indent`: its time, its
/// result's min scaled Jacobian and Gmsh's note when it finished; how it
/// ended (timeout, crash, failure) otherwise.
inline void print_gmsh_peer_status(const meshing::PeerResult& r, double time_limit_s, double min_scaled_jacobian,
                                   const char* indent = "  ") {
  const char* sep = r.note.empty() ? "" : "; gmsh: ";
  if (r.finished)
    std::printf("%s%s: %.2f s, min scaled Jacobian %.3f%s%s\n", indent, gmsh_peer_label(r).c_str(), r.time_s,
                min_scaled_jacobian, sep, r.note.c_str());
  else if (r.status == "timeout")
    std::printf("%sgmsh timeout after %.0f s (%.0f s of processor time; %s)\n", indent, time_limit_s, r.cpu_s,
                gmsh_peer_label(r).c_str());
  else
    std::printf("%sgmsh %s after %.2f s (%s)%s%s\n", indent, r.status.c_str(), r.time_s, gmsh_peer_label(r).c_str(),
                sep, r.note.c_str());
}

/// The peer's JSON entry: tool, version, mode, status, time and its limit,
/// processor time, peak memory, Gmsh's note and, when it finished, hom's
/// statistics of its result (#inverted, q min / max / mean / std, min scaled
/// Jacobian; null otherwise).
inline io::Json gmsh_peer_json(const meshing::PeerResult& r, double time_limit_s, const Statistics& quality,
                               const Statistics& scaled_jacobian) {
  using io::Json;
  const auto when_finished = [&](auto value) { return r.finished ? Json(value) : Json(); };
  Json j = Json::object();
  j.set("tool", r.tool)
      .set("version", r.version)
      .set("mode", r.mode)
      .set("status", r.status)
      .set("time_s", r.time_s)
      .set("time_limit_s", time_limit_s)
      .set("inverted", when_finished(quality.inverted))
      .set("min_q", when_finished(quality.min))
      .set("max_q", when_finished(quality.max))
      .set("mean_q", when_finished(quality.mean))
      .set("std_q", when_finished(quality.std_dev))
      .set("min_scaled_jacobian", when_finished(scaled_jacobian.min))
      .set("cpu_s", r.cpu_s)
      .set("peak_rss_mb", r.peak_rss_mb)
      .set("note", r.note.empty() ? Json() : Json(r.note));
  return j;
}

}  // namespace hom::bench
