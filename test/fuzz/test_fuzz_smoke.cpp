// The fuzz harnesses of test/fuzz, run briefly from their seed corpora on every test run: a crash,
// a sanitizer report, a broken invariant, a leak or an input slower than -timeout fails the test,
// and the input that did it is kept (its path is in the failure message). Each harness runs for
// LASER_RAYCAST_FUZZ_SECONDS (default below: each harness, start-up and the corpus included, within
// 60 s of wall-clock time, 3 minutes in all); docs/testing.md has the long run. Without clang the
// harnesses are not built and these tests are skipped.
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

int seconds(int fallback) {
  const char* env = std::getenv("LASER_RAYCAST_FUZZ_SECONDS");
  return env && *env ? std::atoi(env) : fallback;
}

// Runs harness for `duration` seconds from its seed corpus (new inputs go to a scratch directory,
// not into the source tree) and fails on anything libFuzzer reports.
void smoke(const std::string& harness, int duration, const std::vector<std::string>& seeds) {
  if (kFuzzers.empty()) GTEST_SKIP() << "the fuzz harnesses need clang (apt-get install clang)";
  const fs::path work = fs::temp_directory_path() /
                        ("laser_raycast_fuzz_" + harness + "_" + std::to_string(getpid()));
  fs::remove_all(work);
  fs::create_directories(work / "corpus");
  std::string command =
      kFuzzers + "/" + harness + " -max_total_time=" + std::to_string(duration) +
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
  std::cout << harness << ": " << executed[1] << " inputs in " << duration << " s (" << rate[1]
            << " per second)\n";
  ::testing::Test::RecordProperty("executions", executed[1].str());
  ::testing::Test::RecordProperty("executions_per_second", rate[1].str());
  if (run.status == 0) fs::remove_all(work);
}

TEST(FuzzSmoke, Core) { smoke("fuzz_core", seconds(55), {kCorpus + "core"}); }

TEST(FuzzSmoke, MeshLoader) {
  smoke("fuzz_mesh_loader", seconds(50),
        {kCorpus + "mesh_loader", kSourceDir + "/test/data/meshes"});
}

TEST(FuzzSmoke, UrdfLoader) { smoke("fuzz_urdf_loader", seconds(45), {kCorpus + "urdf_loader"}); }

}  // namespace
}  // namespace laser_raycast_test
