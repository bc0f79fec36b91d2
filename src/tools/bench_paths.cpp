#include "bench_paths.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "bench_scene_builder.h"

namespace laser_raycast {
namespace bench {
namespace {

// A robot keeps this far from every surface, so that no beam starts inside or on one.
constexpr double kClearance = 0.2;  // m
constexpr int kClearanceRays = 16;
constexpr int kAttempts = 200;
// A surface this close ahead makes the robot turn away at kAvoidTurnRate, towards the side with
// more room: in a room or an aisle a path of several metres has to.
constexpr double kLookAhead = 1.5;      // m
constexpr double kAvoidTurnRate = 2.0;  // rad/s
constexpr double kSideProbe = 0.6;      // rad off the heading

// How one attempt steers: its heading off the start pose's yaw, then a turn rate of
// amplitude * sin(2 pi t / period + phase).
struct Steering {
  double heading = 0, amplitude = 0, period = 1, phase = 0;
};

// A normal deviate from two uniform ones (Box-Muller), written out so that every platform draws
// the same.
double normal(std::mt19937_64& rng, double sigma) {
  const double u = uniform(rng, 0x1.0p-53, 1.0), v = uniform(rng, 0.0, 1.0);
  return sigma * std::sqrt(-2 * std::log(u)) * std::cos(2 * M_PI * v);
}

// How far the soup is from pose along a level heading, up to max.
double freeDistance(const SensorPose& pose, double heading, const core::Bvh& soup_bvh, double max) {
  SensorPose probe = pose;
  probe.yaw = heading;
  const Eigen::Isometry3d sensor = toIsometry(probe.exact());
  core::Ray ray;
  ray.origin = sensor.translation();
  ray.dir = sensor.linear() * Eigen::Vector3d::UnitX();
  ray.tmin = 0;
  ray.tmax = max;
  const auto hit = soup_bvh.closestHit<core::TriangleMethod::kWatertight>(ray);
  return hit ? hit->t * ray.dir.norm() : max;
}

// The turn rate at pose and time t: the steering's, or away from a surface ahead.
double turnRate(const SensorPose& pose, const Steering& steering, double t,
                const core::Bvh& soup_bvh) {
  if (freeDistance(pose, pose.yaw, soup_bvh, kLookAhead) >= kLookAhead) {
    return steering.amplitude * std::sin(2 * M_PI * t / steering.period + steering.phase);
  }
  const double left = freeDistance(pose, pose.yaw + kSideProbe, soup_bvh, 2 * kLookAhead);
  const double right = freeDistance(pose, pose.yaw - kSideProbe, soup_bvh, 2 * kLookAhead);
  return left >= right ? kAvoidTurnRate : -kAvoidTurnRate;
}

// The poses of a robot driving at kSpeed, steered as given, sampled at kTfRate; each step moves
// along the heading at the step's middle.
std::vector<SensorPose> steer(const SensorPose& start, const Steering& steering, int samples,
                              const core::Bvh& soup_bvh) {
  const double dt = 1 / kTfRate;
  SensorPose pose = start;
  pose.roll = pose.pitch = 0;
  pose.yaw += steering.heading;
  std::vector<SensorPose> path;
  for (int k = 0; k < samples; ++k) {
    path.push_back(pose);
    const double turn = turnRate(pose, steering, (k + 0.5) * dt, soup_bvh);
    const double heading = pose.yaw + 0.5 * turn * dt;
    pose.x += kSpeed * dt * std::cos(heading);
    pose.y += kSpeed * dt * std::sin(heading);
    pose.yaw += turn * dt;
  }
  return path;
}

// Whether a surface is within kClearance of a pose, in its (level) plane: fans of short rays on
// the soup. Samples are 2.5 cm apart, so a path crossing a surface is caught at the samples
// before it.
bool tooClose(const SensorPose& pose, const core::Bvh& soup_bvh) {
  const Eigen::Isometry3d sensor = toIsometry(pose.exact());
  for (int k = 0; k < kClearanceRays; ++k) {
    const double a = 2 * M_PI * k / kClearanceRays;
    core::Ray ray;
    ray.origin = sensor.translation();
    ray.dir = sensor.linear() * Eigen::Vector3d(std::cos(a), std::sin(a), 0);
    ray.tmin = 0;
    ray.tmax = kClearance;
    if (soup_bvh.closestHit<core::TriangleMethod::kWatertight>(ray)) return true;
  }
  return false;
}

bool clear(const std::vector<SensorPose>& path, const core::Bvh& soup_bvh) {
  return std::none_of(path.begin(), path.end(),
                      [&](const SensorPose& pose) { return tooClose(pose, soup_bvh); });
}

}  // namespace

std::vector<SensorPose> drivePath(const std::vector<SensorPose>& starts, const core::Bvh& soup_bvh,
                                  int samples, double tilt_sigma, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  for (int attempt = 0; attempt < kAttempts; ++attempt) {
    // The first attempts drive off along each start pose's yaw (the scenes point it along an
    // aisle or into the open); later ones in any direction.
    const SensorPose& start = starts[attempt % starts.size()];
    Steering steering;
    steering.heading = attempt < static_cast<int>(starts.size()) ? 0.0 : uniform(rng, -M_PI, M_PI);
    steering.amplitude = uniform(rng, 0.2, 1.0) * kMaxTurnRate;
    steering.period = uniform(rng, 4.0, 12.0);
    steering.phase = uniform(rng, 0.0, 2 * M_PI);
    std::vector<SensorPose> path = steer(start, steering, samples, soup_bvh);
    if (!clear(path, soup_bvh)) continue;
    if (tilt_sigma > 0) {
      for (SensorPose& pose : path) {
        pose.roll = normal(rng, tilt_sigma);
        pose.pitch = normal(rng, tilt_sigma);
      }
    }
    return path;
  }
  throw std::runtime_error("no path of " + std::to_string(samples) +
                           " poses keeps clear of the scene from its sensor poses");
}

core::PoseSamples sweepSamples(const std::vector<SensorPose>& path, double start_seconds,
                               double scan_seconds, const core::FramePoses& frame_poses) {
  const double dt = 1 / kTfRate;
  core::PoseSamples samples;
  for (std::size_t k = 0; k < path.size(); ++k) {
    const double t = k * dt - start_seconds;
    if (t < -1.5 * dt || t > scan_seconds + 1.5 * dt) continue;  // a half step for the rounding
    samples.times.push_back(t);
    samples.world_from_sensor.push_back(toIsometry(path[k].exact()));
    samples.frames.push_back(frame_poses);
  }
  if (samples.times.empty()) throw std::runtime_error("a sweep beyond the end of its path");
  return samples;
}

}  // namespace bench
}  // namespace laser_raycast
