#include "cast_path.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>

#include "command_line.h"
#include "laser_raycast/loader/kinematics.h"

namespace laser_raycast {
namespace tools {

namespace {

// "a,b,c,d,e,f": six finite numbers into v; false for anything else.
bool parseSix(const std::string& text, double v[6]) {
  std::size_t start = 0;
  for (int k = 0; k < 6; ++k) {
    const std::size_t comma = text.find(',', start);
    if ((k < 5) != (comma != std::string::npos)) return false;
    const std::string item = text.substr(start, k < 5 ? comma - start : std::string::npos);
    char* end = nullptr;
    v[k] = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !std::isfinite(v[k])) return false;
    start = comma + 1;
  }
  return true;
}

// "vx,vy,vz,wx,wy,wz"
Twist parseTwist(const std::string& text) {
  double v[6];
  if (!parseSix(text, v)) {
    throw ArgError("--twist: '" + text + "' is not vx,vy,vz,wx,wy,wz (6 finite numbers)");
  }
  Twist twist;
  twist.linear = Eigen::Vector3d(v[0], v[1], v[2]);
  twist.angular = Eigen::Vector3d(v[3], v[4], v[5]);
  return twist;
}

Sweep parseSweep(const std::string& name) {
  Sweep sweep;
  if (!kSweepNames.parse(name, &sweep)) throw ArgError("--sweep: " + kSweepNames.notOneOf(name));
  return sweep;
}

double parseScanTime(const std::string& text) {
  const double seconds = parseNumber("--scan-time", text);
  if (!(seconds > 0)) throw ArgError("--scan-time: '" + text + "' is not > 0 s");
  return seconds;
}

// The line without the white space around it.
std::string trimmed(const std::string& line) {
  const char* const space = " \t\r\n\f\v";
  const std::size_t first = line.find_first_not_of(space);
  if (first == std::string::npos) return "";
  return line.substr(first, line.find_last_not_of(space) + 1 - first);
}

}  // namespace

void addPathFlags(boost::program_options::options_description_easy_init& add, PathArgs* path) {
  add("sensor",
      single("POSE",
             [path](const std::string& v) {
               Eigen::Isometry3d pose;
               if (!parsePose(v, &pose)) {
                 throw ArgError("--sensor: '" + v +
                                "' is not x,y,z,roll,pitch,yaw (6 finite numbers)");
               }
               path->sensors = {pose};
             }),
      "the sensor pose x,y,z,roll,pitch,yaw (this or --poses is required)");
  add("poses",
      single("FILE",
             [path](const std::string& v) {
               path->sensors = readPoses(v);
               path->pose_column = true;
             }),
      "a scan from each pose of FILE in turn: x,y,z,roll,pitch,yaw a line, '#' a comment");
  add("sweep", single("NAME", [path](const std::string& v) { path->sweep = parseSweep(v); }),
      "instant (default): every beam at once; rotating: azimuth column c at c * angle increment * "
      "S / 2pi s after the first beam, the sensor moving on with --twist");
  add("scan-time",
      single("S", [path](const std::string& v) { path->scan_time = parseScanTime(v); }),
      "one turn of the rotating head, s (> 0; required with --sweep rotating)");
  add("twist",
      single("vx,vy,vz,wx,wy,wz", [path](const std::string& v) { path->twist = parseTwist(v); }),
      "the sensor's constant velocity during a rotating sweep, in the fixed frame: m/s, then "
      "rad/s about the fixed axes (default 0)");
}

void checkPathFlags(const boost::program_options::variables_map& values, const PathArgs& path) {
  const bool sensor = values.count("sensor"), poses = values.count("poses");
  if (sensor && poses) throw ArgError("give --sensor or --poses, not both");
  if (!sensor && !poses) throw ArgError("--sensor (or --poses) is required");
  const bool rotating = path.sweep == Sweep::kRotating;
  for (const char* flag : {"scan-time", "twist"}) {
    if (values.count(flag) && !rotating) {
      throw ArgError(std::string("--") + flag + ": only with --sweep rotating");
    }
  }
  if (rotating && !values.count("scan-time")) {
    throw ArgError("--sweep rotating: give --scan-time S (s, one turn of the head)");
  }
}

void checkSweepTimes(const PathArgs& path, const core::FanSpec& fan) {
  if (path.sweep != Sweep::kRotating) return;
  const double increment = timeIncrement(path, fan.increment());
  if (!(increment > 0)) throw ArgError("--scan-time: too short: every beam's time is 0 s");
  if (!std::isfinite((fan.beamCount() - 1) * increment)) {
    throw ArgError("--scan-time: too long: the last beam's time is not finite");
  }
}

bool parsePose(const std::string& text, Eigen::Isometry3d* pose) {
  double v[6];
  if (!parseSix(text, v)) return false;
  *pose = poseFromXyzRpy(v[0], v[1], v[2], v[3], v[4], v[5]);
  return true;
}

std::vector<Eigen::Isometry3d> readPoses(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ArgError("--poses: cannot read '" + path + "' (" + std::strerror(errno) + ")");
  std::vector<Eigen::Isometry3d> poses;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const std::string text = trimmed(line);
    if (text.empty() || text[0] == '#') continue;
    Eigen::Isometry3d pose;
    if (!parsePose(text, &pose)) {
      throw ArgError("--poses " + path + ":" + std::to_string(number) + ": '" + text +
                     "' is not x,y,z,roll,pitch,yaw (6 finite numbers)");
    }
    poses.push_back(pose);
  }
  if (in.bad()) throw ArgError("--poses: cannot read '" + path + "'");
  if (poses.empty()) {
    throw ArgError("--poses " + path + ": no pose (every line is blank or a comment)");
  }
  return poses;
}

