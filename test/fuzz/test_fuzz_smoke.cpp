// The fuzz harnesses of test/fuzz, run briefly from their seed corpora on every test run: a crash,
// a sanitizer report, a broken invariant, a leak or an input slower than -timeout fails the test,
// and the input that did it is kept (its path is in the failure message). Each run is
// deterministic: a fixed seed and a fixed number of inputs (libFuzzer with one seed mutates the
// same way every time), so a test run, CI's included, checks the inputs that the last passing run
// checked, and a new finding comes from a long run (docs/testing.md), not as a failure of an
// unrelated change. A time bound (60 s per harness with start-up) stops a slow machine early: it
// then checks a prefix of the same inputs (so a faster machine can reach an input no earlier run
// did, and find there what a long run would have: the '%n' in a URDF of 2026-11-29). Without
// clang the harnesses are not built and these tests are skipped, unless
// LASER_RAYCAST_REQUIRE_FUZZ=1 (CI, .ci/run) makes that a failure.
//
// LASER_RAYCAST_FUZZ_SEED=N picks another seed (0: a random one, libFuzzer's choice);
// LASER_RAYCAST_FUZZ_RUNS=N and LASER_RAYCAST_FUZZ_SECONDS=N set the number of inputs and the time
// bound of every harness.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <regex>
#include <string>
#include <vector>

#include "run_command.h"

namespace laser_raycast_test {
namespace {

namespace fs = std::filesystem;

const std::string kFuzzers = LASER_RAYCAST_FUZZERS;  // "" when clang was not found
const std::string kSourceDir = LASER_RAYCAST_SOURCE_DIR;
const std::string kCorpus = kSourceDir + "/test/fuzz/corpus/";

// The environment variable's value, or fallback when it is unset or empty.
long setting(const char* name, long fallback) {
  const char* env = std::getenv(name);
  return env && *env ? std::atol(env) : fallback;
}

// Whether the harnesses must have been built (CI): then their absence fails instead of skipping.
bool fuzzRequired() {
  const char* env = std::getenv("LASER_RAYCAST_REQUIRE_FUZZ");
  return env && std::string(env) == "1";
}

// The fixed seed of every smoke run (any number; changing it changes which inputs are checked).
constexpr long kSeed = 20261125;

// Runs harness on `runs` inputs from its seed corpus (new inputs go to a scratch directory, not
// into the source tree), within `duration` seconds, and fails on anything libFuzzer reports.
void smoke(const std::string& harness, long runs, int duration,
           const std::vector<std::string>& seeds) {
  runs = setting("LASER_RAYCAST_FUZZ_RUNS", runs);
  duration = static_cast<int>(setting("LASER_RAYCAST_FUZZ_SECONDS", duration));
  const long seed = setting("LASER_RAYCAST_FUZZ_SEED", kSeed);
  if (kFuzzers.empty()) {
    if (fuzzRequired()) {
      FAIL() << "the fuzz harnesses were not built (no clang++ when CMake configured the package) "
                "and LASER_RAYCAST_REQUIRE_FUZZ=1: install clang and libclang-rt-dev, then "
                "configure again";
    }
    GTEST_SKIP() << "the fuzz harnesses need clang (apt-get install clang libclang-rt-dev)";
  }
  const fs::path work = fs::temp_directory_path() /
                        ("laser_raycast_fuzz_" + harness + "_" + std::to_string(getpid()));
  fs::remove_all(work);
  fs::create_directories(work / "corpus");
  std::string command =
      kFuzzers + "/" + harness + " -seed=" + std::to_string(seed) +
      " -runs=" + std::to_string(runs) + " -max_total_time=" + std::to_string(duration) +
      " -timeout=30 -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix=" + work.string() +
      "/ " + (work / "corpus").string();
  for (const std::string& seed : seeds) command += " " + seed;
  // Leaks of libraries outside the package that the harnesses reach (lsan.supp says which).
  const CommandResult run = runCommand("LSAN_OPTIONS=suppressions=" + kSourceDir +
                                       "/test/fuzz/lsan.supp " + command + " 2>&1");
  std::smatch executed, rate;
  const bool stats =
      std::regex_search(run.output, executed,
                        std::regex("stat::number_of_executed_units: *([0-9]+)")) &&
      std::regex_search(run.output, rate, std::regex("stat::average_exec_per_sec: *([0-9]+)"));
  EXPECT_EQ(run.status, 0) << harness << " failed; the input is kept in " << work << "\n"
                           << run.output.substr(run.output.size() > 6000 ? run.output.size() - 6000
                                                                         : 0);
  ASSERT_TRUE(stats) << run.output;
  std::cout << harness << ": " << executed[1] << " of " << runs << " inputs (seed " << seed
            << ", bound " << duration << " s; " << rate[1] << " per second)\n";
  ::testing::Test::RecordProperty("executions", executed[1].str());
  ::testing::Test::RecordProperty("executions_per_second", rate[1].str());
  if (run.status == 0) fs::remove_all(work);
}

// The numbers of inputs take about 40 s each on the machines CI runs on (fuzz_core ~750 inputs a
// second, fuzz_mesh_loader ~8: each mesh is imported in a child process, fuzz_urdf_loader ~5,000).
TEST(FuzzSmoke, Core) { smoke("fuzz_core", 30000, 55, {kCorpus + "core"}); }

TEST(FuzzSmoke, MeshLoader) {
  smoke("fuzz_mesh_loader", 300, 50, {kCorpus + "mesh_loader", kSourceDir + "/test/data/meshes"});
}

TEST(FuzzSmoke, UrdfLoader) { smoke("fuzz_urdf_loader", 150000, 45, {kCorpus + "urdf_loader"}); }

}  // namespace
}  // namespace laser_raycast_test
