// The benchmark tool run as a user would: `bench --quick --out DIR`. Checks the outputs' format
// (a stable interface), that every method has a row for every still workload and scene that ran
// and the pipeline and Embree for every moving one (with a finite speed ratio), that
// the production rows (watertight_bvh, pipeline) neither leak nor hit what is not there, that the
// agreement columns compare beam for beam (embree_robust agrees with itself on every beam), and
// that --method keeps only the rows asked for. Never timings: the machine may be busy. The quick
// run takes about 6 minutes on an idle core; catkin ignores a gtest TIMEOUT, so the command
// itself is bounded by timeout(1) at 15 minutes.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "run_command.h"

namespace laser_raycast_test {
namespace {

const std::string kBench = BENCH_PATH;
const char* const kHeader =
    "workload,scene,method,threads,triangles,rays,ns_per_ray,mrays_per_s,max_abs_err_m,p99_abs_err_"
    "m,"
    "max_ulp,leaks,false_hits,agree_robust,disagree_robust";
constexpr std::size_t kFields = 15;

std::vector<std::string> splitLines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty()) lines.push_back(line);
  }
  return lines;
}

std::vector<std::string> splitFields(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream s(line);
  std::string field;
  while (std::getline(s, field, ',')) fields.push_back(field);
  if (!line.empty() && line.back() == ',') fields.push_back("");
  return fields;
}

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The whole field must be a finite number.
bool parseDouble(const std::string& text, double* value) {
  char* end = nullptr;
  *value = std::strtod(text.c_str(), &end);
  return !text.empty() && *end == '\0' && std::isfinite(*value);
}

// The whole field must be a non-negative integer.
bool parseCount(const std::string& text, long* value) {
  if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos) return false;
  *value = std::strtol(text.c_str(), nullptr, 10);
  return true;
}

std::string tempDir(const std::string& name) {
  const std::string dir = ::testing::TempDir() + name + "_" + std::to_string(getpid());
  std::filesystem::remove_all(dir);
  return dir;
}

// The beams of one scan of each workload: still (fan2d, rings3d, and beams off any grid:
// pattern_rosette, vlp16_calibrated, os1_64_metadata) and moving.
const std::map<std::string, long> kWorkloadBeams = {{"fan2d", 1081},
                                                    {"rings3d", 64 * 1024},
                                                    {"fan_path", 1081},
                                                    {"fan_path_tilted", 1081},
                                                    {"rings_path", 16 * 1800},
                                                    {"rings_divergent", 7 * 16 * 1800},
                                                    {"sweep_fan", 360},
                                                    {"sweep_rings", 16 * 1800},
                                                    {"pattern_rosette", 10000},
                                                    {"vlp16_calibrated", 16 * 1808},
                                                    {"os1_64_metadata", 64 * 1024},
                                                    {"sweep_vlp16_calibrated", 16 * 1808},
                                                    {"sweep_os1_64_metadata", 64 * 1024}};

// A workload cast from the scene's poses, every method on it.
bool isStill(const std::string& workload) {
  return workload == "fan2d" || workload == "rings3d" || workload == "pattern_rosette" ||
         workload == "vlp16_calibrated" || workload == "os1_64_metadata";
}

bool isBruteForce(const std::string& method) {
  return method.size() > 6 && method.compare(method.size() - 6, 6, "_brute") == 0;
}

bool isMovingRow(const std::string& method) {
  return method == "pipeline" || method == "embree_default" || method == "embree_robust";
}

// The rows a workload has in a run of every method (those of --list-methods).
std::set<std::string> expectedRows(const std::string& workload,
                                   const std::vector<std::string>& methods) {
  const bool still = isStill(workload);
  std::set<std::string> rows;
  for (const std::string& m : methods) {
    if (still ? m != "pipeline_new_plane" || workload == "fan2d" : isMovingRow(m)) rows.insert(m);
  }
  return rows;
}

