#include "beams/beam_cells.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "beams/beam_grid.h"
#include "beams/beam_list_grid.h"

namespace laser_raycast {
namespace core {
namespace {

// How many cells the grid has for each beam. Only speed depends on it: a cell of more beams tests
// more of them with each triangle its window meets, a grid of more cells walks more windows. On
// the benchmark's rosette (10,000 beams over 70 x 70 degrees; bench --quick, pipeline against
// Embree in the same runs), 1 cell a beam ran at 0.35-1.74 times Embree's speed over the seven
// scenes, 1/2 at 0.42-1.39, 1/4 at 0.45-1.78, 1/8 at 0.38-1.41; along a warehouse aisle (30
// poses) 1/8 to 1/2 cast a scan in 2.8-3.3 ms, 1 in 4.0 ms, 2 in 5.0 ms, 4 in 7.4 ms.
constexpr double kCellsPerBeam = 1.0 / 3;

// The arc of azimuths the beams cover: from `start` (rad) over `width`, the turn less the widest
// gap between two beams' azimuths, found within a bin of kGapBins (a full turn if that gap is
// narrower than `full_below`). The arc holds every azimuth whatever the bins: it starts at a beam
// and ends at one.
struct Arc {
  double start, width;
};
Arc azimuthArc(const std::vector<double>& azimuths, double full_below) {
  constexpr int kGapBins = 4096;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<double> lo(kGapBins, kInf), hi(kGapBins, -kInf);
  for (const double a : azimuths) {
    const int bin = std::clamp(static_cast<int>((a + M_PI) * (kGapBins / (2 * M_PI))), 0,
                               kGapBins - 1);
    lo[bin] = std::min(lo[bin], a);
    hi[bin] = std::max(hi[bin], a);
  }
  // The widest run of empty bins, going round from a bin with beams.
  const int some = static_cast<int>(std::find_if(lo.begin(), lo.end(),
                                                 [](double a) { return a < kInf; }) -
                                    lo.begin());
  int best_first = some, best_run = -1, run = 0;
  for (int k = 1; k <= kGapBins; ++k) {
    const int bin = (some + k) % kGapBins;
    if (lo[bin] == kInf) {
      ++run;
      continue;
    }
    if (run > best_run) {
      best_run = run;
      best_first = bin;
    }
    run = 0;
  }
  // From the first beam after that run round to the last before it.
  const int before = (best_first - best_run - 1 + 2 * kGapBins) % kGapBins;
  const double start = lo[best_first];
  double width = hi[before] - start;
  if (width < 0) width += 2 * M_PI;
  if (2 * M_PI - width < full_below) return Arc{-M_PI, 2 * M_PI};
  return Arc{start, width};
}

// The nearest index of a step of `step` from offset >= 0, clamped to [0, count - 1] (rounding
// half up by truncation: the bins need no libm call).
int nearestStep(double offset, double step, int count) {
  return std::clamp(static_cast<int>(offset / step + 0.5), 0, count - 1);
}

// atan2(y, x) within 5e-7 rad, to bin beams by angle: a beam binned a little off still lies in
// its cell, since a cell's reach (BeamCells::turn) is measured from the directions themselves.
// libm's atan2 and asin were half the cost of fitting the cells, and the fit is made anew for
// every scan of a pattern that does not repeat (a rosette's next points). atan(a) for a in [0, 1]
// is a times a polynomial in a^2 (Chebyshev fit of degree 6, made for this file); the octant
// folds the rest onto it.
double binAtan2(double y, double x) {
  constexpr double c[] = {0.9999993278, -0.3332637452, 0.1987987216, -0.1348040561,
                          0.0837415566, -0.0368986293, 0.0078254829};
  const double ax = std::abs(x), ay = std::abs(y);
  const double hi = std::max(ax, ay), lo = std::min(ax, ay);
  const double a = hi > 0 ? lo / hi : 0.0;
  const double s = a * a;
  double p = c[6];
  for (int k = 5; k >= 0; --k) p = p * s + c[k];
  double angle = a * p;
  if (ay > ax) angle = M_PI_2 - angle;
  if (x < 0) angle = M_PI - angle;
  return y < 0 ? -angle : angle;
}

}  // namespace

std::optional<BeamCells> fitBeamCells(const BeamList& beams) {
  const int n = beams.size();
  if (n < kMinCellBeams) return std::nullopt;
  for (int i = 1; i < n; ++i) {
    if (beams.origin(i) != beams.origin(0)) return std::nullopt;
  }
  std::vector<double> azimuth(n), elevation(n);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d& d = beams.directions[i];
    azimuth[i] = binAtan2(d.y(), d.x());
    elevation[i] = binAtan2(d.z(), std::sqrt(d.x() * d.x() + d.y() * d.y()));
  }
  const auto [lowest, highest] = std::minmax_element(elevation.begin(), elevation.end());
  const double el_lo = *lowest, el_hi = *highest;
  if (std::max(-el_lo, el_hi) > BeamGrid::kMaxColumnRasterElevation) return std::nullopt;
  // Cells about as many as the beams, square in azimuth and elevation (over the beams' arc, and at
  // least a cell high): a first guess of the step from the widest extent, then from the arc.
  const double height = el_hi - el_lo;
  double step = std::sqrt(2 * M_PI * std::max(height, 1e-3) / n);
  const Arc arc = azimuthArc(azimuth, 2 * step);
  step = std::sqrt(arc.width * std::max(height, 1e-3) / (n * kCellsPerBeam));
  const bool full = arc.width == 2 * M_PI;
  const int cols = std::max(2, static_cast<int>(std::ceil(arc.width / step)) + (full ? 0 : 1));
  const int rows = std::max(1, static_cast<int>(std::ceil(height / step)) + 1);
  const double increment = full ? 2 * M_PI / cols : arc.width / (cols - 1);
  FanSpec fan;
  fan.angle_min = arc.start;
  fan.angle_max = arc.start + (cols - 1) * increment;
  fan.samples = cols;
  const double row_step = rows > 1 ? height / (rows - 1) : 1.0;
  std::vector<double> elevations(rows);
  for (int r = 0; r < rows; ++r) elevations[r] = rows > 1 ? el_lo + r * row_step : el_lo;
  elevations.back() = rows > 1 ? el_hi : el_lo;

