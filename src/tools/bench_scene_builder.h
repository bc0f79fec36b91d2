// What the benchmark's scene builders share: adding bodies to a BenchScene (with their long double
// poses), the deterministic random numbers that scatter objects, and the builders that live in
// files of their own.
#pragma once

#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "bench_meshes.h"
#include "bench_scenes.h"

namespace laser_raycast {
namespace bench {

// Adds bodies on one frame, "world", at the identity.
class SceneBuilder {
 public:
  explicit SceneBuilder(BenchScene* out) : out_(out) { frame_ = out_->scene.addFrame("world"); }

  void add(const core::Shape& shape, const PoseL& pose, const std::string& label) {
    core::Body body;
    body.shape = shape;
    body.frame = frame_;
    body.label = out_->scene.addLabel(label);
    body.frame_from_body = toIsometry(pose);
    out_->scene.addBody(body);
    out_->body_poses.push_back(pose);
  }
  void add(const MeshData& mesh, const PoseL& pose, const std::string& label) {
    add(meshAsRead(mesh), pose, label);
  }

 private:
  BenchScene* out_;
  int frame_;
};

// A deterministic uniform double in [lo, hi): the mapping is written out, unlike
// std::uniform_real_distribution's, so every platform places the same objects.
inline double uniform(std::mt19937_64& rng, double lo, double hi) {
  return lo + (hi - lo) * static_cast<double>(rng() >> 11) * 0x1.0p-53;
}

// from, from + step, ..., to (to a whole number of steps).
inline std::vector<double> steps(double from, double to, double step) {
  std::vector<double> v;
  const int n = static_cast<int>(std::lround((to - from) / step));
  for (int i = 0; i <= n; ++i) v.push_back(from + i * step);
  return v;
}

// The warehouse scene (bench_warehouse.cpp).
void buildWarehouse(BenchScene* s);

}  // namespace bench
}  // namespace laser_raycast