// Every moving row of the pipeline has Embree's time beside it (when Embree is built in): both
// positive, so the ratio the README reports is finite and positive.
void expectMovingRatios(const std::vector<std::string>& lines, bool has_embree) {
  std::map<std::pair<std::string, std::string>, std::map<std::string, double>> ns;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const auto f = splitFields(lines[i]);
    double value = 0;
    if (f.size() == kFields && parseDouble(f[6], &value)) ns[{f[0], f[1]}][f[2]] = value;
  }
  int moving = 0;
  for (const auto& [key, rows] : ns) {
    if (isStill(key.first)) continue;
    ++moving;
    ASSERT_EQ(rows.count("pipeline"), 1u) << key.first << ", " << key.second;
    if (!has_embree) continue;
    ASSERT_EQ(rows.count("embree_default"), 1u) << key.first << ", " << key.second;
    const double ratio = rows.at("embree_default") / rows.at("pipeline");
    EXPECT_TRUE(std::isfinite(ratio) && ratio > 0) << key.first << ", " << key.second;
  }
  EXPECT_GT(moving, 0);
}

TEST(BenchSmoke, BadArgumentsExitWithTwo) {
  EXPECT_EQ(runCommand(kBench + " --no-such-flag 2>/dev/null").status, 2);
  EXPECT_EQ(runCommand(kBench + " --scene nowhere 2>/dev/null").status, 2);
  EXPECT_EQ(runCommand(kBench + " --scene 2>/dev/null").status, 2);
  EXPECT_EQ(runCommand(kBench + " --method nothing 2>/dev/null").status, 2);
  EXPECT_EQ(runCommand(kBench + " --method 2>/dev/null").status, 2);
  EXPECT_EQ(runCommand(kBench + " --method pipeline --scene 2>/dev/null").status, 2);
  EXPECT_EQ(runCommand(kBench + " --workload sweeping 2>/dev/null").status, 2);
  EXPECT_EQ(runCommand(kBench + " --workload 2>/dev/null").status, 2);
}

TEST(BenchSmoke, ListsTheScenes) {
  const auto result = runCommand(kBench + " --list-scenes");
  ASSERT_EQ(result.status, 0);
  EXPECT_EQ(splitLines(result.output),
            (std::vector<std::string>{"sphere", "box_room", "tb3", "million", "vertex_rows",
                                      "forest", "warehouse", "forest_10m"}));
}

TEST(BenchSmoke, HelpListsEveryFlag) {
  const auto result = runCommand(kBench + " --help");
  ASSERT_EQ(result.status, 0);
  for (const char* flag : {"--quick", "--out", "--scene", "--workload", "--method", "--threads",
                           "--list-methods", "--list-scenes", "Exit status"}) {
    EXPECT_NE(result.output.find(flag), std::string::npos) << flag << "\n" << result.output;
  }
  EXPECT_EQ(runCommand(kBench + " --qui 2>/dev/null").status, 2);
}

TEST(BenchSmoke, ListsTheCoreMethods) {
  const auto result = runCommand(kBench + " --list-methods");
  ASSERT_EQ(result.status, 0);
  const auto lines = splitLines(result.output);
  const std::set<std::string> methods(lines.begin(), lines.end());
  for (const std::string m : {"seed_plane", "seed_uv", "cramer", "moller_trumbore", "watertight"}) {
    for (const std::string variant : {"_bvh", "_brute", "_f32_bvh", "_f32_brute"}) {
      EXPECT_EQ(methods.count(m + variant), 1u) << m + variant;
    }
  }
  EXPECT_EQ(methods.count("pipeline"), 1u);
  EXPECT_EQ(methods.count("pipeline_new_plane"), 1u);
}

// agree_robust is a fraction in [0, 1] that is 1 exactly when disagree_robust is 0, and at most
// the row's rays disagree; both are empty without Embree. embree_robust compared with itself
// agrees on every beam (a misaligned comparison would not).
void expectAgreementFields(const std::string& fraction_text, const std::string& count_text,
                           bool has_robust, long rays, bool is_robust, const std::string& line) {
  if (!has_robust) {
    EXPECT_TRUE(fraction_text.empty() && count_text.empty()) << line;
    return;
  }
  double fraction = -1;
  long disagree = -1;
  ASSERT_TRUE(parseDouble(fraction_text, &fraction) && fraction >= 0 && fraction <= 1) << line;
  ASSERT_TRUE(parseCount(count_text, &disagree) && disagree <= rays) << line;
  EXPECT_EQ(fraction == 1.0, disagree == 0) << line;
  if (is_robust) {
    EXPECT_EQ(disagree, 0) << line;
  }
}

