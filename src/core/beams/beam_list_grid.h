// A beam list that lies on grids: the beams of a calibrated spinning lidar (a Velodyne's lasers at
// their firing times, an Ouster's columns), found in the list itself, so that Caster::castBeams can
// cast them through the grid's walks instead of one ray at a time.
//
// Such a list is a sequence of columns (a firing sequence, an encoder column), each holding every
// laser line once, in the same order, from one origin. Along a line the azimuth advances by the
// same step from column to column, and a line's elevation stays put; lines differ by an azimuth
// offset of their own (a laser's azimuth correction, its firing delay in the sequence, an Ouster's
// beam azimuth angle). Lines whose offsets lie within a step of each other make one part: a grid
// (ScanPattern) of those lines' elevations at the part's mean offset, whose beam at (row, column)
// stands for the list's beam of that line and column. Each beam is cast as a bundle's one sub-ray
// of its grid beam (beam_set.h): its own direction, from its column's origin (a ColumnMotion of
// translations), with the windows widened by how far any beam of the part lies from its grid
// beam. So each range is the one the beam's own ray gives, and the grid's culling and column
// raster do the work of finding the triangles.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "laser_raycast/core/beam_list.h"
#include "laser_raycast/core/scan_pattern.h"

namespace laser_raycast {
namespace core {

struct BeamListGrid {
  struct Part {
    ScanPattern culling;  // the part's lines as rings, its columns as azimuths (ascending)
    // Each beam of culling (ring-major, as culling's directions) as the list has it: its own
    // direction and its index in the list.
    std::vector<Eigen::Vector3d> directions;
    std::vector<int> beam;
    // By culling azimuth index: where that column's beams leave from, relative to center.
    std::vector<Eigen::Vector3d> column_origin;
    double turn = 0;  // rad: no beam's direction is farther from its grid beam's
  };
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // the middle of the columns' origins
  std::vector<Part> parts;
};

// The grids of beams, if it lies on some (above) closely enough to pay: every beam within
// kMaxTurnIncrements azimuth steps of its grid beam and at most kMaxParts parts; else nullopt,
// and the list is cast one ray at a time. beams must be valid (BeamList::validate).
std::optional<BeamListGrid> fitBeamGrid(const BeamList& beams);

inline constexpr double kMaxTurnIncrements = 1.0;
inline constexpr int kMaxParts = 8;

// A part's grid: fan's azimuths at each of elevations. A single ring at elevation exactly 0 would
// be a planar fan, which the walks cast in 2D: it is raised by 1e-9 rad (the grid only culls; the
// beams keep their own directions, and the turn covers the difference).
ScanPattern cullingGrid(const FanSpec& fan, std::vector<double> elevations);
// The farthest angle (rad) of directions[k] from culling's k-th direction, widened for the
// rounding of how it is found.
double farthestTurn(const ScanPattern& culling, const std::vector<Eigen::Vector3d>& directions);
// The same from from[k] to directions[k].
double farthestTurn(const std::vector<Eigen::Vector3d>& from,
                    const std::vector<Eigen::Vector3d>& directions);

}  // namespace core
}  // namespace laser_raycast
