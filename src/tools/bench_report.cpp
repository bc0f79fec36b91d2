#include "bench_report.h"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <ostream>
#include <stdexcept>
#include <utility>

#include "bench_methods.h"

namespace laser_raycast {
namespace bench {
namespace {

// The spacing of floats at x (x > 0): the unit the max_ulp column counts in.
double floatUlp(double x) {
  const float f = static_cast<float>(x);
  if (!(f >= std::numeric_limits<float>::min())) return std::numeric_limits<float>::denorm_min();
  return std::ldexp(1.0, std::ilogb(f) - 23);
}

std::string format(const char* spec, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, spec, value);
  return buffer;
}

// A fraction rounded down to `digits` decimals, so that 1 means no exception at all.
std::string fractionDown(double fraction, int digits) {
  const double scale = std::pow(10.0, digits);
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", digits, std::floor(fraction * scale) / scale);
  return buffer;
}

std::ofstream openForWriting(const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  return out;
}

// The memory per triangle of each scene's meshes, ours and (with Embree) Embree's, with a line
// saying what each side counts: a scene's figure is per mesh triangle, not per soup triangle.
void writeMemoryTable(std::ostream& out, const std::vector<MemoryRow>& memory) {
  const bool embree = std::any_of(memory.begin(), memory.end(),
                                  [](const MemoryRow& m) { return m.embree_bytes.has_value(); });
  out << "\n## Memory per triangle\n\n";
  out << "Each scene's distinct meshes, each once however many bodies instance it, in its own "
         "frame (primitives hold no triangles and are left out); ours: core::Mesh::bytes(), its "
         "vertices (in float where they are a file's floats), triangles, closed components, BVH "
         "slots and wide nodes";
  if (embree) {
    out << "; Embree: the bytes its device's memory monitor counts for the mesh built alone as "
           "embree_default builds the soup, its BVH with triangle leaves plus its float vertex "
           "and index buffers (the monitor counts the buffers made by rtcSetNewGeometryBuffer, "
           "the vertex buffer with its 4 bytes of padding)";
  }
  out << ".\n\n";
  if (memory.empty()) {
    out << "No scene run has meshes.\n";
    return;
  }
  out << "| scene | triangles | ours_bytes_per_triangle |"
      << (embree ? " embree_bytes_per_triangle | ours/embree |" : "") << "\n";
  out << "| --- | ---: | ---: |" << (embree ? " ---: | ---: |" : "") << "\n";
  for (const MemoryRow& m : memory) {
    const double triangles = static_cast<double>(m.triangles);
    const double ours = static_cast<double>(m.ours_bytes) / triangles;
    out << "| " << m.scene << " | " << m.triangles << " | " << format("%.1f", ours) << " |";
    if (embree) {
      if (m.embree_bytes) {
        const double theirs = static_cast<double>(*m.embree_bytes) / triangles;
        out << " " << format("%.1f", theirs) << " | " << format("%.3g", ours / theirs) << " |";
      } else {
        out << " n/a | n/a |";
      }
    }
    out << "\n";
  }
}

}  // namespace

const char* const kCsvHeader =
    "workload,scene,method,threads,triangles,rays,ns_per_ray,mrays_per_s,max_abs_err_m,p99_abs_err_"
    "m,"
    "max_ulp,leaks,false_hits,agree_robust,disagree_robust";

ErrorStats compareWithReference(const std::vector<double>& dist, const std::vector<Real>& reference,
                                const std::vector<int>& rays) {
  ErrorStats stats;
  std::vector<double> errors;
  errors.reserve(rays.size());
  for (const int i : rays) {
    const bool ref_hit = std::isfinite(static_cast<double>(reference[i]));
    const bool hit = std::isfinite(dist[i]);  // NaN (a beam that could not be cast) is no hit
    if (ref_hit && !hit) ++stats.leaks;
    if (hit && !ref_hit) ++stats.false_hits;
    if (!(hit && ref_hit)) continue;
    const double error = static_cast<double>(std::fabs(static_cast<Real>(dist[i]) - reference[i]));
    errors.push_back(error);
    stats.max_abs_err_m = std::max(stats.max_abs_err_m, error);
    stats.max_ulp = std::max(stats.max_ulp, error / floatUlp(static_cast<double>(reference[i])));
  }
  if (!errors.empty()) {
    // The 99th percentile: the smallest error at least 99% of the beams are within.
    const std::size_t k =
        static_cast<std::size_t>(std::ceil(0.99 * static_cast<double>(errors.size()))) - 1;
    std::nth_element(errors.begin(), errors.begin() + k, errors.end());
    stats.p99_abs_err_m = errors[k];
  }
  return stats;
}

bool agrees(double a, double b) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  // inf - x is inf and NaN compares false: only real agreement passes.
  return (a == kInf && b == kInf) || std::fabs(a - b) <= kAgreementTolerance;
}

Agreement compareWithPeer(const std::vector<double>& dist, const std::vector<double>& peer,
                          const std::vector<int>& rays, const std::vector<char>& comparable) {
  Agreement agreement;
  agreement.disagree = 0;
  for (const int i : rays) {
    if (!comparable.empty() && !comparable[i]) {
      ++agreement.excluded;
    } else if (!agrees(dist[i], peer[i])) {
      ++agreement.disagree;
    }
  }
  const auto compared = static_cast<double>(rays.size() - agreement.excluded);
  agreement.fraction =
      compared > 0 ? 1.0 - static_cast<double>(agreement.disagree) / compared : 1.0;
  return agreement;
}

