#include "beams/occlusion_tiles.h"

#include <emmintrin.h>

#include <algorithm>

namespace laser_raycast {
namespace core {
namespace {

// The largest of four floats.
inline float maxOf(__m128 m) {
  m = _mm_max_ps(m, _mm_shuffle_ps(m, m, _MM_SHUFFLE(1, 0, 3, 2)));
  m = _mm_max_ps(m, _mm_shuffle_ps(m, m, _MM_SHUFFLE(2, 3, 0, 1)));
  return _mm_cvtss_f32(m);
}

}  // namespace

void OcclusionTiles::reset(int rows, int cols, float start) {
  rows_ = rows;
  cols_ = cols;
  fine_cols_ = (cols + kFineWidth - 1) / kFineWidth;
  padded_cols_ = fine_cols_ * kFineWidth;
  coarse_rows_ = (rows + kCoarseRings - 1) / kCoarseRings;
  coarse_cols_ = (cols + kCoarseWidth - 1) / kCoarseWidth;
  range_.assign(static_cast<std::size_t>(rows_) * fine_cols_, FineTile{});
  for (int r = 0; r < rows_; ++r)
    std::fill_n(ranges() + static_cast<std::size_t>(r) * padded_cols_, cols_, start);
  Block fresh;
  std::fill_n(fresh.fine_max, kFinePerBlock, start);
  std::fill_n(fresh.fine_stale, kFinePerBlock, 0);
  fresh.coarse_max = start;
  fresh.coarse_stale = 0;
  blocks_.assign(static_cast<std::size_t>(coarse_rows_) * coarse_cols_, fresh);
}

float OcclusionTiles::fineMax(int row, int tile) const {
  Block& b = block(row, tile);
  const int i = fineSlot(row, tile);
  if (b.fine_stale[i]) {
    const float* t = this->row(row) + tile * kFineWidth;
    const __m128 m = _mm_max_ps(_mm_max_ps(_mm_loadu_ps(t), _mm_loadu_ps(t + 4)),
                                _mm_max_ps(_mm_loadu_ps(t + 8), _mm_loadu_ps(t + 12)));
    b.fine_max[i] = maxOf(m);
    b.fine_stale[i] = 0;
  }
  return b.fine_max[i];
}

float OcclusionTiles::coarseMax(int tile_row, int tile) const {
  Block& b = block(tile_row * kCoarseRings, tile * kFinePerCoarse);
  if (b.coarse_stale) {
    float m = 0;
    const int row_end = std::min(rows_, (tile_row + 1) * kCoarseRings);
    const int fine_end = std::min(fine_cols_, (tile + 1) * kFinePerCoarse);
    for (int row = tile_row * kCoarseRings; row < row_end; ++row) {
      for (int k = tile * kFinePerCoarse; k < fine_end; ++k) m = std::max(m, fineMax(row, k));
    }
    b.coarse_max = m;
    b.coarse_stale = 0;
  }
  return b.coarse_max;
}

bool OcclusionTiles::anyOpenInRows(const BeamRect& rect, float near) const {
  if (rect.empty()) return false;
  // Large windows are answered from the coarse tiles (fewer reads, a looser bound).
  const long long fine_tiles = static_cast<long long>(rect.row_hi - rect.row_lo + 1) *
                               (rect.col_hi / kFineWidth - rect.col_lo / kFineWidth + 1);
  if (fine_tiles > 4 * (kCoarseWidth / kFineWidth)) {
    for (int tr = rect.row_lo / kCoarseRings; tr <= rect.row_hi / kCoarseRings; ++tr) {
      for (int t = rect.col_lo / kCoarseWidth; t <= rect.col_hi / kCoarseWidth; ++t) {
        if (!(coarseMax(tr, t) < near)) return true;
      }
    }
    return false;
  }
  if (rect.col_hi - rect.col_lo < kFineWidth) {
    for (int row = rect.row_lo; row <= rect.row_hi; ++row) {
      if (narrowOpen(this->row(row), rect.col_lo, rect.col_hi, near)) return true;
    }
    return false;
  }
  const bool direct = rect.col_hi - rect.col_lo < kDirectColumns;
  for (int row = rect.row_lo; row <= rect.row_hi; ++row) {
    if (direct ? chunkOpen(this->row(row), rect.col_lo, rect.col_hi, near)
               : anyOpenInRow(row, rect.col_lo, rect.col_hi, near)) {
      return true;
    }
  }
  return false;
}

}  // namespace core
}  // namespace laser_raycast
