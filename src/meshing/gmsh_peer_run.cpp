// gmsh_peer_run: the child process of hom::meshing::gmsh_high_order_optimize
// (gmsh_peer.hpp), where Gmsh's high-order optimizer runs, so that the
// caller survives a crash and can kill a run that exceeds its time limit.
//
//   gmsh_peer_run --in IN.msh --out OUT.msh --info INFO.txt --mode 1..4
//                 [--threads N] [--threshold-min X] [--threshold-max X]
//                 [--layers N] [--pass-max N] [--iter-max N]
//
// IN is hom's MSH 4.1 of the mesh (io/msh.hpp), in which a node on a volume
// entity is free and every other node fixed. The model is built through
// Gmsh's API, not by opening the file: one discrete volume per volume entity
// of the file, holding its free nodes and its elements (node order and tags
// as in the file), and one discrete point holding every fixed node (Gmsh 4.8
// lets nodes on curves and surfaces slide; only nodes on points stay).
// Boundary triangles are left out: with Mesh.HighOrderDistCAD off the
// optimizer does not use them. OUT is IN with Gmsh's node coordinates. INFO
// gets "version V" once Gmsh is up, then "optimize_s T", "peak_rss_kb K" (this
// process's VmHWM), "note MESSAGE" (the last error Gmsh reported, if any) and
// "done", or "error MESSAGE".
// Exit status: 0 done, 2 bad arguments, 3 error.

#include <sys/prctl.h>

#include <gmsh.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "hom/io/msh_reader.hpp"
#include "hom/io/msh_writer.hpp"
#include "proc_memory.hpp"

