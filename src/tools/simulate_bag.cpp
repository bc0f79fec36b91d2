// simulate_bag: the node's sensors cast offline over a recorded bag's TF, the scans written to a
// new bag as the node would publish them. Needs no roscore. The engine is the node layer's
// (laser_raycast/node/bag_simulation.h); this is its command line, progress bar and summary. See
// synopsis(), flags() and the README's "Re-simulating a recorded bag".
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>

#include "command_line.h"
#include "laser_raycast/node/bag_simulation.h"

namespace {

using laser_raycast::BagSimulationError;
using laser_raycast::tools::ArgError;
using laser_raycast::tools::single;
namespace po = boost::program_options;

using laser_raycast::tools::kExitBadArguments;  // also a bad configuration file or parameter
constexpr int kExitBadScene = 3;
constexpr int kExitBadInput = 4;
constexpr int kExitBadOutput = 5;

// The bar is redrawn at most this often (wall time): often enough to look alive, rarely enough
// to cost nothing against a scan's cast.
constexpr double kProgressPeriod = 0.1;  // s
constexpr int kBarWidth = 24;            // characters

struct Args {
  laser_raycast::BagSimulationOptions options;
  bool no_progress = false;
};

po::options_description flags(Args* args) {
  laser_raycast::BagSimulationOptions& o = args->options;
  po::options_description options("Options");
  auto add = options.add_options();
  add("input", single("IN.bag", [&o](const std::string& v) { o.input = v; }),
      "the recorded bag: its /tf and /tf_static (and the sensors' pose topics, if configured)");
  add("output", single("OUT.bag", [&o](const std::string& v) { o.output = v; }),
      "the bag written (replaced if it exists): the scans, clouds and labels on the node's "
      "topics at their stamps, and the input's /tf and /tf_static");
  add("config", single("CONFIG.yaml", [&o](const std::string& v) { o.config = v; }),
      "the node's private parameters (models as {file: PATH}, paths or package:// URIs)");
  add("threads",
      single("N",
             [&o](const std::string& v) {
               o.threads = laser_raycast::tools::parseThreads("--threads", v);
             }),
      "threads each cast uses (default: the configuration's ~threads, 1 unless set; 0: every "
      "core); the output is the same for any number");
  add("namespace", single("NS", [&o](const std::string& v) { o.ns = v; }),
      "the node's namespace, which its topics are resolved in (default /)");
  add("no-progress", po::bool_switch(&args->no_progress),
      "no progress bar (there is one on stderr only when it is a terminal)");
  add("verbose", po::bool_switch(&o.verbose), "log every parameter's value and each model loaded");
  add("help,h", "print this help");
  return options;
}

std::string synopsis() {
  return "usage: simulate_bag --input IN.bag --output OUT.bag --config CONFIG.yaml\n"
         "                    [--threads N] [--namespace NS] [--no-progress] [--verbose]\n";
}

std::string notes() {
  return "Casts every sensor of CONFIG.yaml (the node's parameters) at its rate over the bag's\n"
         "transforms, as laser_raycast_node would with the bag played: scans stamped on the\n"
         "rate's grid from the first time the transforms cover to the last. No roscore needed.\n"
         "Exit status: 0 ok, 2 bad arguments or configuration, 3 bad scene input (a URDF or a\n"
         "mesh), 4 bad input bag (unreadable, no TF, frames or pose topic missing, no scan\n"
         "cast), 5 output not writable.\n";
}

// Throws ArgError.
Args parseArgs(int argc, char** argv, bool* help) {
  Args args;
  po::variables_map values;
  *help = !laser_raycast::tools::parseCommandLine(argc, argv, flags(&args), &values);
  if (*help) return args;
  for (const char* required : {"input", "output", "config"}) {
    if (!values.count(required)) throw ArgError(std::string("give --") + required);
  }
  return args;
}

// "1:05" or "0:07": minutes and seconds.
std::string clock(double seconds) {
  const long s = std::lround(std::max(0.0, seconds));
  char text[32];
  std::snprintf(text, sizeof text, "%ld:%02ld", s / 60, s % 60);
  return text;
}

// The bar on stderr, redrawn in place: bag time read of the total, the speed against real time,
// scans a second and the time left at that speed, all from the first message read on (loading the
// models is not counted).
class ProgressBar {
 public:
  void update(const laser_raycast::BagProgress& p, bool last = false) {
    const auto now = std::chrono::steady_clock::now();
    if (!started_) {
      started_ = true;
      start_ = now;
    }
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    if (!last && elapsed - drawn_ < kProgressPeriod) return;
    drawn_ = elapsed;
    // A pose topic's messages may come before the first transform: done is then negative.
    const double share = p.total > 0 ? std::clamp(p.done / p.total, 0.0, 1.0) : 1.0;
    const int filled = static_cast<int>(share * kBarWidth);
    const double speed = elapsed > 0 ? p.done / elapsed : 0;
    std::ostringstream line;
    line << "\r[" << std::string(filled, '#') << std::string(kBarWidth - filled, '.') << "] ";
    char text[160];
    std::snprintf(text, sizeof text, "%.1f / %.1f s of bag, %.1fx real time, %.0f scans/s, %s left",
                  p.done, p.total, speed, elapsed > 0 ? p.scans / elapsed : 0.0,
                  speed > 0 ? clock((p.total - p.done) / speed).c_str() : "?");
    line << text << "\x1b[K" << (last ? "\n" : "");
    std::cerr << line.str() << std::flush;
  }

