// For the Caster tests: poses, one-frame scenes, cast configs, and the reference a cast is checked
// against, every beam against every body by brute force (no culling, no BVH, no slicing).
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "laser_raycast/core/caster.h"

namespace laser_raycast_test {

namespace core = laser_raycast::core;

inline constexpr double kInf = std::numeric_limits<double>::infinity();
inline constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

// -------------------------------------------------------------------------------------------------
// Poses

inline Eigen::Isometry3d pose(const Eigen::Vector3d& t,
                              const Eigen::Matrix3d& r = Eigen::Matrix3d::Identity()) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.linear() = r;
  p.translation() = t;
  return p;
}

// A rotation about z with exact zeros and one, so that z is preserved bit for bit.
inline Eigen::Matrix3d yaw(double a) {
  Eigen::Matrix3d r;
  r << std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a), 0, 0, 0, 1;
  return r;
}

inline Eigen::Matrix3d rpy(double roll, double pitch, double yaw_angle) {
  return (Eigen::AngleAxisd(yaw_angle, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

// -------------------------------------------------------------------------------------------------
// Scenes

inline int addBody(core::Scene* scene, core::Shape shape, int frame,
                   const Eigen::Isometry3d& frame_from_body = Eigen::Isometry3d::Identity(),
                   int label = 0) {
  core::Body body;
  body.shape = std::move(shape);
  body.frame = frame;
  body.label = label;
  body.frame_from_body = frame_from_body;
  return scene->addBody(body);
}

inline core::Scene sceneWithFrame(const std::string& frame = "world") {
  core::Scene scene;
  scene.addFrame(frame);
  scene.addLabel("thing");
  return scene;
}

inline core::CastConfig config(bool fast_path, double tmax = 30.0) {
  core::CastConfig c;
  c.planar_fast_path = fast_path;
  c.tmax = tmax;
  return c;
}

inline core::ScanResult cast(const core::Scene& scene, const core::FramePoses& poses,
                             const Eigen::Isometry3d& sensor, const core::ScanPattern& pattern,
                             const core::CastConfig& c) {
  core::Caster caster;
  return caster.cast(scene, poses, sensor, pattern, c);
}

// -------------------------------------------------------------------------------------------------
// The independent reference

struct BeamTruth {
  double t = kInf;
  int body = -1;
  int triangle = -1;
  double second_body_t = kInf;  // nearest hit on any other body
};

// Every beam against every body (no culling, no BVH): triangles with intersectTriangle, primitives
// with intersect(), rays transformed with Eigen's own inverse.
inline std::vector<BeamTruth> bruteForce(const core::Scene& scene, const core::FramePoses& poses,
                                         const Eigen::Isometry3d& world_from_sensor,
                                         const core::ScanPattern& pattern,
                                         const core::CastConfig& c) {
  std::vector<BeamTruth> out(pattern.size());
  const auto& bodies = scene.bodies();
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    const core::Body& body = bodies[b];
    if (!poses.valid[body.frame]) continue;
    const Eigen::Isometry3d body_from_sensor =
        (poses.pose[body.frame] * body.frame_from_body).inverse(Eigen::Isometry) *
        world_from_sensor;
    for (int i = 0; i < pattern.size(); ++i) {
      core::Ray ray;
      ray.origin = body_from_sensor.translation();
      ray.dir = body_from_sensor.linear() * pattern.directions()[i];
      ray.tmin = c.tmin;
      ray.tmax = c.tmax;
      double t = kInf;
      int tri = -1;
      if (const auto* mesh = std::get_if<std::shared_ptr<const core::Mesh>>(&body.shape)) {
        const auto& v = (*mesh)->vertices();
        const auto& ts = (*mesh)->triangles();
        for (std::size_t k = 0; k < ts.size(); ++k) {
          const auto hit = core::intersectTriangle(c.method, ray, v[ts[k][0]], v[ts[k][1]],
                                                   v[ts[k][2]], c.cull_backfaces);
          if (hit && hit->t < t) {
            t = hit->t;
            tri = static_cast<int>(k);
          }
        }
      } else {
        std::optional<core::PrimitiveHit> hit;
        if (const auto* box = std::get_if<core::Box>(&body.shape)) hit = core::intersect(ray, *box);
        if (const auto* cyl = std::get_if<core::Cylinder>(&body.shape))
          hit = core::intersect(ray, *cyl);
        if (const auto* sph = std::get_if<core::Sphere>(&body.shape))
          hit = core::intersect(ray, *sph);
        if (hit) t = hit->t;
      }
      BeamTruth& truth = out[i];
      if (t < truth.t) {
        truth.second_body_t = truth.t;
        truth.t = t;
        truth.body = static_cast<int>(b);
        truth.triangle = tri;
      } else if (t < truth.second_body_t) {
        truth.second_body_t = t;
      }
    }
  }
  return out;
}

inline bool near(double a, double b, double rel) {
  if (std::isinf(a) || std::isinf(b)) return a == b;
  return std::abs(a - b) <= rel * std::max(std::abs(a), std::abs(b));
}

// result against the brute force: same hit/miss, range within rel, same body unless two bodies are
// hit within rel of each other.
inline void expectMatchesTruth(const core::ScanResult& result, const std::vector<BeamTruth>& truth,
                               double rel, const std::string& what) {
  ASSERT_EQ(result.range.size(), truth.size()) << what;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    ASSERT_TRUE(near(result.range[i], truth[i].t, rel))
        << what << " beam " << i << ": " << result.range[i] << " vs " << truth[i].t;
    if (!near(truth[i].t, truth[i].second_body_t, rel)) {
      ASSERT_EQ(result.body[i], truth[i].body) << what << " beam " << i;
    }
  }
}

// How many beams found nothing (a range that is not finite).
inline int misses(const core::ScanResult& r) {
  int n = 0;
  for (const double t : r.range) n += !std::isfinite(t);
  return n;
}

}  // namespace laser_raycast_test
