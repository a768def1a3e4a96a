#pragma once
/// @file options.hpp
/// The command-line parsing every `hom` subcommand repeats: the visible
/// options (what --help prints), positional arguments kept out of the help,
/// Boost.Program_options errors turned into UsageError ("NAME: what", exit 2),
/// and --help answered:
///
///   po::options_description opts("hom quality MESH [options]\n\n...");
///   opts.add_options()("help,h", "show this help")("vtu", po::value(&vtu), "...");
///   po::variables_map vm;
///   if (!hom::tools::parse_options("quality", argc, argv, opts, {{"mesh", po::value(&path)}}, vm))
///     return 0;  // --help was printed
///
/// Each positional argument takes one word, in the order given.

#include <initializer_list>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <boost/program_options.hpp>

#include "command.hpp"

namespace hom::tools {

/// A positional argument: its name and where its value goes (owned by the
/// parser once passed, as with po::options_description::add_options).
struct Positional {
  const char* name;
  boost::program_options::value_semantic* value;
};

/// Parses argv into `vm`. Returns false when the user asked for --help (the
/// visible options have then been printed to stdout); throws UsageError for
/// anything Boost rejects.
inline bool parse_options(std::string_view command, int argc, char** argv,
                          const boost::program_options::options_description& visible,
                          std::initializer_list<Positional> positional, boost::program_options::variables_map& vm) {
  namespace po = boost::program_options;
  po::options_description hidden;
  po::positional_options_description pos;
  for (const auto& p : positional) {
    hidden.add_options()(p.name, p.value);
    pos.add(p.name, 1);
  }
  po::options_description all;
  all.add(visible).add(hidden);
  try {
    po::store(po::command_line_parser(argc, argv).options(all).positional(pos).run(), vm);
    if (vm.count("help")) {
      std::cout << visible << "\n";
      return false;
    }
    po::notify(vm);
  } catch (const po::error& e) {
    throw UsageError(std::string(command) + ": " + e.what());
  }
  return true;
}

/// A comma-separated list of numbers ("0.5,1,2"); UsageError
/// ("COMMAND: OPTION: 'x' is not a number") for anything else.
inline std::vector<double> parse_number_list(std::string_view command, std::string_view option, const std::string& s) {
  std::vector<double> v;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) {
    try {
      std::size_t used = 0;
      v.push_back(std::stod(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw UsageError(std::string(command) + ": " + std::string(option) + ": '" + item + "' is not a number");
    }
  }
  return v;
}

/// A comma-separated list of at least one integer tag ("3,7").
inline std::vector<int> parse_tag_list(std::string_view command, std::string_view option, const std::string& s) {
  std::vector<int> tags;
  for (double x : parse_number_list(command, option, s)) {
    if (x != double(int(x)))
      throw UsageError(std::string(command) + ": " + std::string(option) + " takes integer tags");
    tags.push_back(int(x));
  }
  if (tags.empty()) throw UsageError(std::string(command) + ": " + std::string(option) + " needs at least one tag");
  return tags;
}

}  // namespace hom::tools