namespace {

struct Args {
  std::string in, out, info;
  int mode = 1, threads = 1, layers = 6, pass_max = 25, iter_max = 100;
  double threshold_min = 0.1, threshold_max = 2.0;
};

Args parse(int argc, char** argv) {
  Args a;
  std::map<std::string, std::string> kv;
  for (int i = 1; i < argc; i += 2) {
    const std::string k = argv[i];
    if (k.rfind("--", 0) != 0 || i + 1 >= argc) throw std::invalid_argument("expected --key value pairs, got '" + k + "'");
    kv[k.substr(2)] = argv[i + 1];
  }
  auto take = [&](const char* k, auto& v) {
    auto it = kv.find(k);
    if (it == kv.end()) return;
    if constexpr (std::is_same_v<std::decay_t<decltype(v)>, std::string>)
      v = it->second;
    else if constexpr (std::is_same_v<std::decay_t<decltype(v)>, int>)
      v = std::stoi(it->second);
    else
      v = std::stod(it->second);
    kv.erase(it);
  };
  take("in", a.in);
  take("out", a.out);
  take("info", a.info);
  take("mode", a.mode);
  take("threads", a.threads);
  take("threshold-min", a.threshold_min);
  take("threshold-max", a.threshold_max);
  take("layers", a.layers);
  take("pass-max", a.pass_max);
  take("iter-max", a.iter_max);
  if (!kv.empty()) throw std::invalid_argument("unknown option --" + kv.begin()->first);
  if (a.in.empty() || a.out.empty() || a.info.empty()) throw std::invalid_argument("--in, --out and --info are required");
  if (a.mode < 1 || a.mode > 4) throw std::invalid_argument("--mode must be 1, 2, 3 or 4");
  return a;
}

// Appends a line to the info file at once (the parent reads it after a kill).
void info_line(const std::string& path, const std::string& line) {
  if (std::FILE* f = std::fopen(path.c_str(), "a")) {
    std::fputs((line + "\n").c_str(), f);
    std::fclose(f);
  }
}

std::string last_gmsh_error() {
  std::string last;
  try {
    gmsh::logger::getLastError(last);
  } catch (...) {
  }
  for (char& c : last)
    if (c == '\n') c = ' ';
  return last;
}

void build_model(const hom::io::MshData& d) {
  constexpr int fixed_point = 1;
  gmsh::model::add("hom_gmsh_peer");
  std::map<int, std::pair<std::vector<std::size_t>, std::vector<double>>> volume_nodes;
  std::pair<std::vector<std::size_t>, std::vector<double>> point_nodes;
  for (const auto& n : d.nodes) {
    const bool free = n.entity && n.entity->dim == 3;
    auto& [tags, xyz] = free ? volume_nodes[n.entity->tag] : point_nodes;
    tags.push_back(static_cast<std::size_t>(n.tag));
    xyz.insert(xyz.end(), n.x.begin(), n.x.end());
  }
  // Elements of the volumes, by (entity, type), in the file's node order.
  std::map<std::pair<int, int>, std::pair<std::vector<std::size_t>, std::vector<std::size_t>>> blocks;
  for (const auto& e : d.elements) {
    if (e.entity.dim != 3) continue;
    auto& [tags, nodes] = blocks[{e.entity.tag, e.type}];
    tags.push_back(static_cast<std::size_t>(e.tag));
    for (auto t : d.nodes_of(e)) nodes.push_back(static_cast<std::size_t>(t));
    volume_nodes[e.entity.tag];  // a volume without free nodes still exists
  }
  if (blocks.empty()) throw std::runtime_error("the input holds no volume elements");
  if (!point_nodes.first.empty()) {
    gmsh::model::addDiscreteEntity(0, fixed_point);
    gmsh::model::mesh::addNodes(0, fixed_point, point_nodes.first, point_nodes.second);
  }
  for (const auto& [tag, nodes] : volume_nodes) {
    gmsh::model::addDiscreteEntity(3, tag);
    if (!nodes.first.empty()) gmsh::model::mesh::addNodes(3, tag, nodes.first, nodes.second);
  }
  for (const auto& [key, block] : blocks)
    gmsh::model::mesh::addElementsByType(key.first, key.second, block.first, block.second);
}

int run(const Args& a) {
  const hom::io::MshData in = hom::io::read_msh_data(a.in);
  gmsh::initialize(0, nullptr, false);
  gmsh::option::setNumber("General.Terminal", 1);
  gmsh::option::setNumber("General.NumThreads", a.threads);
  std::string version;
  gmsh::option::getString("General.Version", version);
  info_line(a.info, "version " + version);

  build_model(in);
  // Keep the node tags: OptimizeMesh renumbers nodes and elements afterwards
  // unless told not to, and the result is matched to the input by tag.
  gmsh::option::setNumber("Mesh.Renumber", 0);
  gmsh::option::setNumber("Mesh.HighOrderOptimize", a.mode);
  gmsh::option::setNumber("Mesh.HighOrderThresholdMin", a.threshold_min);
  gmsh::option::setNumber("Mesh.HighOrderThresholdMax", a.threshold_max);
  gmsh::option::setNumber("Mesh.HighOrderNumLayers", a.layers);
  gmsh::option::setNumber("Mesh.HighOrderPassMax", a.pass_max);
  gmsh::option::setNumber("Mesh.HighOrderIterMax", a.iter_max);

  // What Gmsh's mesh generator runs for each Mesh.HighOrderOptimize value.
  std::vector<std::string> methods;
  if (a.mode == 2 || a.mode == 3) methods.push_back("HighOrderElastic");
  if (a.mode == 1 || a.mode == 2) methods.push_back("HighOrder");
  if (a.mode == 4) methods.push_back("HighOrderFastCurving");
  const auto t0 = std::chrono::steady_clock::now();
  std::string note;
  for (const auto& m : methods) {
    try {
      gmsh::model::mesh::optimize(m, true);
    } catch (...) {
      // Gmsh leaves the mesh as far as it got (a partially failed
      // optimization still improves it); the note says what it reported.
      note = m + ": " + last_gmsh_error();
    }
  }
  const double optimize_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (note.empty()) {
    const std::string last = last_gmsh_error();
    if (!last.empty()) note = last;
  }

  std::vector<std::size_t> tags;
  std::vector<double> xyz, params;
  gmsh::model::mesh::getNodes(tags, xyz, params, -1, -1, false, false);
  std::map<std::size_t, std::size_t> where;
  for (std::size_t i = 0; i < tags.size(); ++i) where[tags[i]] = i;
  hom::io::MshData out = in;
  for (auto& n : out.nodes) {
    const auto it = where.find(static_cast<std::size_t>(n.tag));
    if (it == where.end()) throw std::runtime_error("gmsh lost node " + std::to_string(n.tag));
    for (int k = 0; k < 3; ++k) n.x[k] = xyz[3 * it->second + k];
  }
  if (tags.size() != in.nodes.size())
    throw std::runtime_error("gmsh holds " + std::to_string(tags.size()) + " nodes, the input " + std::to_string(in.nodes.size()));
  hom::io::write_msh_data(a.out, out, {hom::io::MshFormat::Version::v41, true});
  gmsh::finalize();

  info_line(a.info, "optimize_s " + std::to_string(optimize_s));
  if (const long kb = hom::meshing::proc_peak_rss_kb("/proc/self/status"); kb >= 0)
    info_line(a.info, "peak_rss_kb " + std::to_string(kb));
  if (!note.empty()) info_line(a.info, "note " + note);
  info_line(a.info, "done");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // Die with the parent (it may be killed while Gmsh runs for an hour).
  prctl(PR_SET_PDEATHSIG, SIGKILL);
  Args a;
  try {
    a = parse(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "gmsh_peer_run: %s\n", e.what());
    return 2;
  }
  try {
    return run(a);
  } catch (const std::exception& e) {
    std::string msg = e.what();
    if (const std::string g = last_gmsh_error(); !g.empty() && msg.find(g) == std::string::npos) msg += " (gmsh: " + g + ")";
    std::fprintf(stderr, "gmsh_peer_run: %s\n", msg.c_str());
    info_line(a.info, "error " + msg);
    return 3;
  } catch (...) {
    const std::string msg = "gmsh: " + last_gmsh_error();
    std::fprintf(stderr, "gmsh_peer_run: %s\n", msg.c_str());
    info_line(a.info, "error " + msg);
    return 3;
  }
}