  BeamCells cells{cullingGrid(fan, elevations), {}, {}, {}, beams.origin(0), 0.0};
  // Each beam's cell, then the cells' lists by counting.
  std::vector<int> cell(n);
  cells.first.assign(cells.culling.size() + 1, 0);
  for (int i = 0; i < n; ++i) {
    double offset = azimuth[i] - arc.start;
    if (offset < 0) offset += 2 * M_PI;
    int col = static_cast<int>(offset / increment + 0.5);
    col = full ? col % cols : std::clamp(col, 0, cols - 1);
    cell[i] = nearestStep(elevation[i] - el_lo, row_step, rows) * cols + col;
    ++cells.first[cell[i] + 1];
  }
  for (std::size_t c = 1; c < cells.first.size(); ++c) cells.first[c] += cells.first[c - 1];
  cells.directions.resize(n);
  cells.beam.resize(n);
  std::vector<int> next(cells.first.begin(), cells.first.end() - 1);
  for (int i = 0; i < n; ++i) {
    const int s = next[cell[i]]++;
    cells.directions[s] = beams.directions[i];
    cells.beam[s] = i;
  }
  // The farthest any beam lies from its cell's direction.
  std::vector<Eigen::Vector3d> grid_directions(n);
  for (std::size_t c = 0; c + 1 < cells.first.size(); ++c) {
    for (int s = cells.first[c]; s < cells.first[c + 1]; ++s) {
      grid_directions[s] = cells.culling.directions()[c];
    }
  }
  cells.turn = farthestTurn(grid_directions, cells.directions);
  return cells;
}

}  // namespace core
}  // namespace laser_raycast
