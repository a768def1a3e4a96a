#pragma once
/// @file plot_script.hpp
/// How the harnesses draw their figures: a Python script under Debian's
/// /usr/bin/python3 (the one that sees python3-matplotlib) reads the CSV
/// files the harness wrote and writes PNGs beside them. A missing Python,
/// module or script only skips the figures, with a message: the harnesses
/// reproduce tables, the figures are a convenience, and the CSVs are complete
/// without them.

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

namespace hom::bench {

/// A string as one argument of a /bin/sh command line.
inline std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

/// Runs `/usr/bin/python3 SCRIPT OUT_DIR ARGS...` when the interpreter, the
/// Python modules `modules` (comma-separated, as in an import statement) and
/// the script are there; otherwise says which is missing. Never fails the
/// run: a failing script is reported on stdout. Returns whether it ran and
/// succeeded.
inline bool run_plot_script(const std::filesystem::path& script, const std::filesystem::path& out_dir,
                            const std::vector<std::string>& args = {}, const std::string& modules = "matplotlib") {
  const std::string python = "/usr/bin/python3";
  if (!std::filesystem::exists(python)) {
    std::printf("plot: %s not found; skipping the PNG figures\n", python.c_str());
    return false;
  }
  if (std::system((python + " -c " + shell_quote("import " + modules) + " >/dev/null 2>&1").c_str()) != 0) {
    std::printf("plot: %s not available to %s; skipping the PNG figures\n", modules.c_str(), python.c_str());
    return false;
  }
  if (!std::filesystem::exists(script)) {
    std::printf("plot: script %s not found; skipping the PNG figures\n", script.string().c_str());
    return false;
  }
  std::string cmd = python + " " + shell_quote(script.string()) + " " + shell_quote(out_dir.string());
  for (const auto& a : args) cmd += " " + shell_quote(a);
  std::printf("plot: %s\n", cmd.c_str());
  std::fflush(stdout);
  const bool ok = std::system(cmd.c_str()) == 0;
  if (!ok) std::printf("plot: the plotting script failed (the CSV files are complete)\n");
  return ok;
}

}  // namespace hom::bench
