#pragma once
/// @file command.hpp
/// The `hom` command line: a table of subcommands that each cmd_*.cpp file
/// fills with a static RegisterCommand, so a new subcommand is one new file
/// (and one line in src/tools/meson.build):
///
///   namespace { int run(int argc, char** argv) { ... } }
///   static const hom::tools::RegisterCommand reg{{"quality", "Print element quality statistics", run}};
///
/// `run` gets the arguments after the subcommand name (argv[0] is
/// "hom NAME") and returns the exit status. It reports bad command lines by
/// throwing UsageError (hom prints "hom: <message>" and exits with 2) and
/// other failures by throwing any std::exception (exit 1).

#include <stdexcept>
#include <string_view>
#include <vector>

namespace hom::tools {

struct Command {
  std::string_view name;
  std::string_view summary;  ///< one line, for `hom --help`
  int (*run)(int argc, char** argv);
};

/// All registered subcommands (in registration order).
inline std::vector<Command>& commands() {
  static std::vector<Command> table;
  return table;
}

struct RegisterCommand {
  explicit RegisterCommand(Command c) { commands().push_back(c); }
};

/// A bad command line: wrong options, missing arguments.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace hom::tools
