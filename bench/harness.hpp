#pragma once
/// @file harness.hpp
/// What the thesis-reproduction harnesses in bench/ share: timing and memory
/// probes, table formatting, the seeded random perturbation that tangles a
/// mesh, and the interpolation of per-degree calibration tables.

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <iterator>
#include <limits>
#include <map>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Dense>

#if defined(_OPENMP)
#include <omp.h>
#endif

#include "hom/io/report.hpp"
#include "hom/mesh/mesh.hpp"

namespace hom::bench {

/// Peak resident memory of this process so far, in MB.
inline double peak_rss_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / 1024.0;  // Linux: kilobytes
}

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// Applies a harness's --threads (0 keeps OpenMP's default) and returns the
/// number of threads the run will use.
inline int set_threads(int requested) {
#if defined(_OPENMP)
  if (requested > 0) omp_set_num_threads(requested);
  return omp_get_max_threads();
#else
  (void)requested;
  return 1;
#endif
}

/// A table cell: fixed precision, "-" for a missing (non-finite) value.
inline std::string fmt(double v, int prec = 2) {
  if (!std::isfinite(v)) return "-";
  char b[32];
  std::snprintf(b, sizeof b, "%.*f", prec, v);
  return b;
}

/// A calibrated per-degree value (e.g. a perturbation amplitude) at degree p:
/// the table's value at p, interpolated geometrically between calibrated
/// degrees, the nearest value outside them.
inline double interpolate_geometric(const std::map<int, double>& table, int p) {
  auto hi = table.lower_bound(p);
  if (hi == table.end()) return std::prev(hi)->second;
  if (hi->first == p || hi == table.begin()) return hi->second;
  auto lo = std::prev(hi);
  const double t = double(p - lo->first) / double(hi->first - lo->first);
  return std::exp((1 - t) * std::log(lo->second) + t * std::log(hi->second));
}

/// One row of a thesis statistics table (Min, Max, Mean, Std, #inverted).
struct ThesisRow {
  double min, max, mean, std_dev;
  int inverted;
};

/// A thesis row as JSON: quality rows with the report's keys (min_q, ...),
/// scaled-Jacobian rows with plain ones (min, max, mean, std).
inline io::Json thesis_row_json(const ThesisRow& r, bool quality = true) {
  io::Json j = io::Json::object();
  j.set(quality ? "min_q" : "min", r.min)
      .set(quality ? "max_q" : "max", r.max)
      .set(quality ? "mean_q" : "mean", r.mean)
      .set(quality ? "std_q" : "std", r.std_dev)
      .set("inverted", r.inverted);
  return j;
}

/// The entry of a per-degree thesis table (an array of structs with a
/// member p) for degree p, or nullptr when the thesis has none.
template <class Entry, std::size_t N>
const Entry* thesis_entry(const Entry (&table)[N], int p) {
  for (const Entry& e : table)
    if (e.p == p) return &e;
  return nullptr;
}

/// Deterministic across platforms: mt19937_64 is fully specified and the
/// double is built from its top 53 bits (std::uniform_real_distribution is
/// not specified bit for bit).
class Random {
 public:
  explicit Random(std::uint64_t seed) : engine_(seed) {}
  double uniform() { return double(engine_() >> 11) * 0x1.0p-53; }  // [0, 1)
  /// Uniform in the unit ball of R^Dim (rejection sampling).
  template <int Dim = 3>
  Eigen::Matrix<double, Dim, 1> in_unit_ball() {
    for (;;) {
      Eigen::Matrix<double, Dim, 1> v;
      // Last coordinate drawn first: the order GCC gave the calibrations
      // (the amplitudes were calibrated with the draws as constructor
      // arguments, whose evaluation order C++ leaves unspecified).
      for (int d = Dim - 1; d >= 0; --d) v[d] = 2 * uniform() - 1;
      if (v.squaredNorm() <= 1.0) return v;
    }
  }

 private:
  std::mt19937_64 engine_;
};

/// The "tangling" of the harnesses: every free node moves by a random vector,
/// uniform in the ball of radius amplitude * h_i, with h_i the shortest
/// straight-sided edge of the elements that contain node i (the node spacing
/// of a degree-p element is about h / p, so higher degrees tangle with smaller
/// amplitudes). Returns the number of nodes moved.
template <class MeshT>
int perturb_free_nodes(MeshT& mesh, double amplitude, std::uint64_t seed) {
  using Family = typename MeshT::family;
  const int n = mesh.num_nodes();
  std::vector<double> h(n, std::numeric_limits<double>::infinity());
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const auto v = mesh.ideal_vertices(e);
    double shortest = std::numeric_limits<double>::infinity();
    for (const auto& edge : Family::edges()) shortest = std::min(shortest, (v.col(edge[0]) - v.col(edge[1])).norm());
    for (int i = 0; i < mesh.nodes_per_element(); ++i) {
      double& hi = h[mesh.elements()(i, e)];
      hi = std::min(hi, shortest);
    }
  }
  Random rng(seed);
  int moved = 0;
  for (int i = 0; i < n; ++i) {
    if (mesh.node_class(i).kind != NodeKind::free) continue;
    mesh.node(i) += amplitude * h[i] * rng.template in_unit_ball<Family::dim>();
    ++moved;
  }
  return moved;
}

/// The integers of a comma-separated option value ("2,5,10"), each in
/// [lo, hi]; `option` names the option in the error ("--p").
inline std::vector<int> parse_int_list(const std::string& text, const std::string& option, int lo, int hi) {
  std::vector<int> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    std::size_t used = 0;
    int v = 0;
    try {
      v = std::stoi(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size()) throw std::invalid_argument(option + ": '" + item + "' is not an integer");
    if (v < lo || v > hi)
      throw std::invalid_argument(option + ": " + item + " is out of range " + std::to_string(lo) + ".." +
                                  std::to_string(hi));
    out.push_back(v);
  }
  if (out.empty()) throw std::invalid_argument(option + ": no value given");
  return out;
}

/// --peer-mode's value: Gmsh's Mesh.HighOrderOptimize modes (1 to 4), each
/// named once ("2,3,4": one peer run per mode).
inline std::vector<int> parse_peer_modes(const std::string& text) {
  const auto modes = parse_int_list(text, "--peer-mode", 1, 4);
  for (std::size_t i = 0; i < modes.size(); ++i)
    if (std::count(modes.begin(), modes.begin() + i, modes[i]))
      throw std::invalid_argument("--peer-mode: mode " + std::to_string(modes[i]) + " is named twice in '" + text +
                                  "'");
  return modes;
}

/// The thesis's claims a harness checks: each one is recorded (for the
/// report's "checks", io::write_report) and a failed one is announced on
/// stderr at once; the harness's exit status is non-zero when any failed.
class Checks {
 public:
  explicit Checks(std::string tool) : tool_(std::move(tool)) {}
  void expect(bool holds, const std::string& claim) {
    all_.push_back({claim, holds});
    if (!holds) {
      failures_.push_back(claim);
      std::cerr << tool_ << ": CHECK FAILED: " << claim << '\n';
    }
  }
  int count() const { return int(all_.size()); }
  const std::vector<std::string>& failures() const { return failures_; }
  const std::vector<io::Check>& all() const { return all_; }

 private:
  std::string tool_;
  std::vector<io::Check> all_;
  std::vector<std::string> failures_;
};

}  // namespace hom::bench
