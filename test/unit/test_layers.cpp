// The three layers (core, loader, node) stay apart. On Debian the ROS headers live in /usr/include,
// so include paths alone cannot keep a ROS header out of the core: this test reads every source
// file's #include lines, and the core library's dynamic dependencies.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
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

std::vector<Include> includesUnder(const std::vector<fs::path>& dirs) {
  static const std::regex kInclude(R"(^\s*#\s*include\s*[<"]([^>"]+)[>"])");
  std::vector<Include> out;
  for (const fs::path& dir : dirs) {
    EXPECT_TRUE(fs::is_directory(dir)) << dir;
    if (!fs::is_directory(dir)) continue;
    for (const auto& entry : fs::recursive_directory_iterator(dir)) {
      const std::string ext = entry.path().extension().string();
      if (ext != ".h" && ext != ".cpp") continue;
      std::ifstream in(entry.path());
      std::string text;
      for (int line = 1; std::getline(in, text); ++line) {
        std::smatch match;
        if (std::regex_search(text, match, kInclude)) {
          out.push_back({entry.path(), line, match[1].str()});
        }
      }
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

TEST(Layers, TheCoreIncludesOnlyEigenTheStandardLibraryAndItself) {
  const auto includes =
      includesUnder({kSource / "include/laser_raycast/core", kSource / "src/core"});
  ASSERT_FALSE(includes.empty());
  for (const Include& inc : includes) {
    const bool allowed = isStandardOrCompilerHeader(inc.name) || startsWith(inc.name, "Eigen/") ||
                         startsWith(inc.name, "laser_raycast/core/");
    EXPECT_TRUE(allowed) << inc.file.string() << ":" << inc.line << " includes " << inc.name
                         << ": the core may include only Eigen, the standard library and "
                            "laser_raycast/core/";
  }
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

TEST(Layers, NothingOutsideTheNodeIncludesTheNode) {
  const auto includes = includesUnder({kSource / "include/laser_raycast/core", kSource / "src/core",
                                       kSource / "include/laser_raycast/loader",
                                       kSource / "src/loader", kSource / "src/tools"});
  for (const Include& inc : includes) {
    EXPECT_FALSE(startsWith(inc.name, "laser_raycast/node/"))
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
// roslib, KDL) reach them only through it, so the package:// resolver stays the loader's.
TEST(Layers, TheToolsDependDirectlyOnlyOnWhatTheyUse) {
  static const std::regex kForbidden(
      "^lib(ros|urdf|assimp|console_bridge|tinyxml|orocos|python|tf2|message|xmlrpc|cpp_common)");
  for (const std::string tool : {CAST_SCAN_PATH, BENCH_PATH}) {
    const std::vector<std::string> needed = neededLibraries(tool);
    for (const std::string& library : needed) {
      EXPECT_FALSE(std::regex_search(library, kForbidden)) << tool << " links " << library;
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
