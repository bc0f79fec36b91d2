#include "cast_path.h"

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
}

void checkPathFlags(const boost::program_options::variables_map& values) {
  const bool sensor = values.count("sensor"), poses = values.count("poses");
  if (sensor && poses) throw ArgError("give --sensor or --poses, not both");
  if (!sensor && !poses) throw ArgError("--sensor (or --poses) is required");
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

}  // namespace tools
}  // namespace laser_raycast