double timeIncrement(const PathArgs& path, double angle_increment) {
  if (path.sweep != Sweep::kRotating) return 0.0;
  return angle_increment * path.scan_time / (2 * M_PI);
}

Eigen::Isometry3d poseAfter(const Eigen::Isometry3d& start, const Twist& twist, double t) {
  const Eigen::Vector3d turn = twist.angular * t;
  const double angle = turn.norm();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = angle > 0
                      ? Eigen::AngleAxisd(angle, turn / angle).toRotationMatrix() * start.linear()
                      : Eigen::Matrix3d(start.linear());
  pose.translation() = start.translation() + twist.linear * t;
  return pose;
}

core::PoseSamples sweepSamples(const PathArgs& path, const Eigen::Isometry3d& start,
                               const core::FramePoses& frames, const core::ScanPattern& pattern) {
  const double increment = timeIncrement(path, pattern.angleIncrement());
  std::vector<double> times;
  for (int c = 0; c < pattern.azimuthCount(); ++c) {
    times.push_back(c * increment);  // as Caster::castSweep reckons a column's time
  }
  return sweepSamplesAt(path, start, frames, times);
}

core::PoseSamples sweepSamplesAt(const PathArgs& path, const Eigen::Isometry3d& start,
                                 const core::FramePoses& frames,
                                 const std::vector<double>& times) {
  core::PoseSamples samples;
  if (times.empty()) return samples;
  const auto [lowest, highest] = std::minmax_element(times.begin(), times.end());
  const double first = *lowest, last = *highest, span = last - first;
  // Evenly from the first beam's time to the last's, at most kSampleStep s and kSampleTurn rad of
  // the twist's turn apart (so that each interval turns far less than the half turn beyond which
  // a slerp would take the other way round).
  constexpr double kSampleStep = 0.01, kSampleTurn = 0.05;
  const double intervals =
      span > 0 ? std::max({1.0, std::ceil(span / kSampleStep),
                           std::ceil(path.twist.angular.norm() * span / kSampleTurn)})
               : 0.0;
  const int count = static_cast<int>(std::min(intervals, 1e6)) + 1;
  for (int k = 0; k < count; ++k) {
    const double t = k + 1 == count ? last : first + span * k / (count - 1);
    samples.times.push_back(t);
    samples.world_from_sensor.push_back(poseAfter(start, path.twist, t));
    samples.frames.push_back(frames);
  }
  return samples;
}

}  // namespace tools
}  // namespace laser_raycast
