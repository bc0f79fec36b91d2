// An Ouster sensor metadata JSON (what the sensor's get_metadata, ouster-ros and ouster-sdk write)
// in either of its layouts: the legacy flat one (beam_altitude_angles, beam_azimuth_angles,
// lidar_origin_to_beam_origin_mm, lidar_mode, data_format, lidar_to_sensor_transform at the top
// level) or the nested one (beam_intrinsics, lidar_intrinsics, config_params.lidar_mode,
// lidar_data_format, sensor_info, calibration_status). The file is read with yaml-cpp, as JSON is
// YAML; numbers must be JSON numbers, not strings.
#pragma once

#include <string>

#include "laser_raycast/core/ouster_beams.h"

namespace laser_raycast {

// What is read, with the key paths of the nested layout (the legacy keys are the same names at the
// top level, data_format for lidar_data_format):
// - beam_intrinsics.beam_altitude_angles, beam_azimuth_angles (deg, one per row; required);
// - beam_intrinsics.beam_to_lidar_transform (16 numbers, row-major; its x and z translation, mm,
//   are the beam origin), else beam_intrinsics.lidar_origin_to_beam_origin_mm, else the default
//   ouster-sdk assumes from sensor_info.prod_line (OS-0 27.67, OS-1 15.806, OS-2 13.762, other
//   12.163 mm);
// - lidar_intrinsics.lidar_to_sensor_transform (16 numbers, row-major, mm), else ouster-sdk's
//   default (a half turn about z, 36.18 mm up);
// - config_params.lidar_mode ("1024x10": W columns at that many frames a second) and/or
//   lidar_data_format.columns_per_frame (they must agree), lidar_data_format.column_window,
//   lidar_data_format.pixels_per_column (must equal the angle count) and pixel_shift_by_row (a
//   display shift: checked, changes no beam).
// Throws std::invalid_argument naming the file and the key: unreadable JSON, a missing or
// ill-typed key, per-pixel angle arrays (a solid-state sensor's, not read), values
// core::OusterHead::validate refuses.
core::OusterHead loadOusterMetadata(const std::string& path);

}  // namespace laser_raycast
