// bench: speed and accuracy of every triangle method (double and float, brute force and BVH), the
// pipeline (Caster::cast as the node runs it) and the peers (Embree, Bullet) on identical rays,
// every distance measured against a long double reference and compared with Embree's robust mode.
// See kSynopsis, flags() and the README's "Benchmark" section.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench_load.h"
#include "bench_methods.h"
#include "bench_peers.h"
#include "bench_report.h"
#include "bench_run.h"
#include "bench_scenes.h"
#include "command_line.h"

namespace {

namespace bench = laser_raycast::bench;
namespace core = laser_raycast::core;
namespace po = boost::program_options;
using laser_raycast::tools::ArgError;

constexpr int kExitRunFailed = 1;  // bad command lines: tools::kExitBadArguments

const char* const kSynopsis =
    "usage: bench [--quick] [--out DIR] [--scene NAME ...] [--workload NAME ...]\n"
    "             [--method NAME ...] [--list-methods] [--threads N] [--list-scenes]\n";
const char* const kNotes =
    "Times every method on the workloads fan2d and rings3d (one pose cast again and again)\n"
    "and on beams off any grid from the same poses (pattern_rosette: a pattern file's\n"
    "rosette; vlp16_calibrated: a calibrated VLP-16's beams; os1_64_metadata: an Ouster\n"
    "OS1-64's from its metadata file), and the pipeline and Embree on sensors moving along a\n"
    "path (fan_path, fan_path_tilted, rings_path, rings_divergent: each beam 7 sub-rays,\n"
    "sweep_fan, sweep_rings, and the calibrated heads rotating: sweep_vlp16_calibrated,\n"
    "sweep_os1_64_metadata), and measures each\n"
    "beam's error against a long double reference and its agreement with Embree's robust\n"
    "mode. load: each scene's soup of at least 100000 triangles written as a mesh file (STL,\n"
    "and OBJ and PLY without --quick) and loaded as the node does, against assimp reading it and\n"
    "Embree building its BVH. Writes DIR/results.csv, results.md, pareto.png (one point per\n"
    "method) and pareto_matrix.png (every workload and scene) (DIR defaults to\n"
    "bench_results). Scenes:\n"
    "sphere box_room tb3 million vertex_rows forest warehouse forest_10m (default all,\n"
    "forest_10m not with --quick; tb3 needs tb3_world_data: $LASER_RAYCAST_SHARED_DATA, the\n"
    "ROS package, or ../shared/data beside the source). --workload: only these workloads\n"
    "(default all). --method: only these rows (default\n"
    "all; --list-methods names them). --quick: fewer poses, scans and repetitions (6\n"
    "minutes on 2 cores). --threads N: a second pipeline row cast with N threads (0: every\n"
    "core); every other row is single-threaded.\n"
    "Exit status: 0 ok, 1 the run failed, 2 bad arguments.\n";

struct Options {
  bool quick = false;
  std::string out_dir = "bench_results";
  std::vector<std::string> scenes;   // empty: all
  std::vector<std::string> workloads;  // empty: all
  std::vector<std::string> methods;  // empty: all
  int threads = 1;                   // the second pipeline row's; 1: no second row
  bool list_methods = false, list_scenes = false;
};

// The scenes run without --scene: all, but the large ones in a --quick run.
std::vector<std::string> defaultScenes(bool quick) {
  std::vector<std::string> names;
  for (const std::string& name : bench::sceneNames()) {
    if (!quick || !bench::isLargeScene(name)) names.push_back(name);
  }
  return names;
}

// The full run times more and longer batches on more rays; --quick is a smoke test.
bench::Settings settingsFor(bool quick) {
  return quick ? bench::Settings{3, 0.01, 1e6, 1, 3} : bench::Settings{5, 0.05, 4e7, 32, 3};
}

std::vector<std::string> allMethodNames() {
  std::vector<std::string> names = bench::coreMethodNames();
  const std::vector<std::string> peers = bench::peerMethodNames();
  names.insert(names.end(), peers.begin(), peers.end());
  return names;
}

// Not a workload of rays: loading each scene's soup as a mesh file (bench_load.h).
const char* const kLoadWorkload = "load";

std::vector<std::string> workloadNames() {
  std::vector<std::string> names;
  for (const bench::Workload& workload : bench::workloads()) names.push_back(workload.name);
  names.push_back(kLoadWorkload);
  return names;
}

std::string joined(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& name : names) out += (out.empty() ? "" : " ") + name;
  return out;
}

