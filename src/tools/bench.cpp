// bench: speed and accuracy of every triangle method (double and float, brute force and BVH), the
// pipeline (Caster::cast as the node runs it) and the peers (Embree, Bullet) on identical rays,
// every distance measured against a long double reference. See kUsage and the README's
// "Benchmark" section.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <numeric>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench_methods.h"
#include "bench_peers.h"
#include "bench_reference.h"
#include "bench_report.h"
#include "bench_scenes.h"

namespace {

namespace bench = laser_raycast::bench;
namespace core = laser_raycast::core;
using bench::Real;

constexpr int kExitRunFailed = 1;
constexpr int kExitBadArguments = 2;

const char* const kUsage =
    "usage: bench [--quick] [--out DIR] [--scene NAME ...] [--list-methods] [--list-scenes]\n"
    "Times every method on the workloads fan2d and rings3d and measures each beam's error\n"
    "against a long double reference. Writes DIR/results.csv, results.md, pareto.png (one\n"
    "point per method) and pareto_matrix.png (every workload and scene) (DIR defaults to\n"
    "bench_results). Scenes: sphere box_room tb3 million vertex_rows (default\n"
    "all; tb3 needs tb3_world_data: $LASER_RAYCAST_SHARED_DATA, the ROS package, or\n"
    "../shared/data beside the source). --quick: fewer poses and repetitions (under 2 minutes).\n"
    "Exit status: 0 ok, 1 the run failed, 2 bad arguments.\n";

class ArgError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Options {
  bool quick = false;
  std::string out_dir = "bench_results";
  std::vector<std::string> scenes;  // empty: all
  bool list_methods = false, list_scenes = false, help = false;
};

// How much work a run does. Every number here only trades run time for noise.
struct Settings {
  int reps;                  // timed batches per row; the median is reported
  double min_batch_seconds;  // a batch repeats its pass until it lasts this long
  double brute_tests;        // triangle tests a brute-force row may do per pass ...
  int brute_min_rays;        // ... but at least this many rays
  double range_max = 100.0;  // m, every method's tmax
};

Settings settingsFor(bool quick) {
  return quick ? Settings{3, 0.01, 4e6, 8} : Settings{5, 0.05, 4e7, 32};
}

Options parseArgs(int argc, char** argv) {
  Options options;
  const std::vector<std::string> words(argv + 1, argv + argc);
  const auto& known = bench::sceneNames();
  for (std::size_t i = 0; i < words.size(); ++i) {
    std::string flag = words[i], value;
    const bool inline_value = flag.compare(0, 2, "--") == 0 && flag.find('=') != std::string::npos;
    if (inline_value) {
      value = flag.substr(flag.find('=') + 1);
      flag = flag.substr(0, flag.find('='));
    }
    if (flag == "--quick" && !inline_value) {
      options.quick = true;
    } else if (flag == "--out") {
      if (!inline_value) {
        if (i + 1 >= words.size()) throw ArgError("--out needs a directory");
        value = words[++i];
      }
      if (value.empty()) throw ArgError("--out needs a directory");
      options.out_dir = value;
    } else if (flag == "--scene") {
      // --scene A --scene B, or --scene A B.
      std::vector<std::string> names;
      if (inline_value) names.push_back(value);
      while (!inline_value && i + 1 < words.size() && words[i + 1].compare(0, 2, "--") != 0) {
        names.push_back(words[++i]);
      }
      if (names.empty()) throw ArgError("--scene needs a scene name");
      for (const std::string& name : names) {
        if (std::find(known.begin(), known.end(), name) == known.end()) {
          throw ArgError("unknown scene '" + name +
                         "' (scenes: sphere box_room tb3 million vertex_rows)");
        }
        if (std::find(options.scenes.begin(), options.scenes.end(), name) == options.scenes.end())
          options.scenes.push_back(name);
      }
    } else if (flag == "--list-methods" && !inline_value) {
      options.list_methods = true;
    } else if (flag == "--list-scenes" && !inline_value) {
      options.list_scenes = true;
    } else if ((flag == "-h" || flag == "--help") && !inline_value) {
      options.help = true;
    } else {
      throw ArgError("unknown argument '" + words[i] + "'");
    }
  }
  if (options.scenes.empty()) options.scenes = known;
  return options;
}

std::vector<std::string> allMethodNames() {
  std::vector<std::string> names = bench::coreMethodNames();
  const std::vector<std::string> peers = bench::peerMethodNames();
  names.insert(names.end(), peers.begin(), peers.end());
  return names;
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

// Ray indices for brute-force rows: evenly spread over every pose and ring, as many as the budget
// of triangle tests allows (all of them on small scenes).
std::vector<int> bruteSubset(std::size_t rays, std::size_t triangles, const Settings& settings) {
  const double budget = settings.brute_tests / std::max<double>(1.0, triangles);
  const std::size_t count = std::min(
      rays, std::max<std::size_t>(settings.brute_min_rays, static_cast<std::size_t>(budget)));
  std::vector<int> subset;
  for (std::size_t k = 0; k < count; ++k) {
    subset.push_back(static_cast<int>((2 * k + 1) * rays / (2 * count)));
  }
  return subset;
}

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The triangle reference (on the tessellated boxes) against the analytic boxes on the same rays:
// independent code, the same room up to the double rounding of the vertices.
void crossCheckReference(const std::string& label, const std::vector<Real>& triangles,
                         const std::vector<Real>& analytic) {
  long disagree = 0;
  Real max_diff = 0;
  for (std::size_t i = 0; i < triangles.size(); ++i) {
    const bool a = std::isfinite(static_cast<double>(triangles[i]));
    const bool b = std::isfinite(static_cast<double>(analytic[i]));
    if (a != b) ++disagree;
    if (a && b) max_diff = std::max(max_diff, std::fabs(triangles[i] - analytic[i]));
  }
  std::cerr << "  " << label << ": reference cross-check, triangles vs analytic boxes: " << disagree
            << " hit/miss disagreements in " << triangles.size() << " beams, max |difference| "
            << static_cast<double>(max_diff) << " m\n";
}

// The pipeline's beams as it holds them: the double sensor poses and the double directions of
// core::ScanPattern, composed in long double.
std::vector<bench::RayL> pipelineInputRays(const bench::WorkloadRays& w) {
  std::vector<bench::RayL> out;
  for (const Eigen::Isometry3d& sensor : w.sensors) {
    for (const Eigen::Vector3d& d : w.pattern->directions()) {
      bench::RayL ray;
      ray.origin = sensor.translation().cast<Real>();
      ray.dir = sensor.linear().cast<Real>() * d.cast<Real>();
      ray.tmin = 0;
      ray.tmax = w.tmax;
      out.push_back(ray);
    }
  }
  return out;
}

long countHits(const std::vector<Real>& reference) {
  return std::count_if(reference.begin(), reference.end(),
                       [](Real r) { return std::isfinite(static_cast<double>(r)); });
}

// One workload on one scene: the rays, both references, then every method's row.
void runWorkload(const Options& options, const Settings& settings, const bench::BenchScene& scene,
                 const bench::SceneGeometry& geometry, const std::vector<bench::Method>& methods,
                 const bench::Workload& workload, std::vector<bench::Row>* rows) {
  const int poses = options.quick ? workload.quick_poses : workload.full_poses;
  const bench::WorkloadRays rays = bench::makeRays(scene, workload, poses, settings.range_max);
  const auto ref_start = std::chrono::steady_clock::now();
  const std::vector<bench::RayL> exact = bench::exactRays(rays.rays);
  const std::vector<Real> ref_soup = bench::referenceSoup(geometry.bvh, exact);
  const std::vector<Real> ref_pipeline = bench::referenceBodies(
      scene,
      bench::pipelineRays(rays.poses, workload.fan, workload.elevations, settings.range_max));
  std::cerr << "  " << workload.name << ": " << rays.rays.size() << " rays from "
            << rays.poses.size() << " poses; the reference hits " << countHits(ref_soup)
            << " (soup) and " << countHits(ref_pipeline) << " (pipeline), computed in "
            << secondsSince(ref_start) << " s\n";
  // The pipeline's error splits into the rounding of its inputs (pose and beam directions to
  // double) and its arithmetic; the log shows the second alone.
  const std::vector<Real> ref_pipeline_inputs =
      bench::referenceBodies(scene, pipelineInputRays(rays));
  if (scene.name == "box_room") {
    crossCheckReference(workload.name, ref_soup, bench::referenceBodies(scene, exact));
  }

  std::vector<int> all(rays.rays.size());
  std::iota(all.begin(), all.end(), 0);
  const std::vector<int> subset =
      bruteSubset(rays.rays.size(), scene.soup.triangles.size(), settings);
  for (const bench::Method& method : methods) {
    const std::vector<int>& used = method.brute ? subset : all;
    std::vector<double> dist(rays.rays.size(), std::numeric_limits<double>::quiet_NaN());
    const double seconds =
        bench::timePass(method.pass, rays, used, &dist, settings.reps, settings.min_batch_seconds);
    bench::Row row;
    row.workload = workload.name;
    row.scene = scene.name;
    row.method = method.name;
    row.triangles = method.triangles;
    row.rays = used.size();
    row.ns_per_ray = seconds * 1e9 / static_cast<double>(used.size());
    row.errors = bench::compareWithReference(dist, method.pipeline ? ref_pipeline : ref_soup, used);
    std::cerr << "    " << method.name << ": " << row.ns_per_ray << " ns/ray, max error "
              << row.errors.max_abs_err_m << " m, " << row.errors.leaks << " leaks, "
              << row.errors.false_hits << " false hits";
    if (method.pipeline) {
      const auto arithmetic = bench::compareWithReference(dist, ref_pipeline_inputs, used);
      std::cerr << " (against its double inputs: max error " << arithmetic.max_abs_err_m << " m, "
                << arithmetic.leaks << " leaks, " << arithmetic.false_hits << " false hits)";
    }
    std::cerr << "\n";
    rows->push_back(row);
  }
}

std::vector<bench::Row> runBenchmark(const Options& options, const Settings& settings) {
  std::vector<bench::Row> rows;
  const bool wants_tb3 =
      std::find(options.scenes.begin(), options.scenes.end(), "tb3") != options.scenes.end();
  const std::string shared_dir = wants_tb3 ? bench::findSharedData() : std::string();
  for (const std::string& name : options.scenes) {
    const auto build_start = std::chrono::steady_clock::now();
    std::optional<bench::BenchScene> scene = bench::makeScene(name, shared_dir);
    if (!scene) {
      std::cerr << "bench: note: skipping scene " << name
                << ": no tb3_world_data found (set LASER_RAYCAST_SHARED_DATA to the directory "
                   "holding it, or put it on ROS_PACKAGE_PATH)\n";
      continue;
    }
    bench::SceneGeometry geometry;
    geometry.scene = &*scene;
    geometry.bvh = core::Bvh::build(scene->soup.vertices, scene->soup.triangles);
    geometry.bvh_f = core::BvhF::build(scene->soup.vertices, scene->soup.triangles);
    std::vector<bench::Method> methods = bench::coreMethods(geometry);
    for (auto& peer : bench::peerMethods(scene->soup)) methods.push_back(std::move(peer));
    std::cerr << "bench: scene " << name << " (" << scene->note
              << "): " << scene->soup.triangles.size() << " triangles in the soup, "
              << scene->scene.bodies().size() << " bodies, built in " << secondsSince(build_start)
              << " s\n";
    for (const bench::Workload& workload : bench::workloads()) {
      runWorkload(options, settings, *scene, geometry, methods, workload, &rows);
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

// "bench --quick on 2026-01-31 12:00 UTC, <cpu>": which run the results come from.
std::string runLabel(const Options& options) {
  const std::time_t now = std::time(nullptr);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
  return std::string("bench") + (options.quick ? " --quick" : "") + " on " + date + ", " +
         cpuModel();
}

std::string runInfo(const Options& options, const Settings& settings, double seconds) {
  std::ostringstream info;
  info << "# laser_raycast benchmark\n\n";
  info << "Run: " << runLabel(options) << ", single-threaded, " << std::lround(seconds)
       << " s wall clock. ";
  info << "Sensor poses per scene: ";
  for (const auto& w : bench::workloads()) {
    info << w.name << " " << (options.quick ? w.quick_poses : w.full_poses) << ", ";
  }
  info << "range max " << settings.range_max << " m. ns_per_ray: median of " << settings.reps
       << " timed batches (each at least " << settings.min_batch_seconds
       << " s). Brute-force rows use an evenly spread subset of at most " << settings.brute_tests
       << " triangle tests per pass (at least " << settings.brute_min_rays
       << " rays). Peers: " << bench::peerVersions() << ". ";
  info << "Errors against a long double reference on the geometry each method was given; "
          "vs_embree = embree_default's ns_per_ray / the row's (> 1: faster than Embree).\n";
  return info.str();
}

int run(const Options& options) {
  const auto start = std::chrono::steady_clock::now();
  const Settings settings = settingsFor(options.quick);
  const std::filesystem::path out(options.out_dir);
  std::filesystem::create_directories(out);
  const std::vector<bench::Row> rows = runBenchmark(options, settings);
  if (rows.empty()) throw std::runtime_error("no scene ran");
  const std::string csv = (out / "results.csv").string();
  const std::string md = (out / "results.md").string();
  const std::string png = (out / "pareto.png").string();
  const std::string matrix_png = (out / "pareto_matrix.png").string();
  bench::writeCsv(csv, rows);
  bench::writeMarkdown(md, rows, runInfo(options, settings, secondsSince(start)));
  const std::string plot_error = bench::runPlot(
      plotScript(), {csv, png, "--matrix", matrix_png, "--source", "Run: " + runLabel(options)});
  if (!plot_error.empty()) throw std::runtime_error("plotting failed: " + plot_error);
  std::cerr << "bench: done in " << secondsSince(start) << " s: " << csv << ", " << md << ", "
            << png << ", " << matrix_png << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  try {
    options = parseArgs(argc, argv);
  } catch (const ArgError& e) {
    std::cerr << "bench: " << e.what() << "\n" << kUsage;
    return kExitBadArguments;
  }
  if (options.help) {
    std::cout << kUsage;
    return 0;
  }
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
