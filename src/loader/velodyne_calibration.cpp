#include "laser_raycast/loader/velodyne_calibration.h"

#include <yaml-cpp/yaml.h>

#include <stdexcept>

namespace laser_raycast {
namespace {

double number(const YAML::Node& laser, const char* key, bool required, const std::string& where) {
  const YAML::Node value = laser[key];
  if (!value) {
    if (required) throw std::invalid_argument(where + ": no " + key);
    return 0.0;
  }
  try {
    return value.as<double>();
  } catch (const YAML::Exception&) {
    throw std::invalid_argument(where + ": " + key + " is not a number");
  }
}

}  // namespace

core::VelodyneHead loadVelodyneCalibration(const std::string& path) {
  const std::string name = "velodyne calibration " + path;
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument(name + ": " + e.what());
  }
  const YAML::Node lasers = root["lasers"];
  if (!lasers || !lasers.IsSequence() || lasers.size() == 0) {
    throw std::invalid_argument(name + ": no `lasers` list");
  }
  core::VelodyneHead head;
  for (std::size_t i = 0; i < lasers.size(); ++i) {
    const std::string where = name + ": lasers[" + std::to_string(i) + "]";
    if (!lasers[i].IsMap()) throw std::invalid_argument(where + " is not a map");
    core::VelodyneLaser l;
    const double id = number(lasers[i], "laser_id", true, where);
    l.id = static_cast<int>(id);
    if (id != l.id) throw std::invalid_argument(where + ": laser_id is not an integer");
    l.elevation = number(lasers[i], "vert_correction", true, where);
    l.rot_correction = number(lasers[i], "rot_correction", false, where);
    l.vert_offset = number(lasers[i], "vert_offset_correction", false, where);
    l.horiz_offset = number(lasers[i], "horiz_offset_correction", false, where);
    head.lasers.push_back(l);
  }
  if (lasers.size() == 16) {
    head.timing = core::kVlp16Timing;
  } else if (lasers.size() == 32) {
    head.timing = core::kHdl32eTiming;
  } else {
    throw std::invalid_argument(name + ": " + std::to_string(lasers.size()) +
                                " lasers; the firing times are known for 16 (VLP-16) and 32 "
                                "(HDL-32E)");
  }
  try {
    head.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ": " + e.what());
  }
  return head;
}

}  // namespace laser_raycast
