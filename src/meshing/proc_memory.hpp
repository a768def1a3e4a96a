// The peak resident memory (VmHWM) of a running process, from Linux's
// /proc/PID/status. The Gmsh peer needs it because posix_spawn starts the
// child in the parent's address space (vfork), so the child's ru_maxrss from
// wait4 counts the parent's resident memory at spawn time as well; VmHWM
// belongs to the address space the child gets at exec, i.e. to Gmsh alone.
#pragma once

#include <fstream>
#include <string>

namespace hom::meshing {

/// VmHWM of `status_path` ("/proc/self/status", "/proc/PID/status") in
/// kilobytes, or -1 when the file or the line is missing (not Linux, the
/// process has exited).
inline long proc_peak_rss_kb(const std::string& status_path) {
  std::ifstream in(status_path);
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmHWM:", 0) == 0) {
      try {
        return std::stol(line.substr(6));  // "VmHWM:   123456 kB"
      } catch (...) {
        return -1;
      }
    }
  return -1;
}

}  // namespace hom::meshing