// The names given to a list flag, each checked against known and kept once, in the order given.
std::vector<std::string> knownNames(const std::string& what, const std::vector<std::string>& names,
                                    const std::vector<std::string>& known) {
  std::vector<std::string> out;
  for (const std::string& name : names) {
    if (std::find(known.begin(), known.end(), name) == known.end()) {
      throw ArgError("unknown " + what + " '" + name + "' (" + what + "s: " + joined(known) + ")");
    }
    if (std::find(out.begin(), out.end(), name) == out.end()) out.push_back(name);
  }
  return out;
}

// A list flag: --flag A B ..., or --flag A --flag B; the names must be among known.
po::typed_value<std::vector<std::string>>* nameList(const std::string& what,
                                                    std::vector<std::string> known,
                                                    std::vector<std::string>* out) {
  return po::value<std::vector<std::string>>()
      ->multitoken()
      ->composing()
      ->value_name("NAME ...")
      ->notifier([what, known, out](const std::vector<std::string>& names) {
        *out = knownNames(what, names, known);
      });
}

// The flags, in the order the help lists them; the notifiers store the values into *options.
po::options_description flags(Options* options) {
  po::options_description flags("Options");
  auto add = flags.add_options();
  add("quick", po::bool_switch(&options->quick), "fewer poses and repetitions");
  add("out",
      po::value<std::string>()->value_name("DIR")->notifier([options](const std::string& dir) {
        if (dir.empty()) throw ArgError("--out needs a directory");
        options->out_dir = dir;
      }),
      "where the results go (default bench_results)");
  add("scene", nameList("scene", bench::sceneNames(), &options->scenes),
      "the scenes to run (default all)");
  add("workload", nameList("workload", workloadNames(), &options->workloads),
      "the workloads to run (default all)");
  add("method", nameList("method", allMethodNames(), &options->methods),
      "the rows to run (default all)");
  add("threads",
      po::value<std::string>()->value_name("N")->notifier([options](const std::string& text) {
        options->threads = laser_raycast::tools::parseThreads("--threads", text);
      }),
      "also time the pipeline with N threads (0: every core)");
  add("list-methods", po::bool_switch(&options->list_methods),
      "print the methods this build has and exit");
  add("list-scenes", po::bool_switch(&options->list_scenes), "print the scenes and exit");
  add("help,h", "print this help");
  return flags;
}

// Throws ArgError.
Options parseArgs(int argc, char** argv, bool* help) {
  Options options;
  po::variables_map values;
  *help = !laser_raycast::tools::parseCommandLine(argc, argv, flags(&options), &values);
  if (options.scenes.empty()) options.scenes = defaultScenes(options.quick);
  return options;
}

// Installed, the script sits beside the executable (both in lib/laser_raycast); in a devel space
// it is read from the source tree.
std::string plotScript() {
  std::error_code error;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", error);
  if (!error) {
    const auto beside = exe.parent_path() / "plot_pareto";
    if (std::filesystem::exists(beside)) return beside.string();
  }
  return std::string(LASER_RAYCAST_SOURCE_DIR) + "/scripts/plot_pareto";
}

std::string cpuModel() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.compare(0, 10, "model name") == 0) return line.substr(line.find(':') + 2);
  }
  return "unknown CPU";
}

bool contains(const std::vector<std::string>& list, const std::string& name) {
  return std::find(list.begin(), list.end(), name) != list.end();
}

// The scene's rows (those asked for) and Embree's robust mode for the agreement columns.
bench::SceneMethods sceneMethods(const Options& options, bench::SceneGeometry* geometry) {
  const bench::BenchScene& scene = *geometry->scene;
  const auto wanted = [&](const std::string& name) {
    return options.methods.empty() || contains(options.methods, name);
  };
  geometry->bvh = core::Bvh::build(scene.soup.vertices, scene.soup.triangles);  // the reference's
  const auto names = allMethodNames();
  if (std::any_of(names.begin(), names.end(), [&](const std::string& name) {
        return name.find("_f32") != std::string::npos && wanted(name);
      })) {
    geometry->bvh_f = core::BvhF::build(scene.soup.vertices, scene.soup.triangles);
  }
  bench::SceneMethods methods;
  methods.rows = bench::coreMethods(*geometry, wanted, options.threads);
  const auto wanted_or_robust = [&](const std::string& name) {
    return wanted(name) || name == "embree_robust";
  };
  for (bench::Method& peer : bench::peerMethods(scene.soup, wanted_or_robust)) {
    if (peer.name == "embree_robust") methods.robust = peer;
    if (wanted(peer.name)) methods.rows.push_back(std::move(peer));
  }
  return methods;
}

