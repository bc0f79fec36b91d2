// cast_scan's path: where its scans are cast from, one --sensor pose or each pose of a --poses
// file in turn, and how the sensor moves during a scan, a rotating sweep at a constant twist
// (--sweep rotating, --scan-time, --twist). See the README's cast_scan section.
#pragma once

#include <Eigen/Geometry>
#include <boost/program_options.hpp>
#include <string>
#include <vector>

#include "laser_raycast/core/enum_names.h"
#include "laser_raycast/core/pose_samples.h"
#include "laser_raycast/core/scan_pattern.h"
#include "laser_raycast/core/scene.h"

namespace laser_raycast {
namespace tools {

// --sweep: when each beam is taken, with the names of the node's ~sweep (whose table is the node
// layer's, which the tools do not use).
enum class Sweep {
  kInstant,   // every beam at once, from the scan's pose
  kRotating,  // azimuth column c at c * time_increment, from the pose the twist has reached then
};
inline const core::EnumNames<Sweep, 2> kSweepNames{{{
    {Sweep::kInstant, "instant"},
    {Sweep::kRotating, "rotating"},
}}};

// A constant velocity in the fixed frame: linear (m/s) and angular (rad/s).
struct Twist {
  Eigen::Vector3d linear = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular = Eigen::Vector3d::Zero();
};

struct PathArgs {
  std::vector<Eigen::Isometry3d>
      sensors;               // --sensor's pose, or --poses' in file order: a scan each
  bool pose_column = false;  // --poses given: the CSV's leading column 'pose'
  Sweep sweep = Sweep::kInstant;
  double scan_time = 0;  // s, one turn of a rotating head (> 0 with kRotating)
  Twist twist;           // the sensor's during a rotating sweep
};

// Adds --sensor, --poses, --sweep, --scan-time and --twist, which store into *path, to the flags
// add() builds.
void addPathFlags(boost::program_options::options_description_easy_init& add, PathArgs* path);

// Exactly one of --sensor and --poses; --scan-time with --sweep rotating, and only with it, as
// --twist. Throws ArgError.
void checkPathFlags(const boost::program_options::variables_map& values, const PathArgs& path);

// A rotating sweep's column times (timeIncrement) finite and ascending over the valid fan: not so
// for a --scan-time too short or too long for doubles. Throws ArgError.
void checkSweepTimes(const PathArgs& path, const core::FanSpec& fan);

// "x,y,z,roll,pitch,yaw" (metres; radians about the fixed X, Y, Z axes, as URDF's rpy): a pose as
// --sensor, --urdf's @POSE and each line of a --poses file give it. False unless the text is six
// finite numbers separated by commas.
bool parsePose(const std::string& text, Eigen::Isometry3d* pose);

// The poses of a --poses file, one a line (x,y,z,roll,pitch,yaw), in file order. White space around
// a line is ignored; blank lines and lines starting with '#' are skipped. Throws ArgError naming
// the file and the number of the first line that is no pose, or naming the file if it cannot be
// read or holds no pose.
std::vector<Eigen::Isometry3d> readPoses(const std::string& path);

// The time between two azimuth columns, as the node's: angle_increment * scan_time / 2π s for a
// rotating sweep, 0 for an instant scan.
double timeIncrement(const PathArgs& path, double angle_increment);

// The pose t s after start, moving with twist: position p0 + v t, orientation exp([w]x t) R0 (the
// turn w t about the fixed frame's axes, applied on the left).
Eigen::Isometry3d poseAfter(const Eigen::Isometry3d& start, const Twist& twist, double t);

// A rotating sweep's poses from start, for the azimuth columns at times c * time_increment: samples
// from the first column's time to the last's, at most 10 ms and 0.05 rad of the twist's turn
// apart, between which the caster interpolates each column's pose as it does TF's samples (for a
// constant twist, the motion itself: linear in position, a slerp at a constant rate about one axis
// in rotation); the frames stay where they are.
core::PoseSamples sweepSamples(const PathArgs& path, const Eigen::Isometry3d& start,
                               const core::FramePoses& frames, const core::ScanPattern& pattern);
// The same over the times of `times` (s, >= 0, any order): the beams of a pattern file or of a
// calibrated head, each cast from the pose at its own time.
core::PoseSamples sweepSamplesAt(const PathArgs& path, const Eigen::Isometry3d& start,
                                 const core::FramePoses& frames,
                                 const std::vector<double>& times);

}  // namespace tools
}  // namespace laser_raycast