void writeCsv(const std::string& path, const std::vector<Row>& rows) {
  std::ofstream out = openForWriting(path);
  out << kCsvHeader << "\n";
  for (const Row& r : rows) {
    out << r.workload << "," << r.scene << "," << r.method << "," << r.threads << "," << r.triangles
        << "," << r.rays << "," << format("%.6g", r.ns_per_ray) << ","
        << format("%.6g", 1000.0 / r.ns_per_ray) << "," << format("%.6g", r.errors.max_abs_err_m)
        << "," << format("%.6g", r.errors.p99_abs_err_m) << "," << format("%.6g", r.errors.max_ulp)
        << "," << r.errors.leaks << "," << r.errors.false_hits << ",";
    if (r.agree_robust.available()) {
      out << fractionDown(r.agree_robust.fraction, 8) << "," << r.agree_robust.disagree;
    } else {
      out << ",";
    }
    out << "\n";
  }
  if (!out) throw std::runtime_error("writing " + path + " failed");
}

namespace {

// The loads' table of results.md.
void writeLoadTable(std::ostream& out, const std::vector<LoadRow>& loads) {
  out << "\n## Loading a mesh file\n\n";
  out << "Each scene's soup (at least " << kLoadMinTriangles
      << " triangles) written as one file and loaded as a node's start-up does: ours, the "
         "loader from nothing to the mesh built (its own readers of STL and of plain OBJ and "
         "binary PLY, assimp for anything else, in its importer process; the BVHs on `threads` "
         "threads); peer, assimp reading the file "
         "in this process with the importer's post-processing and Embree building its BVH on "
         "one thread. Wall clock, median of the alternated rounds; vs_peer = the peer's median / "
         "ours (> 1: faster).\n\n";
  if (loads.empty()) {
    out << "No scene run has a soup that large.\n";
    return;
  }
  out << "| scene | format | triangles | file_mb | threads | ours_s | assimp_embree_s | vs_peer "
         "|\n";
  out << "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |\n";
  for (const LoadRow& r : loads) {
    const double ours = median(r.ours_seconds);
    out << "| " << r.scene << " | " << r.format << " | " << r.triangles << " | "
        << format("%.1f", r.file_bytes / 1e6) << " | " << r.threads << " | "
        << format("%.3g", ours) << " | ";
    if (r.peer_seconds.empty()) {
      out << "n/a | n/a |\n";
    } else {
      const double peer = median(r.peer_seconds);
      out << format("%.3g", peer) << " | " << format("%.3g", peer / ours) << " |\n";
    }
  }
}

}  // namespace

void writeMarkdown(const std::string& path, const std::vector<Row>& rows,
                   const std::vector<MemoryRow>& memory, const std::vector<LoadRow>& loads,
                   const std::string& run_info) {
  std::map<std::pair<std::string, std::string>, double> embree;
  for (const Row& r : rows) {
    if (r.method == "embree_default") embree[{r.workload, r.scene}] = r.ns_per_ray;
  }
  std::ofstream out = openForWriting(path);
  out << run_info << "\n";
  out << "| workload | scene | method | threads | triangles | rays | ns_per_ray | mrays_per_s | "
         "max_abs_err_m | p99_abs_err_m | max_ulp | leaks | false_hits | vs_embree | agree_robust "
         "| "
         "disagree_robust |\n";
  out << "| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: "
         "| ---: "
         "| ---: | ---: |\n";
  for (const Row& r : rows) {
    const auto it = embree.find({r.workload, r.scene});
    const std::string vs = it == embree.end() ? "n/a" : format("%.3g", it->second / r.ns_per_ray);
    out << "| " << r.workload << " | " << r.scene << " | " << r.method << " | " << r.threads
        << " | " << r.triangles << " | " << r.rays << " | " << format("%.4g", r.ns_per_ray) << " | "
        << format("%.4g", 1000.0 / r.ns_per_ray) << " | " << format("%.3g", r.errors.max_abs_err_m)
        << " | " << format("%.3g", r.errors.p99_abs_err_m) << " | "
        << format("%.3g", r.errors.max_ulp) << " | " << r.errors.leaks << " | "
        << r.errors.false_hits << " | " << vs << " | ";
    if (r.agree_robust.available()) {
      out << fractionDown(r.agree_robust.fraction, 6) << " | " << r.agree_robust.disagree << " |\n";
    } else {
      out << "n/a | n/a |\n";
    }
  }
  writeMemoryTable(out, memory);
  writeLoadTable(out, loads);
  if (!out) throw std::runtime_error("writing " + path + " failed");
}

std::string runPlot(const std::string& script, const std::vector<std::string>& args) {
  // Debian's interpreter, which has python3-matplotlib, not whichever python3 is first on PATH.
  const char* const python = "/usr/bin/python3";
  if (access(python, X_OK) != 0) return std::string(python) + " is not there";
  if (access(script.c_str(), R_OK) != 0) return "the plot script " + script + " is not there";
  std::vector<char*> argv = {const_cast<char*>(python), const_cast<char*>(script.c_str())};
  for (const std::string& arg : args) argv.push_back(const_cast<char*>(arg.c_str()));
  argv.push_back(nullptr);
  const pid_t pid = fork();
  if (pid < 0) return "fork failed";
  if (pid == 0) {
    execv(python, argv.data());
    _exit(127);
  }
  int status = 0;
  if (waitpid(pid, &status, 0) < 0) return "waitpid failed";
  if (!WIFEXITED(status)) return python + std::string(" ") + script + " was killed";
  if (WEXITSTATUS(status) != 0) {
    return python + std::string(" ") + script + " exited with status " +
           std::to_string(WEXITSTATUS(status)) + " (is python3-matplotlib installed?)";
  }
  return "";
}

}  // namespace bench
}  // namespace laser_raycast