// The log line of a scene's memory per triangle.
void logMemory(const bench::MemoryRow& memory) {
  const double triangles = static_cast<double>(memory.triangles);
  const double ours = static_cast<double>(memory.ours_bytes) / triangles;
  std::cerr << "  memory: " << memory.triangles << " triangles in its distinct meshes, ours "
            << ours << " bytes per triangle";
  if (memory.embree_bytes) {
    const double embree = static_cast<double>(*memory.embree_bytes) / triangles;
    std::cerr << ", Embree's " << embree << " bytes per triangle (ours/embree " << ours / embree
              << ")";
  }
  std::cerr << "\n";
}

// The rows, each scene's memory per triangle in *memory (the scenes with meshes), and the loads of
// their soups as files in *loads (the large ones, unless --workload leaves load out).
std::vector<bench::Row> runBenchmark(const Options& options, const bench::Settings& settings,
                                     std::vector<bench::MemoryRow>* memory,
                                     std::vector<bench::LoadRow>* loads) {
  std::vector<bench::Row> rows;
  const std::string shared_dir =
      contains(options.scenes, "tb3") ? bench::findSharedData() : std::string();
  for (const std::string& name : options.scenes) {
    const auto build_start = std::chrono::steady_clock::now();
    std::optional<bench::BenchScene> scene = bench::makeScene(name, shared_dir);
    if (!scene) {
      std::cerr << "bench: note: skipping scene " << name
                << ": no tb3_world_data found (set LASER_RAYCAST_SHARED_DATA to the directory "
                   "holding it, or put it on ROS_PACKAGE_PATH)\n";
      continue;
    }
    // Whatever methods and workloads run, and before the rows' structures are built, so that its
    // Embree scenes are released before any row is built or timed.
    const std::optional<bench::MemoryRow> scene_memory = bench::measureMemory(*scene);
    bench::SceneGeometry geometry;
    geometry.scene = &*scene;
    const bench::SceneMethods methods = sceneMethods(options, &geometry);
    std::cerr << "bench: scene " << name << " (" << scene->note
              << "): " << scene->soup.triangles.size() << " triangles in the soup, "
              << scene->scene.bodies().size() << " bodies, range max " << scene->range_max
              << " m, built in " << bench::secondsSince(build_start) << " s\n";
    if (scene_memory) {
      logMemory(*scene_memory);
      memory->push_back(*scene_memory);
    }
    if (options.workloads.empty() || contains(options.workloads, kLoadWorkload)) {
      // --quick: the STL only, one round (a smoke test of the row).
      const std::vector<std::string> formats =
          options.quick ? std::vector<std::string>{"stl"}
                        : std::vector<std::string>{"stl", "obj", "ply"};
      for (bench::LoadRow& row :
           bench::measureLoads(*scene, formats, options.quick ? 1 : 3, options.threads)) {
        loads->push_back(std::move(row));
      }
    }
    for (const bench::Workload& workload : bench::workloads()) {
      if (!options.workloads.empty() && !contains(options.workloads, workload.name)) continue;
      const int poses = options.quick ? workload.quick_poses : workload.full_poses;
      bench::runWorkload(settings, poses, *scene, geometry, methods, workload, &rows);
    }
  }
  // Workload-major, as the output promises; scenes and methods keep their order.
  auto workload_index = [](const std::string& name) {
    const auto& list = bench::workloads();
    return std::find_if(list.begin(), list.end(),
                        [&](const bench::Workload& w) { return w.name == name; }) -
           list.begin();
  };
  std::stable_sort(rows.begin(), rows.end(), [&](const bench::Row& a, const bench::Row& b) {
    return workload_index(a.workload) < workload_index(b.workload);
  });
  return rows;
}

// The command line as given (defaults left out).
std::string commandLine(const Options& options) {
  std::string command = "bench";
  if (options.quick) command += " --quick";
  if (options.scenes != defaultScenes(options.quick))
    command += " --scene " + joined(options.scenes);
  if (!options.methods.empty()) command += " --method " + joined(options.methods);
  if (options.threads != 1) command += " --threads " + std::to_string(options.threads);
  return command;
}

