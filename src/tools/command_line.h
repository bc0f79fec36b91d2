// The tools' command lines, through boost::program_options: one grammar and one error type for
// cast_scan and bench.
#pragma once

#include <boost/program_options.hpp>
#include <functional>
#include <stdexcept>
#include <string>

namespace laser_raycast {
namespace tools {

// A bad command line; the message names the flag and the problem.
class ArgError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Reads argv against options: --name VALUE or --name=VALUE, a multi-value option takes the words
// up to the next flag, a flag may not be abbreviated, and a word that is no flag's value is an
// error. Returns false, without running the notifiers, if --help (or -h) is given; otherwise
// stores the values in *values and runs the notifiers. Throws ArgError.
bool parseCommandLine(int argc, char** argv,
                      const boost::program_options::options_description& options,
                      boost::program_options::variables_map* values);

// A flag with one value, which store converts and keeps (and may refuse with an ArgError).
boost::program_options::typed_value<std::string>* single(
    const char* value_name, std::function<void(const std::string&)> store);

// A finite number. Throws ArgError naming the flag and the text.
double parseNumber(const std::string& flag, const std::string& text);

// A thread count as core::CastConfig::threads takes it (0: every core). Throws ArgError naming
// the flag and the text.
int parseThreads(const std::string& flag, const std::string& text);

}  // namespace tools
}  // namespace laser_raycast