// results.md's memory table: a row for each scene with meshes (the analytic sphere and box room
// have none), whose figures are positive and consistent: at least a slot's 36 bytes and a
// triangle's indices per triangle, and the ratio the two columns give.
// The rows of results.md's table under `heading` (up to the next heading), each split into its
// cells.
std::vector<std::vector<std::string>> tableRows(const std::string& md, const std::string& heading) {
  const std::size_t start = md.find(heading);
  if (start == std::string::npos) return {};
  const std::size_t end = md.find("\n## ", start + heading.size());
  std::vector<std::vector<std::string>> rows;
  for (const std::string& line : splitLines(md.substr(start, end - start))) {
    if (line.rfind("| ", 0) != 0 || line.rfind("| scene", 0) == 0 || line.rfind("| ---", 0) == 0) {
      continue;  // not a row, the header, or the rule under it
    }
    std::vector<std::string> f;
    std::stringstream cells(line.substr(1));
    for (std::string cell; std::getline(cells, cell, '|');) {
      const auto first = cell.find_first_not_of(' '), last = cell.find_last_not_of(' ');
      f.push_back(first == std::string::npos ? "" : cell.substr(first, last - first + 1));
    }
    rows.push_back(f);
  }
  return rows;
}

void expectMemoryTable(const std::string& md, bool has_embree) {
  ASSERT_NE(md.find("## Memory per triangle"), std::string::npos) << md;
  std::set<std::string> scenes;
  for (const std::vector<std::string>& f : tableRows(md, "## Memory per triangle")) {
    const std::string line = ::testing::PrintToString(f);
    ASSERT_EQ(f.size(), has_embree ? 5u : 3u) << line;
    scenes.insert(f[0]);
    long triangles = 0;
    double ours = 0;
    EXPECT_TRUE(parseCount(f[1], &triangles) && triangles > 0) << line;
    EXPECT_TRUE(parseDouble(f[2], &ours) && ours >= 36 + 12) << line;
    if (!has_embree) continue;
    double embree = 0, ratio = 0;
    EXPECT_TRUE(parseDouble(f[3], &embree) && embree > 0) << line;
    EXPECT_TRUE(parseDouble(f[4], &ratio)) << line;
    EXPECT_NEAR(ratio, ours / embree, 0.01) << line;
  }
  scenes.erase("tb3");  // where its data is
  EXPECT_EQ(scenes, (std::set<std::string>{"million", "vertex_rows", "forest", "warehouse"}));
}

// results.md's load table (--quick: binary STL, one thread): a row for each scene whose soup has
// at least 100000 triangles, the file's size that of a binary STL of them (84 + 50 bytes a
// triangle), positive times, and the ratio the two columns give.
void expectLoadTable(const std::string& md, bool has_embree) {
  ASSERT_NE(md.find("## Loading a mesh file"), std::string::npos) << md;
  std::set<std::string> scenes;
  for (const std::vector<std::string>& f : tableRows(md, "## Loading a mesh file")) {
    const std::string line = ::testing::PrintToString(f);
    ASSERT_EQ(f.size(), 8u) << line;
    scenes.insert(f[0]);
    EXPECT_EQ(f[1], "stl") << line;
    long triangles = 0, threads = 0;
    double mb = 0, ours = 0;
    ASSERT_TRUE(parseCount(f[2], &triangles) && triangles >= 100000) << line;
    EXPECT_TRUE(parseDouble(f[3], &mb)) << line;
    EXPECT_NEAR(mb, (84 + 50.0 * triangles) / 1e6, 0.051) << line;
    EXPECT_TRUE(parseCount(f[4], &threads) && threads == 1) << line;
    EXPECT_TRUE(parseDouble(f[5], &ours) && ours > 0) << line;
    if (!has_embree) {
      EXPECT_EQ(f[6], "n/a") << line;
      continue;
    }
    double peer = 0, ratio = 0;
    EXPECT_TRUE(parseDouble(f[6], &peer) && peer > 0) << line;
    EXPECT_TRUE(parseDouble(f[7], &ratio)) << line;
    EXPECT_NEAR(ratio, peer / ours, 0.01 * ratio + 0.005) << line;
  }
  // The soups of a million triangles and more (sphere's, box_room's and vertex_rows' are smaller).
  scenes.erase("tb3");  // where its data is
  EXPECT_EQ(scenes, (std::set<std::string>{"million", "forest", "warehouse"}));
}

