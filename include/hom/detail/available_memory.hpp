#pragma once
/// @file available_memory.hpp
/// The memory the system can still give this process (Linux's MemAvailable in
/// /proc/meminfo), so that a solver can refuse a problem that would not fit
/// instead of driving the machine into swap or the out-of-memory killer.

#include <fstream>
#include <string>

namespace hom::detail {

/// MemAvailable in bytes, or a negative value where it is unknown (not Linux).
inline double available_memory_bytes() {
  std::ifstream in("/proc/meminfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("MemAvailable:", 0) == 0) {
      try {
        return 1024.0 * std::stod(line.substr(13));  // "MemAvailable:   123456 kB"
      } catch (...) {
        return -1.0;
      }
    }
  return -1.0;
}

}  // namespace hom::detail