// "bench --quick on 2026-01-31 12:00 UTC, <cpu>": which run the results come from.
std::string runLabel(const Options& options) {
  const std::time_t now = std::time(nullptr);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
  return commandLine(options) + " on " + date + ", " + cpuModel();
}

std::string runInfo(const Options& options, const bench::Settings& settings,
                    const std::vector<bench::Row>& rows, double seconds) {
  std::ostringstream info;
  info << "# laser_raycast benchmark\n\n";
  info << "Run: " << runLabel(options) << ", single-threaded";
  if (options.threads != 1) {
    info << " except the second pipeline row (threads " << options.threads
         << (options.threads == 0 ? ": every core" : "") << ")";
  }
  info << ", " << std::lround(seconds) << " s wall clock. ";
  info << "Sensor poses (still workloads) or scans along a path (moving ones) per scene: ";
  for (const auto& w : bench::workloads()) {
    info << w.name << " " << (options.quick ? w.quick_poses : w.full_poses) << ", ";
  }
  info << "range max";
  std::string last_scene;
  for (const bench::Row& row : rows) {
    if (row.scene == last_scene || row.workload != rows.front().workload) continue;
    info << (last_scene.empty() ? " " : ", ") << row.scene << " " << row.range_max << " m";
    last_scene = row.scene;
  }
  info << ". ns_per_ray: median of " << settings.reps << " timed batches (each at least "
       << settings.min_batch_seconds << " s); the pipeline and Embree rows are timed alternately "
       << "in " << settings.rounds << " such rounds and report the median round. Brute-force rows "
       << "use an evenly spread subset of at most " << settings.brute_tests
       << " triangle tests per pass (at least " << settings.brute_min_rays
       << " rays). Peers: " << bench::peerVersions() << ". ";
  info << "Errors against a long double reference on the geometry each method was given; "
          "vs_embree = embree_default's ns_per_ray / the row's (> 1: faster than Embree); "
          "agree_robust: the fraction of the row's beams on which it and embree_robust both miss "
          "or both hit within "
       << bench::kAgreementTolerance << " m, disagree_robust: the beams where they do not.\n";
  return info.str();
}

int run(const Options& options) {
  const auto start = std::chrono::steady_clock::now();
  const bench::Settings settings = settingsFor(options.quick);
  const std::filesystem::path out(options.out_dir);
  std::filesystem::create_directories(out);
  std::vector<bench::MemoryRow> memory;
  std::vector<bench::LoadRow> loads;
  const std::vector<bench::Row> rows = runBenchmark(options, settings, &memory, &loads);
  if (rows.empty() && loads.empty()) throw std::runtime_error("no scene ran");
  const std::string csv = (out / "results.csv").string();
  const std::string md = (out / "results.md").string();
  const std::string png = (out / "pareto.png").string();
  const std::string matrix_png = (out / "pareto_matrix.png").string();
  bench::writeCsv(csv, rows);
  bench::writeMarkdown(md, rows, memory, loads,
                       runInfo(options, settings, rows, bench::secondsSince(start)));
  if (rows.empty()) {  // only loads: nothing to plot
    std::cerr << "bench: done in " << bench::secondsSince(start) << " s: " << md << "\n";
    return 0;
  }
  const std::string plot_error = bench::runPlot(
      plotScript(), {csv, png, "--matrix", matrix_png, "--source", "Run: " + runLabel(options)});
  if (!plot_error.empty()) throw std::runtime_error("plotting failed: " + plot_error);
  std::cerr << "bench: done in " << bench::secondsSince(start) << " s: " << csv << ", " << md
            << ", " << png << ", " << matrix_png << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  const auto exit_now = laser_raycast::tools::readCommandLine("bench", kSynopsis, kNotes, parseArgs,
                                                              flags, argc, argv, &options);
  if (exit_now) return *exit_now;
  if (options.list_methods || options.list_scenes) {
    if (options.list_methods)
      for (const auto& m : allMethodNames()) std::cout << m << "\n";
    if (options.list_scenes)
      for (const auto& s : bench::sceneNames()) std::cout << s << "\n";
    return 0;
  }
  try {
    return run(options);
  } catch (const std::exception& e) {
    std::cerr << "bench: " << e.what() << "\n";
    return kExitRunFailed;
  }
}