TEST(BenchSmoke, QuickRunWritesEveryRow) {
  const auto listed = runCommand(kBench + " --list-methods");
  ASSERT_EQ(listed.status, 0);
  const std::vector<std::string> methods = splitLines(listed.output);

  const bool has_robust =
      std::find(methods.begin(), methods.end(), "embree_robust") != methods.end();
  const std::string dir = tempDir("bench_smoke");
  const std::string log = dir + ".log";
  const auto run = runCommand("timeout 900 " + kBench + " --quick --out " + dir + " 2>" + log);
  ASSERT_EQ(run.status, 0) << readFile(log);

  const auto lines = splitLines(readFile(dir + "/results.csv"));
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(lines[0], kHeader);

  std::map<std::pair<std::string, std::string>, std::set<std::string>> ran;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const auto f = splitFields(lines[i]);
    ASSERT_EQ(f.size(), kFields) << lines[i];
    const std::string& method = f[2];
    ran[{f[0], f[1]}].insert(method);
    EXPECT_EQ(f[3], "1") << lines[i];  // threads: without --threads every row has one
    long triangles = 0, rays = 0, leaks = 0, false_hits = 0;
    double ns = 0, mrays = 0, max_err = 0, p99_err = 0, max_ulp = 0;
    EXPECT_TRUE(parseCount(f[4], &triangles)) << lines[i];
    EXPECT_TRUE(parseCount(f[5], &rays) && rays > 0) << lines[i];
    ASSERT_EQ(kWorkloadBeams.count(f[0]), 1u) << lines[i];
    if (!isBruteForce(method)) {  // whole scans: the beams of every pose
      EXPECT_EQ(rays % kWorkloadBeams.at(f[0]), 0) << lines[i];
    }
    EXPECT_TRUE(parseDouble(f[6], &ns) && ns > 0) << lines[i];
    EXPECT_TRUE(parseDouble(f[7], &mrays) && mrays > 0) << lines[i];
    EXPECT_TRUE(parseDouble(f[8], &max_err) && max_err >= 0) << lines[i];
    EXPECT_TRUE(parseDouble(f[9], &p99_err) && p99_err >= 0 && p99_err <= max_err) << lines[i];
    EXPECT_TRUE(parseDouble(f[10], &max_ulp) && max_ulp >= 0) << lines[i];
    EXPECT_TRUE(parseCount(f[11], &leaks)) << lines[i];
    EXPECT_TRUE(parseCount(f[12], &false_hits)) << lines[i];
    if (method == "watertight_bvh" || method == "pipeline" || method == "pipeline_new_plane") {
      EXPECT_EQ(leaks, 0) << lines[i];
      EXPECT_EQ(false_hits, 0) << lines[i];
    }
    expectAgreementFields(f[13], f[14], has_robust, rays, method == "embree_robust", lines[i]);
  }

  // Every method for every still workload and scene that ran, but pipeline_new_plane on planar
  // fans only (elsewhere it is the pipeline); the pipeline and Embree's rows for the moving ones.
  // Every generated scene in every workload (tb3 runs only where its data is), but forest_10m,
  // which --quick leaves out.
  for (const auto& [key, present] : ran) {
    EXPECT_EQ(present, expectedRows(key.first, methods)) << key.first << ", " << key.second;
  }
  for (const std::string scene :
       {"sphere", "box_room", "million", "vertex_rows", "forest", "warehouse"}) {
    for (const auto& [workload, beams] : kWorkloadBeams) {
      EXPECT_EQ(ran.count({workload, scene}), 1u) << workload << ", " << scene;
    }
  }
  for (const auto& [key, present] : ran) EXPECT_NE(key.second, "forest_10m");
  expectMovingRatios(lines, has_robust);

  expectMemoryTable(readFile(dir + "/results.md"), has_robust);
  expectLoadTable(readFile(dir + "/results.md"), has_robust);
  for (const std::string name : {"pareto.png", "pareto_matrix.png"}) {
    const std::string png = readFile(dir + "/" + name);
    ASSERT_GT(png.size(), 8u) << name;
    EXPECT_EQ(png.substr(1, 3), "PNG") << name;
  }
  std::filesystem::remove_all(dir);
  std::filesystem::remove(log);
}

