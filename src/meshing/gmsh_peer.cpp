// Gmsh's high-order optimizer as a peer, the parent's side: writes the
// input, runs the helper `gmsh_peer_run` (gmsh_peer_run.cpp) under a
// wall-clock limit, reads the result back (see gmsh_peer.hpp). This file does
// not call Gmsh: everything Gmsh does happens in the child.

#include "gmsh_peer.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include "hom/io/msh.hpp"
#include "hom/nodes/equispaced.hpp"
#include "proc_memory.hpp"

extern char** environ;

#ifndef HOM_GMSH_PEER_RUN
#define HOM_GMSH_PEER_RUN ""
#endif

namespace hom::meshing {

namespace {

namespace fs = std::filesystem;
using Tet = Simplex<3>;
using TetMesh = Mesh<Tet>;
using Clock = std::chrono::steady_clock;

double seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

// MSH data of the mesh in which the entity of a node says whether it moves:
// free nodes on a volume (dimension 3), every other node on an entity of
// lower dimension. A non-free node the mesh gives no such entity (a boundary
// node of unknown geometry) goes on a point entity of its own tag, a free
// node with a lower-dimensional entity on its element's volume.
io::MshData peer_input(const TetMesh& m) {
  io::MshData d = io::to_msh_data(m);
  int extra_point = 0;
  for (const auto& en : m.entities())
    if (en.id.dim == 0) extra_point = std::max(extra_point, en.id.tag);
  for (const auto& c : m.node_classes())
    if (c.entity && c.entity->dim == 0) extra_point = std::max(extra_point, c.entity->tag);
  ++extra_point;
  std::vector<int> volume_of(m.num_nodes(), 1);
  for (int e = m.num_elements() - 1; e >= 0; --e)
    for (int i = 0; i < m.nodes_per_element(); ++i) volume_of[m.elements()(i, e)] = m.element_entities()[e];
  for (int n = 0; n < m.num_nodes(); ++n) {
    auto& node = d.nodes[n];  // to_msh_data: node n has tag n + 1
    const bool free = m.node_class(n).kind == NodeKind::free;
    const bool on_volume = node.entity && node.entity->dim == 3;
    if (free && !on_volume) {
      node.entity = EntityId{3, volume_of[n]};
      node.num_params = 0;
    } else if (!free && on_volume) {
      node.entity = EntityId{0, extra_point};
      node.num_params = 0;
    }
  }
  return d;
}

std::string helper_path(const GmshPeerOptions& o) {
  if (!o.helper.empty()) return o.helper;
  if (const char* env = std::getenv("HOM_GMSH_PEER_RUN"); env && *env) return env;
  return HOM_GMSH_PEER_RUN;
}

std::string signal_name(int sig) {
  const char* s = sigdescr_np(sig);
  const char* abbrev = sigabbrev_np(sig);
  std::string out = "signal " + std::to_string(sig);
  if (abbrev) out += std::string(", SIG") + abbrev;
  if (s) out += std::string(", ") + s;
  return out;
}

// "key value" lines of the child's info file.
std::map<std::string, std::string> read_info(const fs::path& path) {
  std::map<std::string, std::string> info;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    const auto sp = line.find(' ');
    info[line.substr(0, sp)] = sp == std::string::npos ? "" : line.substr(sp + 1);
  }
  return info;
}

// Last non-empty line of the log, for a status that says why.
std::string log_tail(const fs::path& path) {
  std::ifstream in(path);
  std::string line, last;
  while (std::getline(in, line))
    if (line.find_first_not_of(" \t\r") != std::string::npos) last = line;
  return last;
}

class ScratchDir {
 public:
  ScratchDir(const GmshPeerOptions& o) : keep_(o.keep_files || !o.work_dir.empty()) {
    if (!o.work_dir.empty()) {
      path_ = o.work_dir;
      fs::create_directories(path_);
      return;
    }
    std::string templ = (fs::temp_directory_path() / "hom_gmsh_peer_XXXXXX").string();
    if (!mkdtemp(templ.data())) throw std::runtime_error("gmsh peer: cannot create a scratch directory: " + std::string(std::strerror(errno)));
    path_ = templ;
  }
  ~ScratchDir() {
    if (keep_) return;
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
  bool keep_;
};

std::string format_number(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

// Node positions at the mesh's node set from positions at the equispaced
// nodes (tag n + 1 -> node n): each element's map is evaluated at the node
// set's reference points (DESIGN.md: converting node sets evaluates the map).
TetMesh::Coordinates from_equispaced(const TetMesh& m, const TetMesh::Coordinates& x) {
  const int p = m.degree();
  const Eigen::MatrixXd B = lagrange_basis<Tet, Equispaced>(p).values(WarpBlend::points<Tet>(p)).transpose();
  TetMesh::Coordinates y = x;
  std::vector<char> done(m.num_nodes(), 0);
  TetMesh::Coordinates xe(3, m.nodes_per_element());
  for (int e = 0; e < m.num_elements(); ++e) {
    for (int i = 0; i < m.nodes_per_element(); ++i) xe.col(i) = x.col(m.elements()(i, e));
    const TetMesh::Coordinates ye = xe * B;
    for (int i = Tet::num_vertices; i < m.nodes_per_element(); ++i) {
      const int n = m.elements()(i, e);
      if (!done[n]) {
        y.col(n) = ye.col(i);
        done[n] = 1;
      }
    }
  }
  return y;
}

}  // namespace

PeerResult gmsh_high_order_optimize(const TetMesh& perturbed, const GmshPeerOptions& o) {
  static_assert(std::is_same_v<TetMesh, Mesh<Tet, WarpBlend>>, "from_equispaced converts to warp & blend nodes");
  if (o.mode < 1 || o.mode > 4)
    throw std::invalid_argument("gmsh peer: Mesh.HighOrderOptimize mode must be 1, 2, 3 or 4, got " + std::to_string(o.mode));
  if (!(o.time_limit_s > 0)) throw std::invalid_argument("gmsh peer: the time limit must be positive");
  if (!(o.threshold_min < o.threshold_max)) throw std::invalid_argument("gmsh peer: need threshold_min < threshold_max");
  if (o.num_layers < 0 || o.pass_max < 1 || o.iter_max < 1 || o.threads < 0)
    throw std::invalid_argument("gmsh peer: layers >= 0, passes >= 1, iterations >= 1 and threads >= 0 required");

  PeerResult r;
  r.mode = o.mode;
  auto fail = [&](const std::string& why) {
    r.finished = false;
    r.status = "failed: " + why;
    return r;
  };
  const std::string helper = helper_path(o);
  if (helper.empty() || access(helper.c_str(), X_OK) != 0)
    return fail("helper '" + helper + "' is not an executable (build the target gmsh_peer_run, or set HOM_GMSH_PEER_RUN)");

  try {
    const ScratchDir dir(o);
    const fs::path in = dir.path() / "in.msh", out = dir.path() / "out.msh", info_path = dir.path() / "info.txt",
                   log = dir.path() / "log.txt";
    fs::remove(out);
    fs::remove(info_path);
    io::write_msh_data(in.string(), peer_input(perturbed), {io::MshFormat::Version::v41, true});

    std::vector<std::string> args = {helper,
                                     "--in", in.string(),
                                     "--out", out.string(),
                                     "--info", info_path.string(),
                                     "--mode", std::to_string(o.mode),
                                     "--threads", std::to_string(o.threads),
                                     "--threshold-min", format_number(o.threshold_min),
                                     "--threshold-max", format_number(o.threshold_max),
                                     "--layers", std::to_string(o.num_layers),
                                     "--pass-max", std::to_string(o.pass_max),
                                     "--iter-max", std::to_string(o.iter_max)};
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);

    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    if (!o.verbose) {
      posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      posix_spawn_file_actions_adddup2(&actions, 1, 2);
    }
    pid_t pid = 0;
    const auto t0 = Clock::now();
    const int rc = posix_spawn(&pid, helper.c_str(), &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (rc != 0) return fail("cannot start '" + helper + "': " + std::strerror(rc));

    // Wait, polling (the child may take an hour; the poll interval grows to
    // 0.2 s so that short runs return promptly).
    const auto deadline = t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(o.time_limit_s));
    int wstatus = 0;
    rusage usage{};
    bool timed_out = false;
    auto nap = std::chrono::milliseconds(5);
    // The child's own peak memory, polled (a killed child writes no info
    // file); not ru_maxrss, which counts the parent's memory (proc_memory.hpp).
    const std::string child_status = "/proc/" + std::to_string(pid) + "/status";
    long peak_kb = 0;
    for (;;) {
      peak_kb = std::max(peak_kb, proc_peak_rss_kb(child_status));
      const pid_t w = wait4(pid, &wstatus, WNOHANG, &usage);
      if (w == pid) break;
      if (w < 0 && errno != EINTR) return fail(std::string("waitpid: ") + std::strerror(errno));
      if (Clock::now() >= deadline) {
        kill(pid, SIGKILL);
        while (wait4(pid, &wstatus, 0, &usage) < 0 && errno == EINTR) {
        }
        timed_out = true;
        break;
      }
      std::this_thread::sleep_for(std::min<Clock::duration>(nap, deadline - Clock::now()));
      nap = std::min(nap * 2, std::chrono::milliseconds(200));
    }
    r.wall_s = seconds(t0, Clock::now());
    r.time_s = r.wall_s;
    r.cpu_s = double(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) + 1e-6 * double(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);

    const auto info = read_info(info_path);
    if (auto it = info.find("version"); it != info.end()) r.version = it->second;
    if (auto it = info.find("note"); it != info.end()) r.note = it->second;
    if (auto it = info.find("peak_rss_kb"); it != info.end()) peak_kb = std::max(peak_kb, std::stol(it->second));
    r.peak_rss_mb = double(peak_kb) / 1024.0;
    if (timed_out) {
      r.status = "timeout";
      if (const auto last = log_tail(log); !last.empty()) r.note = "last message: " + last;  // how far Gmsh got
      return r;
    }
    if (WIFSIGNALED(wstatus)) {
      r.status = "crashed (" + signal_name(WTERMSIG(wstatus)) + ")";
      if (const auto last = log_tail(log); !last.empty()) r.note = r.note.empty() ? last : r.note + "; " + last;
      return r;
    }
    if (!WIFEXITED(wstatus) || WEXITSTATUS(wstatus) != 0 || !info.count("done")) {
      std::string why = info.count("error") ? info.at("error") : log_tail(log);
      return fail("gmsh_peer_run exited with status " + std::to_string(WEXITSTATUS(wstatus)) + (why.empty() ? "" : ": " + why));
    }
    if (auto it = info.find("optimize_s"); it != info.end()) r.time_s = std::stod(it->second);

    // The result: positions by node tag; everything else is the input's.
    const io::MshData d = io::read_msh_data(out.string());
    if (d.nodes.size() != std::size_t(perturbed.num_nodes()))
      return fail("gmsh returned " + std::to_string(d.nodes.size()) + " nodes, the input has " +
                  std::to_string(perturbed.num_nodes()));
    TetMesh::Coordinates x(3, perturbed.num_nodes());
    std::vector<char> seen(perturbed.num_nodes(), 0);
    for (const auto& node : d.nodes) {
      const auto n = node.tag - 1;
      if (n < 0 || n >= perturbed.num_nodes() || seen[n]) return fail("gmsh returned an unknown or repeated node tag " + std::to_string(node.tag));
      seen[n] = 1;
      for (int a = 0; a < 3; ++a) x(a, n) = node.x[a];
    }
    r.mesh = perturbed;
    r.mesh.nodes() = from_equispaced(perturbed, x);
    for (int n = 0; n < perturbed.num_nodes(); ++n)
      if (!r.mesh.node(n).allFinite()) return fail("gmsh returned a non-finite coordinate (node " + std::to_string(n + 1) + ")");

    // Fixed nodes stay (round-off of the node-set conversion aside).
    const Eigen::Vector3d lo = perturbed.nodes().rowwise().minCoeff(), hi = perturbed.nodes().rowwise().maxCoeff();
    const double tolerance = 1e-9 * std::max((hi - lo).norm(), 1e-300);
    for (int n = 0; n < perturbed.num_nodes(); ++n)
      if (perturbed.node_class(n).kind != NodeKind::free)
        r.max_fixed_displacement = std::max(r.max_fixed_displacement, (r.mesh.node(n) - perturbed.node(n)).norm());
    if (!(r.max_fixed_displacement <= tolerance)) {
      r.mesh = TetMesh();
      return fail("gmsh moved fixed nodes (by up to " + format_number(r.max_fixed_displacement) + ")");
    }
    r.finished = true;
    r.status = "ok";
    return r;
  } catch (const std::exception& e) {
    return fail(e.what());
  }
}

}  // namespace hom::meshing
