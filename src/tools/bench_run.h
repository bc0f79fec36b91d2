// One workload on one scene: the rays, the long double references, every row's distances, errors
// and agreement with Embree's robust mode, and its timing. The rows whose speed ratio matters (the
// pipeline and Embree) are timed in alternating rounds, so that a slow spell of a busy machine
// slows each of them alike.
#pragma once

#include <chrono>
#include <optional>
#include <vector>

#include "bench_methods.h"
#include "bench_report.h"
#include "bench_scenes.h"

namespace laser_raycast {
namespace bench {

// How much work a run does. Every number here only trades run time for noise.
struct Settings {
  int reps;                  // timed batches per row (per round); the median is reported
  double min_batch_seconds;  // a batch repeats its pass until it lasts this long
  double brute_tests;        // triangle tests a brute-force row may do per pass ...
  int brute_min_rays;        // ... but at least this many rays
  int rounds;                // paired rows: alternating rounds, the median round is reported
};

// The methods of one scene: the rows asked for, and Embree's robust mode (a row or not), which
// every row is compared with beam by beam (none without Embree).
struct SceneMethods {
  std::vector<Method> rows;
  std::optional<Method> robust;
};

// Appends one row per method (in order) for the workload from `poses` sensor poses; logs each to
// stderr.
void runWorkload(const Settings& settings, int poses, const BenchScene& scene,
                 const SceneGeometry& geometry, const SceneMethods& methods,
                 const Workload& workload, std::vector<Row>* rows);

// The memory per triangle of the scene's distinct meshes, ours and Embree's (one Embree build per
// mesh: call it outside any timing); nullopt if the scene has no meshes.
std::optional<MemoryRow> measureMemory(const BenchScene& scene);

double secondsSince(std::chrono::steady_clock::time_point start);

}  // namespace bench
}  // namespace laser_raycast