TEST(BenchSmoke, MethodKeepsOnlyTheRowsAskedFor) {
  const std::string dir = tempDir("bench_method");
  const std::string log = dir + ".log";
  const auto run = runCommand("timeout 300 " + kBench +
                              " --quick --scene box_room --method "
                              "watertight_bvh pipeline --out " +
                              dir + " 2>" + log);
  ASSERT_EQ(run.status, 0) << readFile(log);
  const auto lines = splitLines(readFile(dir + "/results.csv"));
  // header, 5 still workloads x 2 rows, 8 moving ones x the pipeline's row
  ASSERT_EQ(lines.size(), 19u) << readFile(dir + "/results.csv");
  std::multiset<std::string> rows;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const auto f = splitFields(lines[i]);
    ASSERT_EQ(f.size(), kFields) << lines[i];
    EXPECT_EQ(f[1], "box_room") << lines[i];
    rows.insert(f[0] + " " + f[2]);
  }
  EXPECT_EQ(rows, (std::multiset<std::string>{
                      "fan2d watertight_bvh", "fan2d pipeline", "rings3d watertight_bvh",
                      "rings3d pipeline", "fan_path pipeline", "fan_path_tilted pipeline",
                      "rings_path pipeline", "rings_divergent pipeline", "sweep_fan pipeline",
                      "sweep_rings pipeline",
                      "pattern_rosette watertight_bvh", "pattern_rosette pipeline",
                      "vlp16_calibrated watertight_bvh", "vlp16_calibrated pipeline",
                      "os1_64_metadata watertight_bvh", "os1_64_metadata pipeline",
                      "sweep_vlp16_calibrated pipeline", "sweep_os1_64_metadata pipeline"}));
  std::filesystem::remove_all(dir);
  std::filesystem::remove(log);
}

TEST(BenchSmoke, WorkloadKeepsOnlyTheWorkloadsAskedFor) {
  const std::string dir = tempDir("bench_workload");
  const std::string log = dir + ".log";
  const auto run = runCommand("timeout 300 " + kBench +
                              " --quick --scene sphere box_room --workload sweep_fan fan2d "
                              "--method pipeline --out " +
                              dir + " 2>" + log);
  ASSERT_EQ(run.status, 0) << readFile(log);
  const auto lines = splitLines(readFile(dir + "/results.csv"));
  std::multiset<std::string> rows;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const auto f = splitFields(lines[i]);
    ASSERT_EQ(f.size(), kFields) << lines[i];
    rows.insert(f[0] + " " + f[1] + " " + f[2]);
  }
  // Workload-major, in the benchmark's order of workloads, whatever the order asked in.
  EXPECT_EQ(rows, (std::multiset<std::string>{"fan2d sphere pipeline", "fan2d box_room pipeline",
                                              "sweep_fan sphere pipeline",
                                              "sweep_fan box_room pipeline"}));
  ASSERT_EQ(lines.size(), 5u);
  EXPECT_EQ(splitFields(lines[1])[0], "fan2d");
  EXPECT_EQ(splitFields(lines[4])[0], "sweep_fan");
  std::filesystem::remove_all(dir);
  std::filesystem::remove(log);
}

// pipeline_new_plane casts the fan without kept slices: the same ranges (so the same errors and
// agreement, field for field), and no row on the 3D workload.
TEST(BenchSmoke, NewPlaneRowHasThePipelinesRanges) {
  const std::string dir = tempDir("bench_new_plane");
  const std::string log = dir + ".log";
  const auto run = runCommand(
      "timeout 300 " + kBench +
      " --quick --scene forest --method pipeline pipeline_new_plane --out " + dir + " 2>" + log);
  ASSERT_EQ(run.status, 0) << readFile(log);
  const auto lines = splitLines(readFile(dir + "/results.csv"));
  // header, fan2d x 2 rows, rings3d x 1 row, the pipeline's 6 moving rows, one row each of
  // pattern_rosette, vlp16_calibrated and os1_64_metadata, then the calibrated heads' two sweeps
  ASSERT_EQ(lines.size(), 15u) << readFile(dir + "/results.csv");
  const auto kept = splitFields(lines[1]), fresh = splitFields(lines[2]);
  ASSERT_EQ(kept.size(), kFields);
  ASSERT_EQ(fresh.size(), kFields);
  EXPECT_EQ(kept[0] + " " + kept[2], "fan2d pipeline");
  EXPECT_EQ(fresh[0] + " " + fresh[2], "fan2d pipeline_new_plane");
  for (const std::size_t k : {8, 9, 10, 11, 12, 13, 14}) {  // errors and agreement
    EXPECT_EQ(kept[k], fresh[k]) << "field " << k << ": " << lines[1] << " / " << lines[2];
  }
  EXPECT_EQ(splitFields(lines[3])[2], "pipeline");
  std::filesystem::remove_all(dir);
  std::filesystem::remove(log);
}

