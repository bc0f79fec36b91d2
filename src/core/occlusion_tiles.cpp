#include "laser_raycast/core/occlusion_tiles.h"

#include <algorithm>

namespace laser_raycast {
namespace core {
namespace {

// max() that lets a NaN through, so that a beam that could not be cast never looks closed.
double openMax(double a, double b) { return a > b || a != a ? a : b; }

}  // namespace

void OcclusionTiles::reset(const std::vector<double>* range, const std::vector<int>* beam_of_row,
                           int rows, int cols) {
  range_ = range;
  beam_of_row_ = beam_of_row;
  rows_ = rows;
  cols_ = cols;
  fine_cols_ = (cols + kFineWidth - 1) / kFineWidth;
  coarse_rows_ = (rows + kCoarseRings - 1) / kCoarseRings;
  coarse_cols_ = (cols + kCoarseWidth - 1) / kCoarseWidth;
  fine_max_.assign(static_cast<std::size_t>(rows_) * fine_cols_, 0.0);
  fine_stale_.assign(fine_max_.size(), 1);
  coarse_max_.assign(static_cast<std::size_t>(coarse_rows_) * coarse_cols_, 0.0);
  coarse_stale_.assign(coarse_max_.size(), 1);
  tile_reads_ = 0;
}

double OcclusionTiles::fineMax(int row, int tile) {
  const std::size_t i = static_cast<std::size_t>(row) * fine_cols_ + tile;
  ++tile_reads_;
  if (fine_stale_[i]) {
    double m = -1;
    const int end = std::min(cols_, (tile + 1) * kFineWidth);
    for (int col = tile * kFineWidth; col < end; ++col) m = openMax(rangeAt(row, col), m);
    fine_max_[i] = m;
    fine_stale_[i] = 0;
  }
  return fine_max_[i];
}

double OcclusionTiles::coarseMax(int tile_row, int tile) {
  const std::size_t i = static_cast<std::size_t>(tile_row) * coarse_cols_ + tile;
  ++tile_reads_;
  if (coarse_stale_[i]) {
    double m = -1;
    const int row_end = std::min(rows_, (tile_row + 1) * kCoarseRings);
    const int fine_per_coarse = kCoarseWidth / kFineWidth;
    const int fine_end = std::min(fine_cols_, (tile + 1) * fine_per_coarse);
    for (int row = tile_row * kCoarseRings; row < row_end; ++row) {
      for (int f = tile * fine_per_coarse; f < fine_end; ++f) m = openMax(fineMax(row, f), m);
    }
    coarse_max_[i] = m;
    coarse_stale_[i] = 0;
  }
  return coarse_max_[i];
}

bool OcclusionTiles::anyOpen(const BeamRect& rect, double near) {
  if (rect.empty()) return false;
  // Written so that a NaN near or range keeps the rect open.
  auto open = [&](double m) { return !(m < near); };
  const int f_lo = rect.col_lo / kFineWidth, f_hi = rect.col_hi / kFineWidth;
  const long long fine_tiles =
      static_cast<long long>(rect.row_hi - rect.row_lo + 1) * (f_hi - f_lo + 1);
  // Large windows are answered from the coarse tiles (fewer reads, a looser bound).
  if (fine_tiles > 4 * (kCoarseWidth / kFineWidth)) {
    for (int tr = rect.row_lo / kCoarseRings; tr <= rect.row_hi / kCoarseRings; ++tr) {
      for (int t = rect.col_lo / kCoarseWidth; t <= rect.col_hi / kCoarseWidth; ++t) {
        if (open(coarseMax(tr, t))) return true;
      }
    }
    return false;
  }
  for (int row = rect.row_lo; row <= rect.row_hi; ++row) {
    for (int f = f_lo; f <= f_hi; ++f) {
      if (open(fineMax(row, f))) return true;
    }
  }
  return false;
}

}  // namespace core
}  // namespace laser_raycast
