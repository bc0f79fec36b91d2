#include "laser_raycast/core/occlusion_tiles.h"

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
  range_.assign(static_cast<std::size_t>(rows_) * padded_cols_, 0.0f);
  for (int r = 0; r < rows_; ++r) {
    std::fill_n(range_.begin() + static_cast<std::size_t>(r) * padded_cols_, cols_, start);
  }
  fine_max_.assign(static_cast<std::size_t>(rows_) * fine_cols_, start);
  fine_stale_.assign(fine_max_.size(), 0);
  coarse_max_.assign(static_cast<std::size_t>(coarse_rows_) * coarse_cols_, start);
  coarse_stale_.assign(coarse_max_.size(), 0);
}

float OcclusionTiles::fineMax(int row, int tile) const {
  const std::size_t i = static_cast<std::size_t>(row) * fine_cols_ + tile;
  if (fine_stale_[i]) {
    const float* t = &range_[static_cast<std::size_t>(row) * padded_cols_ + tile * kFineWidth];
    const __m128 m = _mm_max_ps(_mm_max_ps(_mm_loadu_ps(t), _mm_loadu_ps(t + 4)),
                                _mm_max_ps(_mm_loadu_ps(t + 8), _mm_loadu_ps(t + 12)));
    fine_max_[i] = maxOf(m);
    fine_stale_[i] = 0;
  }
  return fine_max_[i];
}

float OcclusionTiles::coarseMax(int tile_row, int tile) const {
  const std::size_t i = static_cast<std::size_t>(tile_row) * coarse_cols_ + tile;
  if (coarse_stale_[i]) {
    float m = 0;
    const int row_end = std::min(rows_, (tile_row + 1) * kCoarseRings);
    const int fine_per_coarse = kCoarseWidth / kFineWidth;
    const int fine_end = std::min(fine_cols_, (tile + 1) * fine_per_coarse);
    for (int row = tile_row * kCoarseRings; row < row_end; ++row) {
      for (int k = tile * fine_per_coarse; k < fine_end; ++k) m = std::max(m, fineMax(row, k));
    }
    coarse_max_[i] = m;
    coarse_stale_[i] = 0;
  }
  return coarse_max_[i];
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
  for (int row = rect.row_lo; row <= rect.row_hi; ++row) {
    if (anyOpenInRow(row, rect.col_lo, rect.col_hi, near)) return true;
  }
  return false;
}

}  // namespace core
}  // namespace laser_raycast
