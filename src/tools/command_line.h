// The tools' command lines, through boost::program_options: one grammar and one error type for
// cast_scan and bench.
#pragma once

#include <boost/program_options.hpp>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>

namespace laser_raycast {
namespace tools {

// A bad command line; the message names the flag and the problem.
class ArgError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Every tool's exit status for a bad command line.
constexpr int kExitBadArguments = 2;

// What a tool says about its command line: its name (messages start with it), its usage lines,
// its flags (for --help) and the notes after them.
struct ToolText {
  std::string name;
  std::string synopsis;
  std::function<boost::program_options::options_description()> flags;
  std::string notes;
};

// Calls parse, which reads the command line (throwing ArgError for a bad one) and returns false
// for --help. Returns what main should exit with now: kExitBadArguments after a bad command line
// (the message, the usage and the notes on stderr), 0 after --help (the usage, the flags and the
// notes on stdout); nullopt to go on.
std::optional<int> readCommandLine(const ToolText& text, const std::function<bool()>& parse);

// The same for a tool whose parse(argc, argv, &help) gives its Args (help: --help was given) and
// whose flags(&args) describes the flags that store into args.
template <class Args>
std::optional<int> readCommandLine(const std::string& name, const std::string& synopsis,
                                   const std::string& notes, Args (*parse)(int, char**, bool*),
                                   boost::program_options::options_description (*flags)(Args*),
                                   int argc, char** argv, Args* args) {
  const auto help_flags = [flags] {
    Args unused;
    return flags(&unused);
  };
  return readCommandLine(ToolText{name, synopsis, help_flags, notes}, [&] {
    bool help = false;
    *args = parse(argc, argv, &help);
    return !help;
  });
}

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
