#include "laser_raycast/loader/ouster_metadata.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <optional>
#include <stdexcept>
#include <vector>

namespace laser_raycast {
namespace {

// The file's keys: where the nested layout keeps each, and what the file calls it in messages.
class Metadata {
 public:
  Metadata(const std::string& path, const YAML::Node& root) : path_(path), root_(root) {
    nested_ = root["beam_intrinsics"].IsDefined();
  }

  bool nested() const { return nested_; }

  // The value under section.key (nested) or key (legacy; legacy_section, when given, is the
  // legacy file's name for the section); an undefined node when absent (never yaml-cpp's invalid
  // node for a missing key, which reset() refuses).
  YAML::Node find(const char* section, const char* key, const char* legacy_section = nullptr,
                  std::string* name = nullptr) const {
    const char* outer = nested_ ? section : legacy_section;
    if (name) *name = outer ? std::string(outer) + "." + key : std::string(key);
    const YAML::Node absent(YAML::NodeType::Undefined);
    const YAML::Node parent = outer ? root_[outer] : root_;
    if (!parent.IsDefined()) return absent;
    if (!parent.IsMap()) fail(outer, "is not an object");
    const YAML::Node value = parent[key];
    return value.IsDefined() ? value : absent;
  }

  [[noreturn]] void fail(const std::string& key, const std::string& what) const {
    throw std::invalid_argument("ouster metadata " + path_ + ": " + key + " " + what);
  }

  // A JSON number: yaml-cpp would read a quoted "1.5" as one too, so a quoted scalar (tag "!") is
  // refused.
  double number(const YAML::Node& node, const std::string& name) const {
    if (!node.IsScalar() || node.Tag() == "!") fail(name, "is not a number");
    try {
      return node.as<double>();
    } catch (const YAML::Exception&) {
      fail(name, "is not a number");
    }
  }

  int integer(const YAML::Node& node, const std::string& name) const {
    const double value = number(node, name);
    if (!(std::abs(value) < 1e9) || value != std::floor(value)) fail(name, "is not an integer");
    return static_cast<int>(value);
  }

  std::vector<double> numbers(const YAML::Node& node, const std::string& name) const {
    if (!node.IsSequence()) fail(name, "is not an array");
    std::vector<double> values;
    for (std::size_t i = 0; i < node.size(); ++i) {
      if (node[i].IsSequence()) {
        fail(name, "holds arrays (per-pixel angles of a solid-state sensor, not read)");
      }
      values.push_back(number(node[i], name + "[" + std::to_string(i) + "]"));
    }
    return values;
  }

  // 16 numbers, row by row.
  Eigen::Matrix4d transform(const YAML::Node& node, const std::string& name) const {
    const std::vector<double> values = numbers(node, name);
    if (values.size() != 16)
      fail(name, "has " + std::to_string(values.size()) + " numbers, not 16");
    Eigen::Matrix4d m;
    for (int i = 0; i < 16; ++i) m(i / 4, i % 4) = values[i];
    return m;
  }

  std::string text(const YAML::Node& node, const std::string& name) const {
    if (!node.IsScalar()) fail(name, "is not a string");
    return node.Scalar();
  }