 private:
  bool started_ = false;
  std::chrono::steady_clock::time_point start_;
  double drawn_ = -kProgressPeriod;
};

void printSummary(const laser_raycast::BagSimulationResult& result) {
  char text[256];
  std::snprintf(text, sizeof text,
                "simulate_bag: %.1f s of bag (%lu TF messages) in %.1f s: %.1fx real time\n",
                result.bag_seconds, static_cast<unsigned long>(result.tf_messages),
                result.wall_seconds,
                result.wall_seconds > 0 ? result.bag_seconds / result.wall_seconds : 0.0);
  std::cerr << text;
  for (const laser_raycast::SimulatedSensor& s : result.sensors) {
    std::cerr << "  sensor '" << s.name << "': " << s.written << " scans on " << s.topic
              << " (labels on " << s.topic << "_labels)";
    if (s.before_transforms > 0) {
      std::cerr << ", " << s.before_transforms << " before the transforms covered them";
    }
    if (s.no_pose > 0) std::cerr << ", " << s.no_pose << " skipped without a pose";
    if (s.dropped > 0) std::cerr << ", " << s.dropped << " dropped waiting for TF";
    if (s.missing_links > 0) std::cerr << ", " << s.missing_links << " links left out";
    if (s.uncovered_at_end > 0) {
      std::cerr << ", " << s.uncovered_at_end << " at the end not covered by TF";
    }
    std::cerr << "\n";
    if (s.written == 0 && !s.last_problem.empty()) {
      std::cerr << "    no scan: " << s.last_problem << "\n";
    }
  }
}

int exitStatus(BagSimulationError::Kind kind) {
  switch (kind) {
    case BagSimulationError::Kind::kConfig:
      return kExitBadArguments;
    case BagSimulationError::Kind::kScene:
      return kExitBadScene;
    case BagSimulationError::Kind::kInput:
      return kExitBadInput;
    case BagSimulationError::Kind::kOutput:
      return kExitBadOutput;
  }
  return kExitBadArguments;
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  const auto exit_now = laser_raycast::tools::readCommandLine("simulate_bag", synopsis(), notes(),
                                                              parseArgs, flags, argc, argv, &args);
  if (exit_now) return *exit_now;
  ProgressBar bar;
  laser_raycast::BagProgress last;
  const bool show = !args.no_progress && isatty(STDERR_FILENO);
  if (show) {
    args.options.progress = [&](const laser_raycast::BagProgress& p) {
      last = p;
      bar.update(p);
    };
  }
  try {
    const laser_raycast::BagSimulationResult result = laser_raycast::simulateBag(args.options);
    if (show) bar.update(last, true);
    printSummary(result);
  } catch (const BagSimulationError& e) {
    if (show) std::cerr << "\n";
    std::cerr << "simulate_bag: " << e.what() << "\n";
    return exitStatus(e.kind());
  }
  return 0;
}