// --threads adds a second pipeline row; the ranges do not depend on the thread count, so its
// errors against the reference are the first row's, field for field.
TEST(BenchSmoke, ThreadsAddsAPipelineRowWithTheSameRanges) {
  const std::string dir = tempDir("bench_threads");
  const std::string log = dir + ".log";
  const auto run = runCommand("timeout 300 " + kBench +
                              " --quick --scene box_room --method pipeline --threads 2 --out " +
                              dir + " 2>" + log);
  ASSERT_EQ(run.status, 0) << readFile(log);
  const auto lines = splitLines(readFile(dir + "/results.csv"));
  ASSERT_EQ(lines.size(), 27u) << readFile(dir + "/results.csv");  // header, 13 workloads x 2
  for (std::size_t i = 1; i + 1 < lines.size(); i += 2) {
    const auto one = splitFields(lines[i]), two = splitFields(lines[i + 1]);
    ASSERT_EQ(one.size(), kFields) << lines[i];
    ASSERT_EQ(two.size(), kFields) << lines[i + 1];
    EXPECT_EQ(one[2], "pipeline");
    EXPECT_EQ(one[3], "1");
    EXPECT_EQ(two[2], "pipeline");
    EXPECT_EQ(two[3], "2");
    for (const std::size_t k : {8, 9, 10, 11, 12, 13, 14}) {  // errors and agreement
      EXPECT_EQ(one[k], two[k]) << "field " << k << ": " << lines[i] << " / " << lines[i + 1];
    }
  }
  EXPECT_NE(readFile(dir + "/results.md").find("| pipeline | 2 |"), std::string::npos);
  EXPECT_EQ(runCommand(kBench + " --threads 5000 2>/dev/null").status, 2);
  EXPECT_EQ(runCommand(kBench + " --threads two 2>/dev/null").status, 2);
  std::filesystem::remove_all(dir);
  std::filesystem::remove(log);
}

// The paths are generated from a fixed seed: two runs cast the same beams from the same poses,
// so every moving row's rays, errors and agreement are the same, field for field.
TEST(BenchSmoke, MovingRowsAreTheSameInEveryRun) {
  std::vector<std::vector<std::string>> runs;
  for (int run = 0; run < 2; ++run) {
    const std::string dir = tempDir("bench_paths" + std::to_string(run));
    const std::string log = dir + ".log";
    const auto result =
        runCommand("timeout 300 " + kBench + " --quick --scene sphere --method pipeline --out " +
                   dir + " 2>" + log);
    ASSERT_EQ(result.status, 0) << readFile(log);
    runs.push_back(splitLines(readFile(dir + "/results.csv")));
    std::filesystem::remove_all(dir);
    std::filesystem::remove(log);
  }
  ASSERT_EQ(runs[0].size(), runs[1].size());
  int moving = 0;
  for (std::size_t i = 1; i < runs[0].size(); ++i) {
    const auto a = splitFields(runs[0][i]), b = splitFields(runs[1][i]);
    ASSERT_EQ(a.size(), kFields) << runs[0][i];
    ASSERT_EQ(b.size(), kFields) << runs[1][i];
    if (isStill(a[0])) continue;
    ++moving;
    for (const std::size_t k : {0, 1, 2, 5, 8, 9, 10, 11, 12, 13, 14}) {
      EXPECT_EQ(a[k], b[k]) << "field " << k << ": " << runs[0][i] << " / " << runs[1][i];
    }
  }
  EXPECT_EQ(moving, 8);
}

}  // namespace
}  // namespace laser_raycast_test
