#include "beams/beam_list_grid.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <utility>

namespace laser_raycast {
namespace core {
namespace {

// angle wrapped into (-pi, pi].
double wrapHalfTurn(double angle) {
  const double a = std::remainder(angle, 2 * M_PI);
  return a <= -M_PI ? a + 2 * M_PI : a;
}

// How many beams a column holds: the list up to the first line that comes again (0 if none does).
int columnHeight(const std::vector<int>& lines) {
  for (std::size_t i = 1; i < lines.size(); ++i) {
    if (std::find(lines.begin(), lines.begin() + i, lines[i]) != lines.begin() + i) {
      return static_cast<int>(i);
    }
  }
  return 0;
}

// Whether every column holds the first column's lines in its order, from one origin.
bool sameColumns(const BeamList& beams, int height, int columns) {
  for (int c = 1; c < columns; ++c) {
    for (int p = 0; p < height; ++p) {
      if (beams.lines[c * height + p] != beams.lines[p]) return false;
    }
  }
  if (beams.origins.empty()) return true;
  for (int c = 0; c < columns; ++c) {
    for (int p = 1; p < height; ++p) {
      if (beams.origins[c * height + p] != beams.origins[c * height]) return false;
    }
  }
  return true;
}

// Each line's first azimuth and elevations, and the mean step of the lines' azimuths (unwrapped
// along their columns) from one column to the next.
struct Lines {
  std::vector<double> start, elevation_lo, elevation_hi;
  double step = 0;
};
Lines measureLines(const BeamList& beams, int height, int columns) {
  auto azimuth = [&](int i) {
    return std::atan2(beams.directions[i].y(), beams.directions[i].x());
  };
  Lines out;
  out.start.resize(height);
  out.elevation_lo.assign(height, M_PI);
  out.elevation_hi.assign(height, -M_PI);
  for (int p = 0; p < height; ++p) {
    double u = out.start[p] = azimuth(p), previous = u;
    for (int c = 0; c < columns; ++c) {
      const int i = c * height + p;
      const double e = std::asin(std::max(-1.0, std::min(1.0, beams.directions[i].z())));
      out.elevation_lo[p] = std::min(out.elevation_lo[p], e);
      out.elevation_hi[p] = std::max(out.elevation_hi[p], e);
      if (c == 0) continue;
      const double a = azimuth(i);
      u += wrapHalfTurn(a - previous);
      previous = a;
    }
    out.step += (u - out.start[p]) / (columns - 1) / height;
  }
  return out;
}

// A necessary condition, cheaper than measuring every line (a pattern file's lines, which wander in
// elevation, fail it at once): along a grid's line the elevation stays within a turn (at most
// kMaxTurnIncrements steps) of its row's, so its z, which changes no faster, spreads over at most
// twice that. The step here is line 0's mean advance; a grid's other lines advance as much to
// within two turns over the columns, a few percent from 16 columns on, far inside the margin of
// 1.5 (shorter lists are left to the full measure).
bool linesMayKeepTheirElevations(const BeamList& beams, int height, int columns) {
  if (columns < 16) return true;
  auto azimuth = [&](int i) {
    return std::atan2(beams.directions[i].y(), beams.directions[i].x());
  };
  double advance = 0, previous = azimuth(0);
  for (int c = 1; c < columns; ++c) {
    const double a = azimuth(c * height);
    advance += wrapHalfTurn(a - previous);
    previous = a;
  }
  const double limit = 2 * kMaxTurnIncrements * 1.5 * std::abs(advance) / (columns - 1) + 1e-9;
  for (int p = 0; p < height; ++p) {
    double lo = beams.directions[p].z(), hi = lo;
    for (int c = 1; c < columns; ++c) {
      const double z = beams.directions[c * height + p].z();
      lo = std::min(lo, z);
      hi = std::max(hi, z);
    }
    if (hi - lo > limit) return false;
  }
  return true;
}

}  // namespace

ScanPattern cullingGrid(const FanSpec& fan, std::vector<double> elevations) {
  if (elevations.size() == 1 && elevations[0] == 0.0) elevations[0] = 1e-9;
  return ScanPattern(fan, std::move(elevations));
}

double farthestTurn(const ScanPattern& culling, const std::vector<Eigen::Vector3d>& directions) {
  return farthestTurn(culling.directions(), directions);
}

double farthestTurn(const std::vector<Eigen::Vector3d>& from,
                    const std::vector<Eigen::Vector3d>& directions) {
  double chord = 0;  // the longest: the arcsine grows with it
  for (std::size_t k = 0; k < directions.size(); ++k) {
    chord = std::max(chord, (directions[k] - from[k]).norm());
  }
  const double turn = 2 * std::asin(std::min(1.0, chord / 2));
  // Widened for the rounding of the chord and its arcsine (a few ulps of the turn).
  return turn * (1 + 1e-9) + 1e-15;
}

std::optional<BeamListGrid> fitBeamGrid(const BeamList& beams) {
  if (beams.lines.size() != beams.directions.size()) return std::nullopt;
  const int height = columnHeight(beams.lines);
  if (height == 0 || beams.size() % height != 0) return std::nullopt;
  const int columns = beams.size() / height;
  if (columns < 2 || !sameColumns(beams, height, columns) ||
      !linesMayKeepTheirElevations(beams, height, columns)) {
    return std::nullopt;
  }

  auto beam = [&](int p, int c) { return c * height + p; };
  const Lines lines_of = measureLines(beams, height, columns);
  const std::vector<double>& start = lines_of.start;
  const double step = lines_of.step;
  const double increment = std::abs(step);
  if (!(increment > 0) || !std::isfinite(increment)) return std::nullopt;

  // The lines by their azimuth offset from line 0, in parts whose offsets lie within a step.
  std::vector<double> offset(height);
  for (int p = 0; p < height; ++p) offset[p] = wrapHalfTurn(start[p] - start[0]);
  std::vector<int> order(height);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return offset[a] < offset[b]; });
  std::vector<std::vector<int>> part_lines;
  for (int p : order) {
    if (part_lines.empty() || offset[p] - offset[part_lines.back().front()] > increment) {
      part_lines.emplace_back();
    }
    part_lines.back().push_back(p);
  }
  if (static_cast<int>(part_lines.size()) > kMaxParts) return std::nullopt;