 private:
  std::string path_;
  YAML::Node root_;
  bool nested_ = false;
};

// ouster-sdk's beam origin for a file that gives none, by product line.
double defaultBeamOriginMm(const std::string& prod_line) {
  if (prod_line.rfind("OS-0-", 0) == 0) return 27.67;
  if (prod_line.rfind("OS-1-", 0) == 0) return 15.806;
  if (prod_line.rfind("OS-2-", 0) == 0) return 13.762;
  return 12.163;  // the first generation's
}

// yaml-cpp's Node::operator= writes into the node a variable refers to: each key is looked up
// into `node` with reset(), which makes the variable refer to another node instead.
void readBeams(const Metadata& m, core::OusterHead* head) {
  std::string name;
  YAML::Node node = m.find("beam_intrinsics", "beam_altitude_angles", nullptr, &name);
  if (!node.IsDefined()) m.fail(name, "is missing");
  head->altitudes_deg = m.numbers(node, name);
  node.reset(m.find("beam_intrinsics", "beam_azimuth_angles", nullptr, &name));
  if (!node.IsDefined()) m.fail(name, "is missing");
  head->azimuths_deg = m.numbers(node, name);

  node.reset(m.find("beam_intrinsics", "beam_to_lidar_transform", nullptr, &name));
  if (node.IsDefined()) {
    const Eigen::Matrix4d beam_to_lidar = m.transform(node, name);
    head->beam_origin_x_mm = beam_to_lidar(0, 3);
    head->beam_origin_z_mm = beam_to_lidar(2, 3);
    return;
  }
  node.reset(m.find("beam_intrinsics", "lidar_origin_to_beam_origin_mm", nullptr, &name));
  if (node.IsDefined()) {
    head->beam_origin_x_mm = m.number(node, name);
    return;
  }
  node.reset(m.find("sensor_info", "prod_line", nullptr, &name));
  head->beam_origin_x_mm = defaultBeamOriginMm(node.IsDefined() ? m.text(node, name) : "");
}

void readFormat(const Metadata& m, core::OusterHead* head) {
  std::string name;
  std::optional<int> mode_columns;
  YAML::Node node = m.find("config_params", "lidar_mode", nullptr, &name);
  if (node.IsDefined()) {
    const std::string mode = m.text(node, name);
    const std::size_t x = mode.find('x');
    try {
      std::size_t end_w = 0, end_f = 0;
      const int w = std::stoi(mode.substr(0, x), &end_w);
      const int f = std::stoi(mode.substr(x + 1), &end_f);
      if (x == std::string::npos || end_w != x || end_f != mode.size() - x - 1 || w < 1 || f < 1) {
        throw std::invalid_argument(mode);
      }
      mode_columns = w;
      head->fps = f;
    } catch (const std::exception&) {
      m.fail(name, "'" + mode + "' is not of the form COLUMNSxFPS (\"1024x10\")");
    }
  }
  const char* format = "lidar_data_format";
  const char* legacy_format = "data_format";
  std::string columns_name;
  node.reset(m.find(format, "columns_per_frame", legacy_format, &columns_name));
  if (node.IsDefined()) {
    head->columns = m.integer(node, columns_name);
    if (mode_columns && *mode_columns != head->columns) {
      m.fail(columns_name, std::to_string(head->columns) + " does not match " + name + " (" +
                               std::to_string(*mode_columns) + " columns)");
    }
  } else if (mode_columns) {
    head->columns = *mode_columns;
  } else {
    m.fail(name, "is missing, and so is " + columns_name + " (the columns a frame)");
  }
  node.reset(m.find(format, "fps", legacy_format, &name));
  if (node.IsDefined()) head->fps = m.number(node, name);
  head->first_column = 0;
  head->last_column = head->columns - 1;
  node.reset(m.find(format, "column_window", legacy_format, &name));
  if (node.IsDefined()) {
    const std::vector<double> window = m.numbers(node, name);
    if (window.size() != 2) m.fail(name, "does not hold two columns");
    head->first_column = m.integer(node[0], name + "[0]");
    head->last_column = m.integer(node[1], name + "[1]");
  }
  const std::size_t rows = head->altitudes_deg.size();
  node.reset(m.find(format, "pixels_per_column", legacy_format, &name));
  if (node.IsDefined() && m.integer(node, name) != static_cast<int>(rows)) {
    m.fail(name, "is not the number of beam_altitude_angles (" + std::to_string(rows) + ")");
  }
  node.reset(m.find(format, "pixel_shift_by_row", legacy_format, &name));
  if (node.IsDefined()) {
    const std::vector<double> shifts = m.numbers(node, name);
    if (shifts.size() != rows) {
      m.fail(name, "has " + std::to_string(shifts.size()) + " rows, not " + std::to_string(rows));
    }
    for (std::size_t r = 0; r < rows; ++r) m.integer(node[r], name + "[" + std::to_string(r) + "]");
  }
}

}  // namespace

core::OusterHead loadOusterMetadata(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument("ouster metadata " + path + ": " + e.what());
  }
  if (!root.IsMap()) throw std::invalid_argument("ouster metadata " + path + ": not an object");
  const Metadata m(path, root);
  core::OusterHead head;
  readBeams(m, &head);
  readFormat(m, &head);
  std::string name;
  const YAML::Node node = m.find("lidar_intrinsics", "lidar_to_sensor_transform", nullptr, &name);
  if (node.IsDefined()) {
    head.lidar_to_sensor = m.transform(node, name);
  } else {
    // ouster-sdk's default: the lidar frame turned half a turn about z, 36.18 mm above the
    // sensor frame's origin.
    head.lidar_to_sensor << -1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1, 36.18, 0, 0, 0, 1;
  }
  try {
    head.validate();
  } catch (const std::invalid_argument& e) {
    // The core's "ouster metadata: ...", with the file named as in the messages above.
    const std::string what = e.what();
    throw std::invalid_argument("ouster metadata " + path + what.substr(what.find(':')));
  }
  return head;
}

}  // namespace laser_raycast
