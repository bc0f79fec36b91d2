// Loading a mesh file, as a node does at start-up: each scene's soup written as a file, read and
// its BVH built by the loader (its own STL reader, assimp in the importer process for the other
// formats), against assimp reading the same file and Embree building its BVH.
#pragma once

#include <string>
#include <vector>

#include "bench_report.h"
#include "bench_scenes.h"

namespace laser_raycast {
namespace bench {

// The rows for the scene's soup, one per format and thread count (threads: 1, and the second if it
// is not 1), each timed in `rounds` alternated rounds, the files written in a directory of their
// own under /tmp and removed. None for a soup under
// kLoadMinTriangles. Throws std::runtime_error if a file cannot be written or either side cannot
// read it.
std::vector<LoadRow> measureLoads(const BenchScene& scene, const std::vector<std::string>& formats,
                                  int rounds, int threads);

}  // namespace bench
}  // namespace laser_raycast
