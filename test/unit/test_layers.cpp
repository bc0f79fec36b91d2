// The three layers (core, loader, node) stay apart. On Debian the ROS headers live in /usr/include,
// so include paths alone cannot keep a ROS header out of the core: this test reads every source
// file's #include lines, and the core library's dynamic dependencies. Inside the core, the same
// #include lines keep its own layers (src/core/<layer>/) in order and its modules free of cycles.
#include <gtest/gtest.h>

#include <algorithm>
#include <deque>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "run_command.h"

namespace laser_raycast_test {
namespace {

namespace fs = std::filesystem;

const fs::path kSource = LASER_RAYCAST_SOURCE_DIR;

struct Include {
  fs::path file;
  int line;
  std::string name;  // as written between <> or ""
};

bool isSourceFile(const fs::path& file) {
  const std::string ext = file.extension().string();
  return ext == ".h" || ext == ".cpp";
}

std::vector<Include> includesOf(const fs::path& file) {
  static const std::regex kInclude(R"(^\s*#\s*include\s*[<"]([^>"]+)[>"])");
  std::vector<Include> out;
  std::ifstream in(file);
  std::string text;
  for (int line = 1; std::getline(in, text); ++line) {
    std::smatch match;
    if (std::regex_search(text, match, kInclude)) out.push_back({file, line, match[1].str()});
  }
  return out;
}

std::vector<Include> includesUnder(const std::vector<fs::path>& dirs) {
  std::vector<Include> out;
  for (const fs::path& dir : dirs) {
    EXPECT_TRUE(fs::is_directory(dir)) << dir;
    if (!fs::is_directory(dir)) continue;
    for (const auto& entry : fs::recursive_directory_iterator(dir)) {
      if (!isSourceFile(entry.path())) continue;
      const std::vector<Include> found = includesOf(entry.path());
      out.insert(out.end(), found.begin(), found.end());
    }
  }
  return out;
}

bool startsWith(const std::string& s, const std::string& prefix) {
  return s.compare(0, prefix.size(), prefix) == 0;
}

// The C++ standard library's headers have no extension and no directory; the SIMD intrinsics
// headers are the compiler's own.
bool isStandardOrCompilerHeader(const std::string& name) {
  static const std::set<std::string> kIntrinsics = {"emmintrin.h", "immintrin.h", "xmmintrin.h",
                                                    "pmmintrin.h", "smmintrin.h", "nmmintrin.h",
                                                    "cpuid.h"};
  if (kIntrinsics.count(name)) return true;
  return name.find('/') == std::string::npos && name.find('.') == std::string::npos;
}

// The core's own layers, lowest first (docs/design.md §2). Each private file lives in
// src/core/<layer>/ and is included as "<layer>/<name>.h".
const std::vector<std::string> kCoreLayers = {"util",  "geometry", "accel",  "scene",      "beams",
                                              "slice", "walk",     "caster", "measurement"};

// Where a layer stands in kCoreLayers; -1 for a name that is no layer.
int layerRank(const std::string& layer) {
  const auto it = std::find(kCoreLayers.begin(), kCoreLayers.end(), layer);
  return it == kCoreLayers.end() ? -1 : static_cast<int>(it - kCoreLayers.begin());
}

// The public headers stay flat in include/laser_raycast/core/, so their folder cannot say which
// layer they belong to: this table does. A new public header must be added here.
const std::map<std::string, std::string>& publicHeaderLayers() {
  static const std::map<std::string, std::string> kTable = {
      {"enum_names.h", "util"},
      {"ray.h", "geometry"},
      {"aabb.h", "geometry"},
      {"triangle.h", "geometry"},
      {"primitives.h", "geometry"},
      {"pose.h", "geometry"},
      {"bvh.h", "accel"},
      {"bvh_config.h", "accel"},
      {"mesh.h", "scene"},
      {"scene.h", "scene"},
      {"pose_samples.h", "scene"},
      {"surface.h", "scene"},
      {"scan_pattern.h", "beams"},
      {"beam_list.h", "beams"},
      {"pattern_file.h", "beams"},
      {"velodyne_beams.h", "beams"},
      {"ouster_beams.h", "beams"},
      {"cast_config.h", "beams"},
      {"scan_result.h", "beams"},
      {"caster.h", "caster"},
      {"sub_ray_bundle.h", "caster"},
      {"measurement_model.h", "measurement"},
      {"scan_spec.h", "measurement"},
      {"sensor_model.h", "measurement"},
      {"surface_reflectance.h", "measurement"},
      {"returns.h", "measurement"},
  };
  return kTable;
}

// A module is a header and its source: the same name in the same layer, whether the header is
// public (include/laser_raycast/core/x.h) or private (src/core/<layer>/x.h).
struct Module {
  std::string layer;
  std::string name;  // the file name without its extension
  bool operator<(const Module& o) const {
    return std::tie(layer, name) < std::tie(o.layer, o.name);
  }
  bool operator==(const Module& o) const { return layer == o.layer && name == o.name; }
  std::string str() const { return layer + "/" + name; }
};

// The module of a public header, given by its path under laser_raycast/core/.
std::optional<Module> publicModule(const std::string& header, std::string& problem) {
  const auto it = publicHeaderLayers().find(header);
  if (it == publicHeaderLayers().end()) {
    problem = "the public header laser_raycast/core/" + header +
              " has no layer: add it to the table in publicHeaderLayers() (test_layers.cpp)";
    return std::nullopt;
  }
  return Module{it->second, fs::path(header).stem().string()};
}

// The module of a private file, given by its path under src/core/: exactly <layer>/<file>.
std::optional<Module> privateModule(const std::string& path, std::string& problem) {
  const fs::path rel(path);
  const std::string folder = rel.parent_path().generic_string();
  if (layerRank(folder) < 0) {
    problem = "src/core/" + path + " is not in a layer's folder: a core file lives in " +
              "src/core/<layer>/ for one of util, geometry, accel, scene, beams, slice, walk, " +
              "caster, measurement";
    return std::nullopt;
  }
  return Module{folder, rel.stem().string()};
}

// The first folder of an include, "" if it has none.
std::string firstFolder(const std::string& name) {
  const std::size_t slash = name.find('/');
  return slash == std::string::npos ? "" : name.substr(0, slash);
}

// The core module an #include names; none, and no problem, for a header outside the core.
std::optional<Module> includedModule(const std::string& name, std::string& problem) {
  static const std::string kPublic = "laser_raycast/core/";
  if (startsWith(name, kPublic)) return publicModule(name.substr(kPublic.size()), problem);
  if (layerRank(firstFolder(name)) >= 0) return privateModule(name, problem);
  return std::nullopt;
}

TEST(Layers, TheCoreIncludesOnlyEigenTheStandardLibraryAndItself) {
  const auto includes =
      includesUnder({kSource / "include/laser_raycast/core", kSource / "src/core"});
  ASSERT_FALSE(includes.empty());
  for (const Include& inc : includes) {
    // Which core headers a core file may include is the layering tests' business below.
    const bool allowed = isStandardOrCompilerHeader(inc.name) || startsWith(inc.name, "Eigen/") ||
                         startsWith(inc.name, "laser_raycast/core/") ||
                         layerRank(firstFolder(inc.name)) >= 0;
    EXPECT_TRUE(allowed) << inc.file.string() << ":" << inc.line << " includes " << inc.name
                         << ": the core may include only Eigen, the standard library, "
                            "laser_raycast/core/ and its own layers' folders (\"<layer>/...\")";
  }
}

// One #include from one core module of another (or of itself: a source and its header).
struct ModuleEdge {
  std::string file;
  int line;
  std::string included;  // as written
  Module from;
  Module to;
};

// The layering rule on plain data: a module may include only its own layer and the ones below.
std::vector<std::string> layeringViolations(const std::vector<ModuleEdge>& edges) {
  std::vector<std::string> out;
  for (const ModuleEdge& e : edges) {
    const int from = layerRank(e.from.layer);
    const int to = layerRank(e.to.layer);
    if (from >= 0 && to >= 0 && to <= from) continue;
    out.push_back(e.file + ":" + std::to_string(e.line) + " includes " + e.included + " (layer " +
                  e.to.layer + ") from layer " + e.from.layer +
                  ": a layer may include only its own and the ones below it (docs/design.md §2)");
  }
  return out;
}

// For each module, the modules it includes, each with the first #include that does so.
using ModuleGraph = std::map<Module, std::map<Module, ModuleEdge>>;

ModuleGraph moduleGraph(const std::vector<ModuleEdge>& edges) {
  ModuleGraph graph;
  for (const ModuleEdge& e : edges) {
    if (e.from == e.to) continue;  // a source including its own header is no dependency
    graph[e.from].emplace(e.to, e);
  }
  return graph;
}

// Breadth first from start: every module it reaches, with the edge by which it was first reached
// (start itself only if it lies on a cycle, and then the path back to it is a shortest cycle).
std::map<Module, const ModuleEdge*> searchFrom(const ModuleGraph& graph, const Module& start) {
  std::map<Module, const ModuleEdge*> reachedBy;
  std::deque<Module> queue = {start};
  while (!queue.empty()) {
    const auto out = graph.find(queue.front());
    queue.pop_front();
    if (out == graph.end()) continue;
    for (const auto& [next, edge] : out->second) {
      if (reachedBy.count(next)) continue;
      reachedBy[next] = &edge;
      queue.push_back(next);
    }
  }
  return reachedBy;
}

// "a -> b -> a", then the #include behind each step; start must lie on a cycle.
std::string describeCycle(const ModuleGraph& graph, const Module& start) {
  const std::map<Module, const ModuleEdge*> reachedBy = searchFrom(graph, start);
  std::vector<const ModuleEdge*> path;
  Module at = start;
  do {
    path.insert(path.begin(), reachedBy.at(at));
    at = path.front()->from;
  } while (!(at == start));
  std::string chain = start.str();
  std::string steps;
  for (const ModuleEdge* e : path) {
    chain += " -> " + e->to.str();
    steps += "\n  " + e->file + ":" + std::to_string(e->line) + " includes " + e->included;
  }
  return "include cycle between core modules: " + chain + steps;
}

// No cycles on plain data: one cycle for each strongly connected component of more than one
// module (a module that reaches itself, with every module it reaches and that reaches it back).
std::vector<std::string> includeCycles(const std::vector<ModuleEdge>& edges) {
  const ModuleGraph graph = moduleGraph(edges);
  std::map<Module, std::set<Module>> reaches;
  for (const auto& entry : graph) {
    for (const auto& [module, edge] : searchFrom(graph, entry.first)) {
      reaches[entry.first].insert(module);
    }
  }
  const auto reachesModule = [&reaches](const Module& from, const Module& to) {
    const auto it = reaches.find(from);
    return it != reaches.end() && it->second.count(to) > 0;
  };
  std::set<Module> reported;
  std::vector<std::string> out;
  for (const auto& [module, reached] : reaches) {
    if (reported.count(module) || !reached.count(module)) continue;
    for (const Module& other : reached) {
      if (reachesModule(other, module)) reported.insert(other);
    }
    out.push_back(describeCycle(graph, module));
  }
  return out;
}

// Every core file's includes of other core files, and every file or include without a layer.
struct CoreGraph {
  std::vector<ModuleEdge> edges;
  std::vector<std::string> unplaced;
};

CoreGraph readCoreGraph() {
  const std::vector<std::pair<fs::path, bool>> roots = {
      {kSource / "include/laser_raycast/core", true}, {kSource / "src/core", false}};
  CoreGraph graph;
  for (const auto& [root, isPublic] : roots) {
    EXPECT_TRUE(fs::is_directory(root)) << root;
    if (!fs::is_directory(root)) continue;
    for (const auto& entry : fs::recursive_directory_iterator(root)) {
      if (!isSourceFile(entry.path())) continue;
      const std::string rel = entry.path().lexically_relative(root).generic_string();
      std::string problem;
      const auto from = isPublic ? publicModule(rel, problem) : privateModule(rel, problem);
      if (!from) graph.unplaced.push_back(entry.path().string() + ": " + problem);
      for (const Include& inc : includesOf(entry.path())) {
        problem.clear();  // none for a header outside the core
        const auto to = includedModule(inc.name, problem);
        const std::string where = inc.file.string() + ":" + std::to_string(inc.line);
        if (!to && !problem.empty()) graph.unplaced.push_back(where + ": " + problem);
        if (from && to) graph.edges.push_back({inc.file.string(), inc.line, inc.name, *from, *to});
      }
    }
  }
  return graph;
}

// Every core file, and every core header a core file includes, belongs to one of the layers.
TEST(Layers, EveryCoreFileHasALayer) {
  for (const std::string& problem : readCoreGraph().unplaced) ADD_FAILURE() << problem;
}

TEST(Layers, CoreFilesIncludeOnlyTheirOwnLayerAndTheOnesBelow) {
  const CoreGraph graph = readCoreGraph();
  ASSERT_FALSE(graph.edges.empty());
  for (const std::string& violation : layeringViolations(graph.edges)) ADD_FAILURE() << violation;
}

// The layers order the core only between layers; within one, modules must not include each other
// in a circle either, or they could be neither built nor read one at a time.
TEST(Layers, CoreModulesIncludeEachOtherWithoutCycles) {
  const CoreGraph graph = readCoreGraph();
  ASSERT_FALSE(graph.edges.empty());
  for (const std::string& cycle : includeCycles(graph.edges)) ADD_FAILURE() << cycle;
}

// The public headers are the only ones installed: one that included a private header would not
// compile in a downstream package.
TEST(Layers, PublicHeadersIncludeOnlyPublicHeaders) {
  const auto includes = includesUnder({kSource / "include/laser_raycast/core"});
  ASSERT_FALSE(includes.empty());
  for (const Include& inc : includes) {
    EXPECT_LT(layerRank(firstFolder(inc.name)), 0)
        << inc.file.string() << ":" << inc.line << " includes the private header " << inc.name
        << ": an installed header may include only laser_raycast/core/ and outside headers";
  }
}

// The checks above pass on a good tree; these show on made-up includes that they can also fail.
ModuleEdge syntheticEdge(const std::string& from, const std::string& to) {
  const auto module = [](const std::string& s) {
    return Module{firstFolder(s), s.substr(s.find('/') + 1)};
  };
  return {"src/core/" + from + ".cpp", 1, to + ".h", module(from), module(to)};
}

const std::vector<ModuleEdge> kCleanEdges = {
    syntheticEdge("geometry/ray", "util/enum_names"), syntheticEdge("accel/bvh", "geometry/ray"),
    syntheticEdge("accel/bvh", "accel/wide_bvh"),     syntheticEdge("accel/bvh", "accel/bvh"),
    syntheticEdge("walk/slice_walk", "accel/bvh"),    syntheticEdge("walk/slice_walk", "walk/a"),
    syntheticEdge("walk/a", "accel/wide_bvh"),
};

TEST(LayerChecks, ACleanGraphReportsNothing) {
  EXPECT_TRUE(layeringViolations(kCleanEdges).empty());
  EXPECT_TRUE(includeCycles(kCleanEdges).empty());
}

TEST(LayerChecks, ABackEdgeIsReported) {
  std::vector<ModuleEdge> edges = kCleanEdges;
  edges.push_back(syntheticEdge("beams/scan_pattern", "walk/slice_walk"));
  const std::vector<std::string> violations = layeringViolations(edges);
  ASSERT_EQ(violations.size(), 1u);
  EXPECT_NE(violations[0].find("src/core/beams/scan_pattern.cpp:1 includes walk/slice_walk.h "
                               "(layer walk) from layer beams"),
            std::string::npos)
      << violations[0];
  EXPECT_TRUE(includeCycles(edges).empty());  // a back edge alone closes no circle
}

TEST(LayerChecks, ACycleWithinOneLayerIsReported) {
  std::vector<ModuleEdge> edges = kCleanEdges;
  edges.push_back(syntheticEdge("slice/a", "slice/b"));
  edges.push_back(syntheticEdge("slice/b", "slice/a"));
  EXPECT_TRUE(layeringViolations(edges).empty());  // within one layer, so no layering violation
  const std::vector<std::string> cycles = includeCycles(edges);
  ASSERT_EQ(cycles.size(), 1u);
  EXPECT_NE(cycles[0].find("slice/a -> slice/b -> slice/a"), std::string::npos) << cycles[0];
  EXPECT_NE(cycles[0].find("src/core/slice/b.cpp:1 includes slice/a.h"), std::string::npos)
      << cycles[0];
}

// The module of a file or an include comes from the table or the folder; anything else has none.
TEST(LayerChecks, FilesAndIncludesArePlacedByTheTableAndTheFolders) {
  std::string problem;
  EXPECT_EQ(includedModule("laser_raycast/core/bvh.h", problem), (Module{"accel", "bvh"}));
  EXPECT_EQ(includedModule("walk/slice_walk.h", problem), (Module{"walk", "slice_walk"}));
  EXPECT_FALSE(includedModule("vector", problem) || includedModule("Eigen/Core", problem));
  EXPECT_TRUE(problem.empty()) << problem;
  EXPECT_FALSE(includedModule("laser_raycast/core/new_thing.h", problem));
  EXPECT_NE(problem.find("add it to the table"), std::string::npos) << problem;
  problem.clear();
  EXPECT_FALSE(privateModule("stray.cpp", problem));
  EXPECT_NE(problem.find("is not in a layer's folder"), std::string::npos) << problem;
  problem.clear();
  EXPECT_FALSE(privateModule("other/stray.cpp", problem));
  EXPECT_FALSE(problem.empty());
}

TEST(Layers, TheLoaderIncludesNoRoscppTfMessagesOrNode) {
  const auto includes =
      includesUnder({kSource / "include/laser_raycast/loader", kSource / "src/loader"});
  ASSERT_FALSE(includes.empty());
  for (const Include& inc : includes) {
    // roslib's ros/package.h (package:// look-up) needs no roscore and no roscpp.
    const bool roscpp = startsWith(inc.name, "ros/") && inc.name != "ros/package.h";
    const bool forbidden = roscpp || startsWith(inc.name, "tf2") ||
                           inc.name.find("_msgs/") != std::string::npos ||
                           startsWith(inc.name, "laser_raycast/node/");
    EXPECT_FALSE(forbidden) << inc.file.string() << ":" << inc.line << " includes " << inc.name
                            << ": the loader may not use roscpp, TF, messages or the node";
  }
}

// The one exception is the node's offline front end, the tool simulate_bag, through the node's
// public header for it.
TEST(Layers, NothingOutsideTheNodeIncludesTheNode) {
  const auto includes =
      includesUnder({kSource / "include/laser_raycast/core", kSource / "src/core",
                     kSource / "include/laser_raycast/loader", kSource / "src/loader",
                     kSource / "src/python", kSource / "src/tools"});
  for (const Include& inc : includes) {
    const bool front_end = inc.file == kSource / "src/tools/simulate_bag.cpp" &&
                           inc.name == "laser_raycast/node/bag_simulation.h";
    EXPECT_FALSE(startsWith(inc.name, "laser_raycast/node/") && !front_end)
        << inc.file.string() << ":" << inc.line << " includes " << inc.name;
  }
}

// The shared libraries a binary loads directly (its NEEDED entries).
std::vector<std::string> neededLibraries(const std::string& binary) {
  const CommandResult r = runCommand("objdump -p '" + binary + "' 2>&1 | grep NEEDED");
  EXPECT_EQ(r.status, 0) << "objdump found no NEEDED entries in " << binary << ": " << r.output;
  std::vector<std::string> needed;
  std::istringstream lines(r.output);
  std::string word;
  while (lines >> word) {
    if (word == "NEEDED" && lines >> word) needed.push_back(word);
  }
  return needed;
}

TEST(Layers, TheCoreLibraryLinksNothingFromRosOrTheLoader) {
  static const std::regex kForbidden("ros|urdf|assimp|console_bridge|tinyxml|boost|tf2");
  const std::vector<std::string> needed = neededLibraries(CORE_LIBRARY_PATH);
  for (const std::string& library : needed) {
    EXPECT_FALSE(std::regex_search(library, kForbidden))
        << "the core library " << CORE_LIBRARY_PATH << " links " << library;
  }
  EXPECT_FALSE(needed.empty());  // at least the C++ runtime: objdump did see the dynamic section
}

// The tools depend directly only on what they use: the core, the loader, the kinematics and their
// own libraries (program_options, the bench's peers). The loader's libraries (urdfdom, assimp,
// roslib, KDL) reach them only through it, so the package:// resolver stays the loader's. One
// exception: the bench's load row times assimp itself as a peer (assimp reading a mesh file, then
// Embree's build), so the bench may link assimp; it never resolves a URI with it.
TEST(Layers, TheToolsDependDirectlyOnlyOnWhatTheyUse) {
  static const std::regex kForbidden(
      "^lib(ros|urdf|assimp|console_bridge|tinyxml|orocos|python|tf2|message|xmlrpc|cpp_common)");
  static const std::regex kAssimp("^libassimp");
  for (const std::string tool : {CAST_SCAN_PATH, BENCH_PATH}) {
    const std::vector<std::string> needed = neededLibraries(tool);
    for (const std::string& library : needed) {
      const bool peer = tool == std::string(BENCH_PATH) && std::regex_search(library, kAssimp);
      EXPECT_FALSE(std::regex_search(library, kForbidden) && !peer) << tool << " links " << library;
    }
    for (const std::string used : {"liblaser_raycast_core.so", "liblaser_raycast_scene_loader.so",
                                   "liblaser_raycast_kinematics.so"}) {
      EXPECT_EQ(std::count(needed.begin(), needed.end(), used), 1) << tool << " needs " << used;
    }
  }
}

// Nor do they load roscpp at all, not even through a library (kdl_parser, the ROS urdf library).
TEST(Layers, TheToolsLoadNoRoscpp) {
  static const std::regex kRoscpp(
      "(^|\\s)lib(roscpp|rosconsole|xmlrpcpp|tf2|kdl_parser|urdf\\.so)");
  for (const std::string tool : {CAST_SCAN_PATH, BENCH_PATH}) {
    const CommandResult r = runCommand("ldd '" + tool + "' 2>&1");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("liblaser_raycast_scene_loader.so"), std::string::npos) << r.output;
    std::istringstream lines(r.output);
    std::string line;
    while (std::getline(lines, line)) {
      EXPECT_FALSE(std::regex_search(line, kRoscpp)) << tool << " loads " << line;
    }
  }
}

}  // namespace
}  // namespace laser_raycast_test
