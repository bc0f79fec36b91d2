#include "bench_run.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <limits>
#include <memory>
#include <numeric>
#include <set>
#include <sstream>
#include <string>
#include <variant>

#include "bench_peers.h"
#include "bench_reference.h"

namespace laser_raycast {
namespace bench {
namespace {

// The references a workload's rows are measured against.
struct References {
  std::vector<Real> soup;      // the soup, on the rays the soup methods are given
  std::vector<Real> pipeline;  // the bodies, on the exact beams (pose and fan in long double)
  // The bodies on the pipeline's own double inputs: its error without the rounding of its inputs.
  std::vector<Real> pipeline_inputs;
  // Per beam, whether the soup and the bodies both hit or both miss: not where a beam grazes a
  // primitive whose facets in the soup it passes (or hits) while the analytic surface is hit (or
  // passed). The pipeline's agreement with a soup peer is counted on these beams only.
  std::vector<char> same_hit;
};

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

// The pipeline's beams as it holds them: the double sensor poses (a sweep's column poses) and the
// double directions of core::ScanPattern, composed in long double.
std::vector<RayL> pipelineInputRays(const WorkloadRays& w) {
  std::vector<RayL> out;
  const auto& directions = w.directions();
  for (std::size_t scan = 0; scan < w.scans(); ++scan) {
    for (int b = 0; b < w.beamCount(); ++b) {
      const Eigen::Isometry3d& sensor = w.sensors[w.poseIndex(scan, b)];
      RayL ray;
      ray.origin = sensor.linear().cast<Real>() * w.origin(b).cast<Real>() +
                   sensor.translation().cast<Real>();
      ray.dir = sensor.linear().cast<Real>() * directions[b].cast<Real>();
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

References computeReferences(const BenchScene& scene, const SceneGeometry& geometry,
                             const Workload& workload, const WorkloadRays& rays) {
  const auto start = std::chrono::steady_clock::now();
  References refs;
  const std::vector<RayL> exact = exactRays(rays.rays);
  refs.soup = referenceSoup(geometry.bvh, exact);
  // A pattern file's beams: its directions as the pipeline holds them (double), there being no
  // angles to recompute them from in long double.
  refs.pipeline = referenceBodies(
      scene, rays.offGrid() ? pipelineInputRays(rays)
                            : pipelineRays(rays.poses, workload.fan, workload.elevations, rays.tmax,
                                           !rays.sweeps.empty()));
  std::cerr << "  " << workload.name << ": " << rays.rays.size() << " rays from " << rays.scans()
            << (rays.sweeps.empty() ? " poses" : " rotating scans") << "; the reference hits "
            << countHits(refs.soup) << " (soup) and " << countHits(refs.pipeline)
            << " (pipeline), computed in " << secondsSince(start) << " s\n";
  refs.pipeline_inputs = referenceBodies(scene, pipelineInputRays(rays));
  refs.same_hit.resize(rays.rays.size());
  for (std::size_t i = 0; i < refs.same_hit.size(); ++i) {
    refs.same_hit[i] = std::isfinite(static_cast<double>(refs.soup[i])) ==
                       std::isfinite(static_cast<double>(refs.pipeline[i]));
  }
  if (scene.name == "box_room") {
    crossCheckReference(workload.name, refs.soup, referenceBodies(scene, exact));
  }
  return refs;
}

// A row whose distances are measured and whose timing may still be to come.
struct Measured {
  const Method* method;
  const std::vector<int>* rays;  // the indices it casts
  int per_batch;                 // passes per timed batch
  std::vector<double> seconds;   // per pass: one batch median, or one per round if paired
  std::string log;               // what it measured, for stderr
};

// The pipeline's distances carried over to the soup's geometry, to compare them with a soup peer's:
// where both references hit, minus their difference (on meshes 0 up to the rounding of the
// vertices; on a primitive, how far along the beam its facets are from its surface).
std::vector<double> onSoupGeometry(const std::vector<double>& dist, const References& refs,
                                   const std::vector<int>& used) {
  std::vector<double> moved = dist;
  for (const int i : used) {
    if (std::isfinite(static_cast<double>(refs.soup[i] + refs.pipeline[i]))) {
      moved[i] = static_cast<double>(dist[i] - (refs.pipeline[i] - refs.soup[i]));
    }
  }
  return moved;
}

// How many of the disagreeing beams are the peer's error: where it is off its own reference.
long peerErrors(const std::vector<double>& compared, const std::vector<double>& robust,
                const std::vector<int>& used, const std::vector<char>& comparable,
                const std::vector<Real>& peer_reference) {
  long count = 0;
  for (const int i : used) {
    if (!comparable.empty() && !comparable[i]) continue;
    count += !agrees(compared[i], robust[i]) &&
             !agrees(robust[i], static_cast<double>(peer_reference[i]));
  }
  return count;
}

// The row of one method from its distances, and the log line's accuracy part.
Row measureRow(const Method& method, const std::vector<double>& dist, const std::vector<int>& used,
               const References& refs, const std::vector<double>& robust, std::string* log) {
  Row row;
  row.method = method.name;
  row.threads = method.threads;
  row.triangles = method.triangles;
  row.rays = used.size();
  row.errors = compareWithReference(dist, method.pipeline ? refs.pipeline : refs.soup, used);
  std::ostringstream text;
  text << ", max error " << row.errors.max_abs_err_m << " m, " << row.errors.leaks << " leaks, "
       << row.errors.false_hits << " false hits";
  if (method.pipeline) {
    const ErrorStats arithmetic = compareWithReference(dist, refs.pipeline_inputs, used);
    text << " (against its double inputs: max error " << arithmetic.max_abs_err_m << " m, "
         << arithmetic.leaks << " leaks, " << arithmetic.false_hits << " false hits)";
  }
  if (!robust.empty()) {
    const std::vector<double> compared = method.pipeline ? onSoupGeometry(dist, refs, used) : dist;
    const std::vector<char> no_mask;
    const std::vector<char>& comparable = method.pipeline ? refs.same_hit : no_mask;
    row.agree_robust = compareWithPeer(compared, robust, used, comparable);
    text << "; " << row.agree_robust.disagree << " beams disagree with embree_robust ("
         << peerErrors(compared, robust, used, comparable, refs.soup)
         << " where embree_robust is off the reference";
    if (method.pipeline) {
      text << "; " << row.agree_robust.excluded
           << " beams not compared: a primitive's facets and surface differ in hit or miss";
    }
    text << ")";
  }
  *log = text.str();
  return row;
}

}  // namespace

void runWorkload(const Settings& settings, int poses, const BenchScene& scene,
                 const SceneGeometry& geometry, const SceneMethods& methods,
                 const Workload& workload, std::vector<Row>* rows) {
  const WorkloadRays rays = makeRays(scene, geometry.bvh, workload, poses, scene.range_max);
  const References refs = computeReferences(scene, geometry, workload, rays);
  std::vector<int> all(rays.rays.size());
  std::iota(all.begin(), all.end(), 0);
  const std::vector<int> subset =
      bruteSubset(rays.rays.size(), scene.soup.triangles.size(), settings);
  const auto unknown = [&] {
    return std::vector<double>(rays.rays.size(), std::numeric_limits<double>::quiet_NaN());
  };
  std::vector<double> robust;
  if (methods.robust) {
    robust = unknown();
    methods.robust->pass(rays, all, &robust);
  }

  // Every row's distances (and the unpaired rows' times), in order.
  const std::size_t first = rows->size();
  std::vector<Measured> measured;
  for (const Method& method : methods.rows) {
    if (method.planar_only && !rays.planar()) continue;
    if (workload.motion != Motion::kStill && !method.moving) continue;
    const std::vector<int>& used = method.brute ? subset : all;
    std::vector<double> dist = unknown();
    Measured m{&method, &used, 0, {}, {}};
    m.per_batch = firstPass(method.pass, rays, used, &dist, settings.min_batch_seconds);
    rows->push_back(measureRow(method, dist, used, refs, robust, &m.log));
    if (!method.paired) {
      m.seconds.push_back(timeBatches(method.pass, rays, used, m.per_batch, settings.reps));
    }
    measured.push_back(std::move(m));
  }
  // The paired rows in alternating rounds.
  for (int round = 0; round < settings.rounds; ++round) {
    for (Measured& m : measured) {
      if (!m.method->paired) continue;
      m.seconds.push_back(timeBatches(m.method->pass, rays, *m.rays, m.per_batch, settings.reps));
    }
  }

  for (std::size_t k = 0; k < measured.size(); ++k) {
    Row& row = (*rows)[first + k];
    row.workload = workload.name;
    row.scene = scene.name;
    row.range_max = scene.range_max;
    const double ns = 1e9 / static_cast<double>(row.rays);
    row.ns_per_ray = median(measured[k].seconds) * ns;
    std::cerr << "    " << row.method
              << (row.threads == 1 ? "" : " (threads " + std::to_string(row.threads) + ")") << ": "
              << row.ns_per_ray << " ns/ray";
    if (measured[k].method->paired) {
      std::cerr << " (rounds:";
      for (const double s : measured[k].seconds) std::cerr << " " << s * ns;
      std::cerr << ")";
    }
    std::cerr << measured[k].log << "\n";
  }
}

std::optional<MemoryRow> measureMemory(const BenchScene& scene) {
  // Instances share their Mesh, which is held once however many bodies place it.
  std::set<const core::Mesh*> seen;
  MemoryRow memory;
  memory.scene = scene.name;
  // Embree's total, until a mesh has no figure from it (a build without Embree).
  memory.embree_bytes.emplace(0);
  for (const core::Body& body : scene.scene.bodies()) {
    const auto* mesh = std::get_if<std::shared_ptr<const core::Mesh>>(&body.shape);
    if (!mesh || !seen.insert(mesh->get()).second) continue;
    memory.triangles += (*mesh)->triangles().size();
    memory.ours_bytes += (*mesh)->bytes();
    const std::optional<std::size_t> embree = embreeMeshBytes(**mesh);
    if (embree && memory.embree_bytes) {
      *memory.embree_bytes += *embree;
    } else {
      memory.embree_bytes.reset();
    }
  }
  if (seen.empty()) return std::nullopt;
  return memory;
}

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace bench
}  // namespace laser_raycast
