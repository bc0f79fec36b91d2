// The caster's results on a fixed set of scenes, held against a record of them
// (test/data/recorded_ranges.txt): per case a hash of every beam's range, body and triangle bits (and
// the normal and incidence where computed), the beam count and the hit count. A change that only
// moves, renames or reorganises the core must leave every hash as it was; a change meant to alter
// results must say so and record them anew:
//
//   LASER_RAYCAST_RECORD_RANGES=/path/to/recorded_ranges.txt devel/lib/laser_raycast/test_recorded_ranges
//
// writes the file from the current build (and the test then compares against what it wrote).
// The cases cover every path of the walk: planar fans (fresh cuts, then kept slices of the same
// plane), tilted fans, rings (traced and rasterised nodes), several threads, a rotating sweep of a
// moving sensor, and incidence; on random scenes of meshes of many components, a sphere mesh, a
// triangle soup, boxes, cylinders and spheres on a fixed and a moving frame.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "cast_reference.h"
#include "fan_specs.h"
#include "random.h"
#include "random_scene.h"
#include "test_geometry.h"

namespace laser_raycast_test {
namespace {

struct Record {
  std::uint64_t hash = 1469598103934665603ull;  // FNV-1a 64 offset basis
  long long beams = 0, hits = 0;

  void add(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) hash = (hash ^ p[i]) * 1099511628211ull;
  }
  void addDouble(double v) {
    if (std::isnan(v)) v = std::numeric_limits<double>::quiet_NaN();  // one NaN pattern
    add(&v, sizeof v);
  }
  void addResult(const core::ScanResult& r) {
    for (std::size_t i = 0; i < r.range.size(); ++i) {
      addDouble(r.range[i]);
      add(&r.body[i], sizeof(int));
      add(&r.triangle[i], sizeof(int));
      if (!r.cos_incidence.empty()) {
        addDouble(r.cos_incidence[i]);
        for (int k = 0; k < 3; ++k) addDouble(r.normal[i][k]);
      }
      hits += std::isfinite(r.range[i]) ? 1 : 0;
    }
    beams += static_cast<long long>(r.range.size());
  }
};

std::string line(const std::string& name, const Record& r) {
  std::ostringstream out;
  out << name << ' ' << std::hex << r.hash << std::dec << ' ' << r.beams << ' ' << r.hits;
  return out.str();
}

core::ScanPattern rings(int count, double lo, double hi, int azimuths) {
  std::vector<double> elevations;
  for (int r = 0; r < count; ++r) elevations.push_back(lo + (hi - lo) * r / (count - 1));
  return core::ScanPattern(fanBySamples(-M_PI, M_PI, azimuths), elevations);
}

// Every case, by name, computed by the current build.
std::map<std::string, Record> computeCases(int* kept_slices) {
  std::map<std::string, Record> out;
  *kept_slices = 0;
  const core::ScanPattern fan360(fanBySamples(-M_PI, M_PI, 720));
  const core::ScanPattern fan270(fanBySamples(-2.35, 2.35, 1081));
  const core::ScanPattern rings16 = rings(16, -0.26, 0.26, 512);
  const core::ScanPattern rings64 = rings(64, -0.39, 0.39, 1024);
  Rng rng(20261126);
  for (int s = 0; s < 4; ++s) {
    const RandomScene rs = randomScene(rng);
    const std::string scene = "scene" + std::to_string(s) + ".";
    // Level fans along a path at one height with one caster: the plane is cut fresh, then kept.
    {
      core::Caster caster;
      const double z = uniform(rng, -0.4, 0.4);
      Record level;
      for (int p = 0; p < 4; ++p) {
        const Eigen::Isometry3d at = pose(
            Eigen::Vector3d(uniform(rng, -8, 8), uniform(rng, -8, 8), z), yaw(uniform(rng, -3, 3)));
        const core::ScanResult& r =
            caster.cast(rs.scene, rs.poses, at, p % 2 ? fan270 : fan360, config(true));
        level.addResult(r);
        *kept_slices += r.stats.kept_slices;
      }
      out[scene + "level_fans"] = level;
    }
    // Tilted fans, every plane new; traced as well (no slicing, no raster).
    Record tilted, traced;
    for (int p = 0; p < 3; ++p) {
      const Eigen::Isometry3d at =
          pose(uniformInBox(rng, Eigen::Vector3d(-8, -8, -0.5), Eigen::Vector3d(8, 8, 0.5)),
               rpy(uniform(rng, -0.2, 0.2), uniform(rng, -0.2, 0.2), uniform(rng, -3, 3)));
      tilted.addResult(cast(rs.scene, rs.poses, at, fan270, config(true)));
      core::CastConfig slow = config(false);
      slow.raster_fast_path = false;
      traced.addResult(cast(rs.scene, rs.poses, at, fan360, slow));
    }
    out[scene + "tilted_fans"] = tilted;
    out[scene + "traced_fans"] = traced;
    // Rings, one thread and two, with incidence on the second.
    Record ring1, ring2;
    for (int p = 0; p < 2; ++p) {
      const Eigen::Isometry3d at =
          pose(uniformInBox(rng, Eigen::Vector3d(-6, -6, -0.3), Eigen::Vector3d(6, 6, 0.3)),
               rpy(uniform(rng, -0.1, 0.1), uniform(rng, -0.1, 0.1), uniform(rng, -3, 3)));
      ring1.addResult(cast(rs.scene, rs.poses, at, p ? rings64 : rings16, config(true)));
      core::CastConfig two = config(true);
      two.threads = 2;
      two.compute_incidence = true;
      ring2.addResult(cast(rs.scene, rs.poses, at, p ? rings16 : rings64, two));
    }
    out[scene + "rings"] = ring1;
    out[scene + "rings_threads_incidence"] = ring2;
    // A rotating sweep of a sensor moving at 1 m/s and turning at 1 rad/s, with the cart moving.
    {
      const int cart = 1;
      core::PoseSamples samples;
      const Eigen::Vector3d start(uniform(rng, -5, 5), uniform(rng, -5, 5), 0.1);
      for (int k = 0; k <= 10; ++k) {
        const double t = 0.01 * k;
        samples.times.push_back(t);
        samples.world_from_sensor.push_back(
            pose(start + Eigen::Vector3d(t, 0.3 * t, 0), rpy(0.02, 0.01, 0.5 + t)));
        core::FramePoses frames = rs.poses;
        frames.pose[cart].translation() += Eigen::Vector3d(0, 0.5 * t, 0);
        samples.frames.push_back(frames);
      }
      core::Caster caster;
      Record sweep;
      sweep.addResult(caster.castSweep(rs.scene, samples, rings16, config(true), 0.1 / 512));
      sweep.addResult(caster.castSweep(rs.scene, samples, fan360, config(true), 0.1 / 720));
      out[scene + "sweeps"] = sweep;
    }
  }
  return out;
}

TEST(RecordedRanges, EveryCaseHasTheBitsItWasRecordedWith) {
  int kept_slices = 0;
  const std::map<std::string, Record> now = computeCases(&kept_slices);
  EXPECT_GT(kept_slices, 0);  // the level fans went through kept slices too
  const std::string path = std::string(LASER_RAYCAST_SOURCE_DIR) + "/test/data/recorded_ranges.txt";
  if (const char* record = std::getenv("LASER_RAYCAST_RECORD_RANGES")) {  // write, then compare
    std::ofstream out(record);
    ASSERT_TRUE(out) << "cannot write " << record;
    out << "# Written by test_recorded_ranges with LASER_RAYCAST_RECORD_RANGES (see that test): "
           "case, hash, beams, hits.\n";
    for (const auto& [name, r] : now) out << line(name, r) << '\n';
  }
  const char* record = std::getenv("LASER_RAYCAST_RECORD_RANGES");
  std::ifstream in(record ? record : path.c_str());
  ASSERT_TRUE(in) << "cannot read " << path;
  std::map<std::string, std::string> recorded;
  for (std::string text; std::getline(in, text);) {
    if (text.empty() || text[0] == '#') continue;
    recorded[text.substr(0, text.find(' '))] = text;
  }
  EXPECT_EQ(recorded.size(), now.size()) << "cases recorded vs computed";
  long long hits = 0;
  for (const auto& [name, r] : now) {
    const auto it = recorded.find(name);
    ASSERT_NE(it, recorded.end()) << "no record of case " << name;
    EXPECT_EQ(it->second, line(name, r)) << "case " << name << ": recorded vs computed";
    hits += r.hits;
  }
  EXPECT_GT(hits, 100000);  // the cases see the scenes, not empty space
}

}  // namespace
}  // namespace laser_raycast_test
