// The benchmark's results: per-row error statistics against the reference, and the three outputs
// (results.csv, results.md, pareto.png through scripts/plot_pareto).
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "bench_meshes.h"

namespace laser_raycast {
namespace bench {

struct ErrorStats {
  double max_abs_err_m = 0;  // over the beams where both the method and the reference hit
  double p99_abs_err_m = 0;
  double max_ulp = 0;   // the largest error in units of the float spacing at the reference range
  long leaks = 0;       // the method misses where the reference hits
  long false_hits = 0;  // the method hits where the reference misses
};

// Compares the method's distances with the reference's at the given ray indices (+inf: no hit).
ErrorStats compareWithReference(const std::vector<double>& dist, const std::vector<Real>& reference,
                                const std::vector<int>& rays);

// Per beam, whether a method and a peer (Embree's robust mode) give the same answer: both miss,
// or both hit within the tolerance. Unavailable (no such peer): disagree < 0.
struct Agreement {
  double fraction = 0;  // of the beams compared
  long disagree = -1;   // beams compared that do not agree
  long excluded = 0;    // beams not compared: the method's geometry differs from the peer's there
  bool available() const { return disagree >= 0; }
};

// The tolerance of the agreement column (m): the performance issue's criterion.
constexpr double kAgreementTolerance = 1e-4;

// Whether two distances (+inf: no hit) agree: both miss, or both hit within the tolerance. NaN,
// and a hit against a miss, never agree.
bool agrees(double a, double b);

// Compares the method's distances with the peer's at the given ray indices where comparable is
// non-zero (an empty comparable: at all of them).
Agreement compareWithPeer(const std::vector<double>& dist, const std::vector<double>& peer,
                          const std::vector<int>& rays, const std::vector<char>& comparable);

struct Row {
  std::string workload, scene, method;
  int threads = 1;  // threads the method cast with (0: every core)
  std::size_t triangles = 0, rays = 0;
  double ns_per_ray = 0;
  ErrorStats errors;
  Agreement agree_robust;  // with embree_robust
  double range_max = 0;    // m, the scene's (for the run's description)
};

// The memory of one scene's meshes, each distinct mesh once however many bodies instance it (the
// primitives hold no triangles).
struct MemoryRow {
  std::string scene;
  std::size_t triangles = 0;   // of the distinct meshes
  std::size_t ours_bytes = 0;  // core::Mesh::bytes(), summed over them
  // What Embree holds for the same meshes, each built alone in its own frame (embreeMeshBytes);
  // nullopt without Embree.
  std::optional<std::size_t> embree_bytes;
};

// Loading one scene's soup written as a mesh file (bench_load.h).
struct LoadRow {
  std::string scene, format;  // whose soup the file holds; stl (binary) or obj
  std::size_t triangles = 0, file_bytes = 0;
  int threads = 1;  // the loader's BVH build threads (0: every core)
  // Wall clock of each round, alternated: the loader's (file to built mesh), and assimp's read
  // plus Embree's build (one build thread), empty without Embree.
  std::vector<double> ours_seconds, peer_seconds;
};

// Soups with fewer triangles are not written: either side loads them in well under a second.
constexpr std::size_t kLoadMinTriangles = 100000;

// The stable header of results.csv.
extern const char* const kCsvHeader;

void writeCsv(const std::string& path, const std::vector<Row>& rows);
// The table of results.csv plus vs_embree (embree_default's ns_per_ray over the row's, same
// workload and scene), after a few lines that say how the run was made (run_info, markdown), then
// the memory per triangle of each scene that has meshes (Embree's columns only with Embree).
// Unavailable agreement columns are empty in the CSV and n/a in the table.
// Then the loads ("Loading a mesh file": medians, and vs_peer, the peer's median over ours).
void writeMarkdown(const std::string& path, const std::vector<Row>& rows,
                   const std::vector<MemoryRow>& memory, const std::vector<LoadRow>& loads,
                   const std::string& run_info);

// Runs /usr/bin/python3 script args... Returns "" on success, else what went wrong.
std::string runPlot(const std::string& script, const std::vector<std::string>& args);

}  // namespace bench
}  // namespace laser_raycast
