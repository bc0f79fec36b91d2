#include "laser_raycast/node/point_cloud.h"

#include <sensor_msgs/PointField.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

namespace laser_raycast {
namespace {

using Layout = CloudPointLayout;

sensor_msgs::PointField field(const char* name, std::uint32_t offset, std::uint8_t datatype) {
  sensor_msgs::PointField f;
  f.name = name;
  f.offset = offset;
  f.datatype = datatype;
  f.count = 1;
  return f;
}

bool hostIsBigEndian() {
  const std::uint16_t one = 1;
  std::uint8_t first;
  std::memcpy(&first, &one, 1);
  return first == 0;
}

struct Point {
  float x, y, z, intensity;
  std::uint16_t ring;
  float time;
};

// memcpy: the data buffer gives no alignment guarantee.
void writePoint(const Point& p, std::uint8_t* out) {
  std::memset(out, 0, Layout::kPointStep);  // the padding too, so equal clouds are equal bytes
  std::memcpy(out + Layout::kX, &p.x, 4);
  std::memcpy(out + Layout::kY, &p.y, 4);
  std::memcpy(out + Layout::kZ, &p.z, 4);
  std::memcpy(out + Layout::kIntensity, &p.intensity, 4);
  std::memcpy(out + Layout::kRing, &p.ring, 2);
  std::memcpy(out + Layout::kTime, &p.time, 4);
}

void checkSizes(const core::ScanPattern& pattern, const core::MeasuredScan& scan,
                const std::vector<double>& column_times) {
  const std::size_t beams = pattern.size();
  std::string problem;
  if (scan.ranges.size() != beams) {
    problem = "the scan has " + std::to_string(scan.ranges.size()) + " ranges";
  } else if (!scan.intensities.empty() && scan.intensities.size() != beams) {
    problem = "the scan has " + std::to_string(scan.intensities.size()) + " intensities";
  } else if (!column_times.empty() &&
             column_times.size() != static_cast<std::size_t>(pattern.azimuthCount())) {
    problem = std::to_string(column_times.size()) + " column times are given";
  } else if (pattern.ringCount() > std::numeric_limits<std::uint16_t>::max() + 1) {
    problem = "ring numbers are uint16";
  } else {
    return;
  }
  throw std::invalid_argument("buildPointCloud: " + problem + " for a pattern of " +
                              std::to_string(pattern.ringCount()) + " rings x " +
                              std::to_string(pattern.azimuthCount()) + " azimuths");
}

}  // namespace

void buildPointCloud(const core::ScanPattern& pattern, const core::MeasuredScan& scan,
                     const std::vector<double>& column_times, const std_msgs::Header& header,
                     const CloudOptions& options, sensor_msgs::PointCloud2* cloud) {
  checkSizes(pattern, scan, column_times);
  const int beams = pattern.size(), azimuths = pattern.azimuthCount();
  int points = beams;
  if (!options.organized) {
    points = 0;
    for (const float r : scan.ranges) points += std::isfinite(r);
  }

  cloud->header = header;
  cloud->height = options.organized ? pattern.ringCount() : 1;
  cloud->width = options.organized ? azimuths : points;
  cloud->fields = {field("x", Layout::kX, sensor_msgs::PointField::FLOAT32),
                   field("y", Layout::kY, sensor_msgs::PointField::FLOAT32),
                   field("z", Layout::kZ, sensor_msgs::PointField::FLOAT32),
                   field("intensity", Layout::kIntensity, sensor_msgs::PointField::FLOAT32),
                   field("ring", Layout::kRing, sensor_msgs::PointField::UINT16),
                   field("time", Layout::kTime, sensor_msgs::PointField::FLOAT32)};
  cloud->is_bigendian = hostIsBigEndian();
  cloud->point_step = Layout::kPointStep;
  cloud->row_step = cloud->width * Layout::kPointStep;
  cloud->data.resize(static_cast<std::size_t>(points) * Layout::kPointStep);

  constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
  bool all_valid = true;
  std::uint8_t* out = cloud->data.data();
  for (int b = 0; b < beams; ++b) {
    const float range = scan.ranges[b];
    const bool valid = std::isfinite(range);
    all_valid = all_valid && valid;
    if (!valid && !options.organized) continue;
    const int column = b % azimuths;
    Point p;
    p.ring = static_cast<std::uint16_t>(b / azimuths);
    p.time = column_times.empty() ? 0.0f : static_cast<float>(column_times[column]);
    if (valid) {
      const Eigen::Vector3d xyz = pattern.directions()[b] * static_cast<double>(range);
      p.x = static_cast<float>(xyz.x());
      p.y = static_cast<float>(xyz.y());
      p.z = static_cast<float>(xyz.z());
      p.intensity = scan.intensities.empty() ? 0.0f : scan.intensities[b];
    } else {
      p.x = p.y = p.z = p.intensity = kNan;
    }
    writePoint(p, out);
    out += Layout::kPointStep;
  }
  cloud->is_dense = !options.organized || all_valid;
}

std::vector<double> rotatingColumnTimes(int azimuths, double time_increment) {
  std::vector<double> times(azimuths);
  for (int c = 0; c < azimuths; ++c) times[c] = c * time_increment;
  return times;
}

}  // namespace laser_raycast
