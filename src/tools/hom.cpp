// The `hom` command line: dispatches `hom NAME ARGS...` to the subcommand
// NAME registered by one of the cmd_*.cpp files (command.hpp).
//
// Exit status: 0 success, 1 failure (bad input file, I/O error), 2 bad
// command line. Errors are one line on stderr: "hom: <message>".

#include <algorithm>
#include <cstring>
#include <exception>
#include <iostream>
#include <string>
#include <vector>

#include "command.hpp"

namespace {

void print_help(std::ostream& out) {
  auto cmds = hom::tools::commands();
  std::sort(cmds.begin(), cmds.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
  out << "usage: hom <command> [options]\n\n"
         "Validate, convert, smooth and generate curved high-order meshes.\n\ncommands:\n";
  std::size_t width = 0;
  for (const auto& c : cmds) width = std::max(width, c.name.size());
  for (const auto& c : cmds) out << "  " << c.name << std::string(width + 2 - c.name.size(), ' ') << c.summary << "\n";
  out << "\n'hom <command> --help' describes a command's options.\n";
}

int dispatch(int argc, char** argv) {
  if (argc < 2) {
    print_help(std::cerr);
    return 2;
  }
  const std::string name = argv[1];
  if (name == "--help" || name == "-h" || name == "help") {
    if (name == "help" && argc > 2) {
      std::string help = "--help";
      std::vector<char*> args{argv[0], argv[2], help.data()};
      return dispatch(3, args.data());
    }
    print_help(std::cout);
    return 0;
  }
  if (name == "--version") {
    std::cout << "hom " << HOM_VERSION << "\n";
    return 0;
  }
  const auto& cmds = hom::tools::commands();
  const auto it = std::find_if(cmds.begin(), cmds.end(), [&](const auto& c) { return c.name == name; });
  if (it == cmds.end()) {
    std::cerr << "hom: unknown command '" << name << "' (see 'hom --help')\n";
    return 2;
  }
  std::string argv0 = "hom " + name;
  std::vector<char*> args{argv0.data()};
  for (int i = 2; i < argc; ++i) args.push_back(argv[i]);
  try {
    return it->run(static_cast<int>(args.size()), args.data());
  } catch (const hom::tools::UsageError& e) {
    std::cerr << "hom: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "hom: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace

int main(int argc, char** argv) { return dispatch(argc, argv); }
