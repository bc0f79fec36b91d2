// Beams off any grid from one origin (a pattern file's: a Livox rosette, a solid-state scanner's
// points), gathered into the cells of an angular grid over their directions, so that
// Caster::castBeams can cast them through the grid's walks instead of one ray at a time.
//
// The grid's columns step in azimuth over the arc the beams cover and its rows in elevation, one
// cell for about every beam. Each beam belongs to the cell whose direction is nearest in azimuth
// and elevation; a cell holds any number of beams, none included. The cells are cast as a bundle
// (beam_set.h) whose grid beam stands for its cell's beams, each tested as its own ray, with the
// windows widened by how far any beam lies from its cell's direction (turn); a cell without beams
// is never open. So each range is the one the beam's own ray gives, and the grid's culling and
// column raster find the triangles.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "laser_raycast/core/beam_list.h"
#include "laser_raycast/core/scan_pattern.h"

namespace laser_raycast {
namespace core {

struct BeamCells {
  ScanPattern culling;  // the cells as a grid; cell i is culling's beam i
  // Cell i's beams are sub-rays first[i] to first[i + 1] - 1: their directions (the list's) and
  // their indices in the list.
  std::vector<int> first;
  std::vector<Eigen::Vector3d> directions;
  std::vector<int> beam;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // where every beam leaves from
  double turn = 0;  // rad: no beam's direction is farther from its cell's
};

// The cells of beams, if they pay: at least kMinCellBeams beams, all from one origin, none
// steeper than the column raster takes (BeamGrid::kMaxColumnRasterElevation); else nullopt, and
// the list is cast one ray at a time. beams must be valid (BeamList::validate).
std::optional<BeamCells> fitBeamCells(const BeamList& beams);

inline constexpr int kMinCellBeams = 256;

}  // namespace core
}  // namespace laser_raycast
