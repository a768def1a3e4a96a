#pragma once
/// @file report.hpp
/// The machine-readable report of DESIGN.md: every `hom` command and harness
/// that prints statistics writes, with `--json FILE`, one object
///   {"tool": ..., "version": ..., "cases": [ ... ]}
/// with one case per mesh and stage. This header builds the common keys of a
/// case from a Statistics row and writes the report atomically.

#include <sstream>
#include <string>
#include <vector>

#include "hom/io/error.hpp"
#include "hom/io/json.hpp"
#include "hom/quality/statistics.hpp"

namespace hom::io {

/// The keys every quality case carries.
struct CaseHeader {
  std::string name;
  std::string family;
  int p = 1;
  int elements = 0;
  int nodes = 0;
  std::string stage;    ///< "linear", "initial", "optimized", ...
  std::string measure;  ///< "shape" or "oddy"
  std::string ideal;    ///< "straight-sided" or "equilateral"
};

inline Json quality_case(const CaseHeader& h, const Statistics& quality, const Statistics& scaled_jacobian) {
  Json c = Json::object();
  c.set("name", h.name)
      .set("family", h.family)
      .set("p", h.p)
      .set("elements", h.elements)
      .set("nodes", h.nodes)
      .set("stage", h.stage)
      .set("measure", h.measure)
      .set("ideal", h.ideal)
      .set("min_q", quality.min)
      .set("max_q", quality.max)
      .set("mean_q", quality.mean)
      .set("std_q", quality.std_dev)
      .set("inverted", quality.inverted)
      .set("min_scaled_jacobian", scaled_jacobian.min)
      .set("mean_scaled_jacobian", scaled_jacobian.mean);
  return c;
}

/// One checked claim of the thesis (harnesses): the text and whether it held.
struct Check {
  std::string claim;
  bool holds = false;
};

/// The report's "checks": [{"claim", "holds"}, ...].
inline Json checks_json(const std::vector<Check>& checks) {
  Json::Array list;
  for (const auto& c : checks) {
    Json j = Json::object();
    j.set("claim", c.claim).set("holds", c.holds);
    list.push_back(std::move(j));
  }
  return Json(std::move(list));
}

/// Writes {"tool", "version", "cases"[, "checks"]} to `path` (FILE.tmp, then
/// renamed). `checks`, when given, lists the harness's claim checks as
/// {"claim", "holds"} objects beside the cases (they are not meshes).
inline void write_report(const std::string& path, const std::string& tool, const std::string& version,
                         std::vector<Json> cases, const std::vector<Check>& checks = {}) {
  Json report = Json::object();
  report.set("tool", tool).set("version", version).set("cases", Json(Json::Array(std::move(cases))));
  if (!checks.empty()) report.set("checks", checks_json(checks));
  std::ostringstream os;
  report.write(os);
  os << "\n";
  const std::string text = os.str();
  write_atomically(path, [&](std::FILE* f) { write_all(f, path, text.data(), text.size()); });
}

}  // namespace hom::io
