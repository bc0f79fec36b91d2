#include "command_line.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include "laser_raycast/core/caster.h"

namespace laser_raycast {
namespace tools {

namespace po = boost::program_options;

bool parseCommandLine(int argc, char** argv, const po::options_description& options,
                      po::variables_map* values) {
  // program_options would otherwise accept any unambiguous prefix of a flag.
  const int style = po::command_line_style::default_style & ~po::command_line_style::allow_guessing;
  std::vector<std::string> unknown;
  try {
    // Unregistered flags and stray words are collected rather than rejected, so that --help works
    // beside them and the message names the word as given.
    const po::parsed_options parsed = po::command_line_parser(argc, argv)
                                          .options(options)
                                          .style(style)
                                          .allow_unregistered()
                                          .run();
    unknown = po::collect_unrecognized(parsed.options, po::include_positional);
    po::store(parsed, *values);
  } catch (const po::error& e) {
    throw ArgError(e.what());
  }
  if (values->count("help")) return false;
  if (!unknown.empty()) throw ArgError("unknown argument '" + unknown.front() + "'");
  try {
    po::notify(*values);
  } catch (const po::error& e) {
    throw ArgError(e.what());
  }
  return true;
}

std::optional<int> readCommandLine(const ToolText& text, const std::function<bool()>& parse) {
  try {
    if (parse()) return std::nullopt;
  } catch (const ArgError& e) {
    std::cerr << text.name << ": " << e.what() << "\n" << text.synopsis << text.notes;
    return kExitBadArguments;
  }
  std::cout << text.synopsis << "\n" << text.flags() << "\n" << text.notes;
  return 0;
}

po::typed_value<std::string>* single(const char* value_name,
                                     std::function<void(const std::string&)> store) {
  return po::value<std::string>()->value_name(value_name)->notifier(std::move(store));
}

double parseNumber(const std::string& flag, const std::string& text) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(value)) {
    throw ArgError(flag + ": '" + text + "' is not a finite number");
  }
  return value;
}

int parseThreads(const std::string& flag, const std::string& text) {
  char* end = nullptr;
  const long value = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0') throw ArgError(flag + ": '" + text + "' is not an integer");
  core::CastConfig config;  // its validate() holds the bounds
  config.threads = static_cast<int>(std::clamp<long>(value, -1, 1L << 20));
  try {
    config.validate();
  } catch (const std::invalid_argument& e) {
    throw ArgError(flag + ": '" + text + "': " + e.what());
  }
  return config.threads;
}

}  // namespace tools
}  // namespace laser_raycast
