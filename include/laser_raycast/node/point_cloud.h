// sensor_msgs/PointCloud2 from one encoded scan, as a pure function, in the point layout of a real
// driver (point_layout.h) that lidar SLAM packages read by field name: by default
// velodyne_pointcloud's x y z intensity (float32), ring (uint16) and time (float32, s after
// header.stamp).
#pragma once

#include <sensor_msgs/PointCloud2.h>
#include <std_msgs/Header.h>

#include <vector>

#include "laser_raycast/core/beam_list.h"
#include "laser_raycast/core/measurement_model.h"
#include "laser_raycast/core/scan_pattern.h"
#include "laser_raycast/node/point_layout.h"

namespace laser_raycast {

struct CloudOptions {
  // false: only valid returns (finite ranges, i.e. REP 117's range_min <= r <= range_max) in one
  // row (height 1, is_dense true). true: every beam, height = rings, width = azimuths, row r =
  // ring r (ring 0 lowest, as the pattern orders beams), a beam without a valid return as NaN x, y,
  // z and intensity (its ring and times kept; reflectivity and range 0), is_dense true only if
  // every beam has a return.
  bool organized = false;
  PointLayout layout = PointLayout::kVelodyne;  // the fields, their offsets and types
};

// The cloud of one scan. Beam b of the pattern (ring-major: ring b / azimuthCount(), azimuth
// column b % azimuthCount()) with a valid range r is the point r * direction(b) in the sensor frame
// (computed in double, stored as float), with scan.intensities[b] (0 if scan has none), its ring,
// range r, and time column_times[column] (s after header.stamp; empty: every column at the stamp,
// an instantaneous scan; see rotatingColumnTimes), each in the fields of options.layout that hold
// it (PointValue). Throws std::invalid_argument if scan.ranges, scan.intensities or column_times
// do not match the pattern's size, or the layout cannot hold the scan (pointLayoutLimit).
//
// With last (dual returns, core::ReturnMode::kDual: scan the strongest returns, last the last
// ones, invalid where a beam's last return is its strongest), every point also has a uint8 field
// `return` after the layout's (1 the strongest, 2 the last; point_step one byte longer), and each
// beam's last return follows its strongest as a point of its own; organized, a row is 2 x
// azimuths wide, beam column c's strongest return at 2c and its last at 2c + 1 (NaN without one).
void buildPointCloud(const core::ScanPattern& pattern, const core::MeasuredScan& scan,
                     const std::vector<double>& column_times, const std_msgs::Header& header,
                     const CloudOptions& options, sensor_msgs::PointCloud2* cloud,
                     const core::MeasuredScan* last = nullptr);

// The name of the dual returns' field (buildPointCloud's last).
inline constexpr const char* kReturnField = "return";

// The cloud of beams off any grid (a calibration's, a metadata file's or a pattern file's,
// core::BeamList): beam b with a valid range r is the point origin(b) + r * direction(b), with its
// line as the ring, its time (s after header.stamp) and r as its range (from its own origin).
// Organized: if lines 0 .. H - 1 each have W beams (a Velodyne calibration's rings, an Ouster's
// beams), H rows of W, row r line r's beams in the list's order (the drivers' images: an Ouster
// column not destaggered); else one row of every beam. Throws std::invalid_argument as
// buildPointCloud.
void buildBeamCloud(const core::BeamList& beams, const core::MeasuredScan& scan,
                    const std_msgs::Header& header, const CloudOptions& options,
                    sensor_msgs::PointCloud2* cloud);

// The times of a rotating scan's columns: column c taken c * time_increment s after the first.
std::vector<double> rotatingColumnTimes(int azimuths, double time_increment);

}  // namespace laser_raycast
