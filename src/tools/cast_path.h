// cast_scan's path: where its scans are cast from, one --sensor pose or each pose of a --poses
// file in turn. See the README's cast_scan section.
#pragma once

#include <Eigen/Geometry>
#include <boost/program_options.hpp>
#include <string>
#include <vector>

namespace laser_raycast {
namespace tools {

struct PathArgs {
  std::vector<Eigen::Isometry3d>
      sensors;               // --sensor's pose, or --poses' in file order: a scan each
  bool pose_column = false;  // --poses given: the CSV's leading column 'pose'
};

// Adds --sensor and --poses, which store into *path, to the flags add() builds.
void addPathFlags(boost::program_options::options_description_easy_init& add, PathArgs* path);

// Exactly one of --sensor and --poses. Throws ArgError.
void checkPathFlags(const boost::program_options::variables_map& values);

// "x,y,z,roll,pitch,yaw" (metres; radians about the fixed X, Y, Z axes, as URDF's rpy): a pose as
// --sensor, --urdf's @POSE and each line of a --poses file give it. False unless the text is six
// finite numbers separated by commas.
bool parsePose(const std::string& text, Eigen::Isometry3d* pose);

// The poses of a --poses file, one a line (x,y,z,roll,pitch,yaw), in file order. White space around
// a line is ignored; blank lines and lines starting with '#' are skipped. Throws ArgError naming
// the file and the number of the first line that is no pose, or naming the file if it cannot be
// read or holds no pose.
std::vector<Eigen::Isometry3d> readPoses(const std::string& path);

}  // namespace tools
}  // namespace laser_raycast
