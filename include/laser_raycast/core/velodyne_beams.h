// A calibrated Velodyne head as velodyne_pointcloud places its points: each laser with its own
// elevation, azimuth offset and origin offsets (the calibration YAML's vert_correction,
// rot_correction, vert_offset_correction, horiz_offset_correction), fired one after another at the
// times of the user manual's timing tables while the head turns clockwise (seen from above).
#pragma once

#include <cmath>
#include <vector>

#include "laser_raycast/core/beam_list.h"

namespace laser_raycast {
namespace core {

struct VelodyneLaser {
  int id = 0;                 // laser_id: its place in a firing sequence
  double elevation = 0;       // rad, vert_correction (up positive)
  double rot_correction = 0;  // rad, subtracted from the head's azimuth by the driver
  double vert_offset = 0;     // m, vert_offset_correction
  double horiz_offset = 0;    // m, horiz_offset_correction
};

// The firing timing of a model, from its user manual.
struct VelodyneTiming {
  double laser_period;     // s between two lasers of a sequence
  double sequence_period;  // s from one firing sequence to the next
};
// VLP-16: 2.304 us between lasers, a sequence of 16 every 55.296 us (two sequences a data block).
inline constexpr VelodyneTiming kVlp16Timing{2.304e-6, 55.296e-6};
// HDL-32E: 1.152 us between lasers, a sequence of 32 every 46.08 us.
inline constexpr VelodyneTiming kHdl32eTiming{1.152e-6, 46.08e-6};

struct VelodyneHead {
  std::vector<VelodyneLaser> lasers;  // by laser id, 0 .. n - 1
  VelodyneTiming timing = kVlp16Timing;

  // Throws std::invalid_argument naming the problem: no lasers, ids that are not 0 .. n - 1 (each
  // once), a non-finite value, an elevation outside [-pi/2, pi/2], two lasers at one elevation
  // (their rings would be ambiguous), a timing whose sequence is shorter than its lasers' firings.
  void validate() const;
  // Laser id -> ring: rings numbered by ascending elevation, as velodyne_pointcloud numbers them.
  std::vector<int> rings() const;

  // One turn of the head taking scan_time s: floor(scan_time / sequence_period) firing sequences,
  // sequence s starting at s * sequence_period, laser i of it firing laser_period * i later, each
  // beam at its own time. The head's azimuth (counter-clockwise from x) starts at start_azimuth and
  // decreases by 2 pi over the turn; a laser's beam leaves along head azimuth + rot_correction at
  // its elevation, from the origin its offsets give (the driver's point at distance 0), so that
  // origin + range * direction is the point the driver computes for that range. Lines are rings.
  BeamList scan(double scan_time, double start_azimuth = M_PI) const;
};

// The published per-laser elevations of two models, by laser id (deg): VLP-16 -15, 1, -13, 3, ...
// (user manual, table "laser id and vertical angle"); HDL-32E -30.67, -9.33, -29.33, ... (user
// manual, its table of the same). No azimuth or origin offsets (a nominal head).
VelodyneHead nominalVlp16();
VelodyneHead nominalHdl32e();

}  // namespace core
}  // namespace laser_raycast
