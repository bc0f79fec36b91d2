// A Velodyne calibration YAML as velodyne_pointcloud reads it (its params/*.yaml): `lasers:`, each
// with laser_id, vert_correction and rot_correction (rad), vert_offset_correction and
// horiz_offset_correction (m), and the corrections of range and intensity, which change neither a
// beam's direction nor its origin and are read past. The firing timing follows the laser count:
// 16 lasers fire as a VLP-16, 32 as an HDL-32E.
#pragma once

#include <string>

#include "laser_raycast/core/velodyne_beams.h"

namespace laser_raycast {

// Throws std::invalid_argument naming the file and the problem: unreadable YAML, no `lasers`
// list, a laser without laser_id or vert_correction, a value that is not a number, a laser count
// other than 16 or 32, or what core::VelodyneHead::validate refuses.
core::VelodyneHead loadVelodyneCalibration(const std::string& path);

}  // namespace laser_raycast
