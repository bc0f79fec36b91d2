#include "laser_raycast/core/ouster_beams.h"

#include <Eigen/Geometry>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace laser_raycast {
namespace core {

void OusterHead::validate() const {
  auto bad = [](const std::string& what) {
    throw std::invalid_argument("ouster metadata: " + what);
  };
  if (altitudes_deg.empty()) bad("no beams (beam_altitude_angles is empty)");
  if (azimuths_deg.size() != altitudes_deg.size()) {
    bad(std::to_string(altitudes_deg.size()) + " beam_altitude_angles but " +
        std::to_string(azimuths_deg.size()) + " beam_azimuth_angles");
  }
  if (altitudes_deg.size() > 256) {
    bad(std::to_string(altitudes_deg.size()) + " beams, more than 256");
  }
  for (std::size_t r = 0; r < altitudes_deg.size(); ++r) {
    // Written so that NaN fails too.
    if (!(std::abs(altitudes_deg[r]) <= 90)) {
      std::ostringstream msg;
      msg << "beam_altitude_angles[" << r << "] " << altitudes_deg[r]
          << " deg is outside [-90, 90]";
      bad(msg.str());
    }
    if (!std::isfinite(azimuths_deg[r])) {
      bad("beam_azimuth_angles[" + std::to_string(r) + "] is not finite");
    }
  }
  if (columns < 1 || columns > 65536) {
    bad("columns_per_frame " + std::to_string(columns) + " is not in [1, 65536]");
  }
  if (first_column < 0 || first_column >= columns || last_column < 0 || last_column >= columns) {
    bad("column_window [" + std::to_string(first_column) + ", " + std::to_string(last_column) +
        "] is not within [0, " + std::to_string(columns - 1) + "]");
  }
  if (!(std::isfinite(fps) && fps > 0)) {
    std::ostringstream msg;
    msg << "fps " << fps << " is not > 0";
    bad(msg.str());
  }
  if (!std::isfinite(beam_origin_x_mm) || !std::isfinite(beam_origin_z_mm)) {
    bad("the beam origin (lidar_origin_to_beam_origin_mm) is not finite");
  }
  const Eigen::Matrix3d rotation = lidar_to_sensor.topLeftCorner<3, 3>();
  const bool rigid =
      lidar_to_sensor.allFinite() &&
      (rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <=
          1e-6 &&
      std::abs(rotation.determinant() - 1) <= 1e-6 &&
      lidar_to_sensor.row(3) == Eigen::RowVector4d(0, 0, 0, 1);
  if (!rigid) bad("lidar_to_sensor_transform is not a rotation and a translation");
}

BeamList OusterHead::scan(double scan_time) const {
  validate();
  constexpr double kDeg = M_PI / 180;
  // The file's rotation is orthonormal to 1e-6: make it exactly so, that directions stay unit.
  const Eigen::Matrix3d rotation =
      Eigen::Quaterniond(Eigen::Matrix3d(lidar_to_sensor.topLeftCorner<3, 3>()))
          .normalized()
          .toRotationMatrix();
  const Eigen::Vector3d translation_mm = lidar_to_sensor.topRightCorner<3, 1>();
  const int window = (last_column - first_column + columns) % columns + 1;
  const int h = rows();
  BeamList beams;
  const std::size_t n = static_cast<std::size_t>(window) * h;
  beams.directions.reserve(n);
  beams.origins.reserve(n);
  beams.times.reserve(n);
  beams.lines.reserve(n);
  for (int k = 0; k < window; ++k) {
    const int c = (first_column + k) % columns;
    const double t = k * scan_time / columns;
    // The encoder angle: the head turns clockwise seen from above (from the lidar frame's +x at
    // column 0), a full turn over the W columns.
    const double encoder = 2 * M_PI * (1 - static_cast<double>(c) / columns);
    const Eigen::Vector3d origin_mm(beam_origin_x_mm * std::cos(encoder),
                                    beam_origin_x_mm * std::sin(encoder), beam_origin_z_mm);
    const Eigen::Vector3d origin = (rotation * origin_mm + translation_mm) / 1000;
    for (int r = 0; r < h; ++r) {
      // A positive azimuth offset points the beam clockwise of the encoder angle.
      const double azimuth = encoder - azimuths_deg[r] * kDeg;
      const double altitude = altitudes_deg[r] * kDeg;
      const Eigen::Vector3d lidar_dir(std::cos(azimuth) * std::cos(altitude),
                                      std::sin(azimuth) * std::cos(altitude), std::sin(altitude));
      beams.directions.push_back(rotation * lidar_dir);
      beams.origins.push_back(origin);
      beams.times.push_back(t);
      beams.lines.push_back(r);
    }
  }
  return beams;
}

}  // namespace core
}  // namespace laser_raycast
