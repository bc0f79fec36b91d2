// Moving sensors for the benchmark's headline workloads: a robot driving a smooth path through a
// scene, its pose sampled as TF publishes it, and the rotating sweeps of a sensor it carries.
// Every path is deterministic (seeded) and never one pose repeated: each sample is a few
// centimetres on from the last and turned a little.
#pragma once

#include <cstdint>
#include <vector>

#include "bench_scenes.h"
#include "laser_raycast/core/bvh.h"
#include "laser_raycast/core/pose_samples.h"

namespace laser_raycast {
namespace bench {

// How the robot drives: 1 m/s, its turn rate a slow sine of up to 0.5 rad/s (2 rad/s away from a
// surface less than 1.5 m ahead), its pose published at 40 Hz (2.5 cm apart).
constexpr double kTfRate = 40;        // Hz
constexpr double kSpeed = 1.0;        // m/s
constexpr double kMaxTurnRate = 0.5;  // rad/s

// `samples` poses of a path, one every 1 / kTfRate s, from the position and height of one of the
// starts (the first from which one is found; in its base frame, level in it), that keeps clear of
// every triangle of the soup (soup_bvh is built over it). With tilt_sigma > 0 each pose gets its
// own roll and pitch ~ N(0, tilt_sigma) rad, as a 3D pose estimate of a legged or outdoor robot
// has: every scan plane is new. Throws std::runtime_error if no clear path is found.
std::vector<SensorPose> drivePath(const std::vector<SensorPose>& starts, const core::Bvh& soup_bvh,
                                  int samples, double tilt_sigma, std::uint64_t seed);

// The TF samples a rotating scan of scan_seconds starting at start_seconds on the path is cast
// from: those from one before it starts to one after it ends, their times relative to its start;
// every frame at frame_poses (the scenes are static).
core::PoseSamples sweepSamples(const std::vector<SensorPose>& path, double start_seconds,
                               double scan_seconds, const core::FramePoses& frame_poses);

}  // namespace bench
}  // namespace laser_raycast
