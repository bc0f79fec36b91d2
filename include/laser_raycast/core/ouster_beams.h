// An Ouster OS sensor's beams as ouster-sdk's XYZ look-up table places its points: W measurement
// columns a turn, every row (beam) of a column fired at the column's time; row r of column c leaves
// along the encoder angle 2 pi (1 - c / W) minus the row's azimuth offset, at the row's altitude,
// from the beam origin lidar_origin_to_beam_origin_mm out along the encoder direction, all in the
// lidar frame, then turned and moved into the sensor frame (os_sensor) by lidar_to_sensor.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "laser_raycast/core/beam_list.h"

namespace laser_raycast {
namespace core {

struct OusterHead {
  std::vector<double> altitudes_deg;  // beam_altitude_angles, row 0 first (the top beam)
  std::vector<double> azimuths_deg;   // beam_azimuth_angles: each row's azimuth offset
  // The beam origin in the lidar frame at encoder angle 0, mm: beam_to_lidar_transform's x and z
  // (lidar_origin_to_beam_origin_mm and 0 in files without that transform).
  double beam_origin_x_mm = 0;
  double beam_origin_z_mm = 0;
  // lidar_to_sensor_transform: rotation, and translation in mm (the file's unit).
  Eigen::Matrix4d lidar_to_sensor = Eigen::Matrix4d::Identity();
  int columns = 1024;  // W: measurement columns a turn (lidar_mode "1024x10")
  // column_window: the columns the sensor sends, first to last inclusive (last < first wraps
  // round through W - 1).
  int first_column = 0;
  int last_column = 1023;
  double fps = 10;  // the lidar_mode's frames a second (for the caller to compare with its rate)

  int rows() const { return static_cast<int>(altitudes_deg.size()); }
  // Throws std::invalid_argument naming the problem: no rows, angle lists of different sizes, more
  // than 256 rows, an angle that is not finite, an altitude outside [-90, 90] deg, columns not in
  // [1, 65536], a column window outside [0, W), fps not > 0, a non-finite beam origin, a
  // lidar_to_sensor that is not a rigid motion (rotation orthonormal within 1e-6, determinant 1,
  // last row 0 0 0 1).
  void validate() const;

  // One frame taking scan_time s: the window's columns in turn, column c at
  // ((c - first_column) mod W) * scan_time / W s (every row of a column at its time), its rows in
  // order; lines are the rows (ouster-ros's ring). Directions and origins in the sensor frame, m.
  BeamList scan(double scan_time) const;
};

}  // namespace core
}  // namespace laser_raycast