  BeamListGrid grid;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  for (int c = 0; c < columns; ++c) {
    const Eigen::Vector3d o = beams.origin(beam(0, c));
    lo = lo.cwiseMin(o);
    hi = hi.cwiseMax(o);
  }
  grid.center = (lo + hi) / 2;
  // Azimuth index j is column c counted in ascending azimuth.
  auto columnOf = [&](int j) { return step > 0 ? j : columns - 1 - j; };
  for (const std::vector<int>& lines : part_lines) {
    const double middle = (offset[lines.front()] + offset[lines.back()]) / 2;
    FanSpec fan;
    fan.angle_min = wrapHalfTurn(start[0] + middle + (step > 0 ? 0.0 : (columns - 1) * step));
    fan.angle_max = fan.angle_min + (columns - 1) * increment;
    fan.samples = columns;
    std::vector<double> elevations;
    for (int p : lines) {
      elevations.push_back((lines_of.elevation_lo[p] + lines_of.elevation_hi[p]) / 2);
    }
    BeamListGrid::Part part{cullingGrid(fan, elevations), {}, {}, {}, 0};
    for (std::size_t q = 0; q < lines.size(); ++q) {
      for (int j = 0; j < columns; ++j) {
        const int i = beam(lines[q], columnOf(j));
        part.directions.push_back(beams.directions[i]);
        part.beam.push_back(i);
      }
    }
    part.turn = farthestTurn(part.culling, part.directions);
    if (!(part.turn <= kMaxTurnIncrements * increment)) return std::nullopt;
    for (int j = 0; j < columns; ++j) {
      part.column_origin.push_back(beams.origin(beam(0, columnOf(j))) - grid.center);
    }
    grid.parts.push_back(std::move(part));
  }
  return grid;
}

}  // namespace core
}  // namespace laser_raycast
