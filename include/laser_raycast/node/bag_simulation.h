// simulate_bag's engine: the node's sensors cast offline over a recorded bag. The configuration is
// the node's private parameters in a YAML file, read and checked by the node's own parser; the
// transforms come from the bag's /tf and /tf_static (and the sensors' pose topics from theirs),
// into a tf2 buffer read in bag time order; the scans are stamped on their rate's grid, queued,
// waited for and cast as the node's cast thread does (job_caster.h), with the bag's time as the
// clock, and written to the output bag on the topics the node would publish on, each at its stamp,
// beside a copy of the input's TF. No roscore, no parameter server.
#pragma once

#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace laser_raycast {

// How far the reading is, for a progress report.
struct BagProgress {
  double done = 0;          // s of bag time read, from its first TF message
  double total = 0;         // s from its first TF message to its last
  std::uint64_t scans = 0;  // written so far, every sensor
};

struct BagSimulationOptions {
  std::string input;     // the bag read: its /tf, /tf_static and the sensors' pose topics
  std::string output;    // the bag written (replaced if it exists)
  std::string config;    // a YAML file of the node's private parameters
  std::string ns = "/";  // the node's namespace, which its topics are resolved in
  int threads = -1;      // threads per cast (0: every core); -1: the configuration's ~threads
  // Log every parameter's value and each model loaded (rosconsole INFO); otherwise only warnings.
  bool verbose = false;
  // Called after every message read (it may be empty).
  std::function<void(const BagProgress&)> progress;
};

// What one sensor did.
struct SimulatedSensor {
  std::string name;
  std::string topic;  // its scans' topic in the output (resolved); labels: topic + "_labels"
  std::uint64_t written = 0;  // scans written
  // Not cast before its first scan: not every transform it needs covered their times yet (the
  // bag's first moments).
  std::uint64_t before_transforms = 0;
  // Not cast later: no sensor pose (TF, or a stale or bad pose topic message).
  std::uint64_t no_pose = 0;
  // Dropped from the full queue while waiting for late TF (the node's "cast thread behind").
  std::uint64_t dropped = 0;
  std::uint64_t missing_links = 0;  // link transforms left out of scans written
  // Queued when the bag ended but never cast: TF never covered their last beam.
  std::uint64_t uncovered_at_end = 0;
  std::string last_problem;  // why the last scan not cast was skipped ("" if none was)
};

struct BagSimulationResult {
  std::vector<SimulatedSensor> sensors;
  double bag_seconds = 0;   // from the first TF message to the last
  double wall_seconds = 0;  // from loading the models to closing the output
  std::uint64_t tf_messages = 0;
};

// A simulation that cannot run, or produced no scan; the message names the file, the parameter or
// the frames at fault.
class BagSimulationError : public std::runtime_error {
 public:
  enum class Kind {
    kConfig,  // the YAML file, a parameter, or an option
    kScene,   // a URDF or a mesh of the models
    kInput,   // the input bag: unreadable, without TF, without the frames or pose topic needed
    kOutput,  // the output bag cannot be written
  };
  BagSimulationError(Kind kind, const std::string& message)
      : std::runtime_error(message), kind_(kind) {}
  Kind kind() const { return kind_; }

 private:
  Kind kind_;
};

// Runs the simulation. Throws BagSimulationError (the output is removed if it was begun), also when
// not a single scan could be cast.
BagSimulationResult simulateBag(const BagSimulationOptions& options);

}  // namespace laser_raycast
