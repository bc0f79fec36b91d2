// Which parts of a scan are still open: every beam's range so far, rounded up to float, and its
// maximum over tiles of beams in two levels (fine tiles of one ring by kFineWidth azimuths, coarse
// tiles of kCoarseRings rings by kCoarseWidth azimuths), so that "is every beam of this window
// already nearer than d?" costs a few reads, four at a time, instead of one per beam. The caster
// asks it before it walks a body or a BVH node: if every beam the node's window holds has hit
// something nearer than the node, the node is hidden.
//
// Ranges only ever decrease while a scan is cast, so a stale maximum is still an upper bound: a hit
// only marks its tiles stale, and a read refreshes the stale tiles it reads. Threads that cast
// separate pieces of the scan (whole coarse tiles each) never share a tile, nor a cache line of
// the tiles' bookkeeping: each coarse tile keeps its own and its fine tiles' in one block of whole
// cache lines (written by two cores, one shared line would bounce between them on every hit).
#pragma once

#include <emmintrin.h>

#include <algorithm>
#include <cstdint>
#include <vector>

namespace laser_raycast {
namespace core {

// Beams (row r, column a) with r in [row_lo, row_hi] and a in [col_lo, col_hi], inclusive. Rows are
// rings in ascending elevation, columns azimuth indices.
struct BeamRect {
  int row_lo, row_hi, col_lo, col_hi;
  bool empty() const { return row_lo > row_hi || col_lo > col_hi; }
  long long beams() const {
    return empty() ? 0 : static_cast<long long>(row_hi - row_lo + 1) * (col_hi - col_lo + 1);
  }
};

class OcclusionTiles {
 public:
  static constexpr int kFineWidth = 16;
  static constexpr int kCoarseRings = 8;
  static constexpr int kCoarseWidth = 128;

  // rows x cols beams, every range `start` (the farthest hit a beam can keep: tmax, rounded up).
  void reset(int rows, int cols, float start);
  // The ranges of one row, padded to whole fine tiles (the padding holds 0: never open).
  const float* row(int r) const { return ranges() + static_cast<std::size_t>(r) * padded_cols_; }
  // The beam at (row, col) hit something at `range` (rounded up), nearer than before.
  // (Always inlined: the few lines run for every hit kept, and GCC left them out of line once a
  // third caller came.)
  __attribute__((always_inline)) void lower(int row, int col, float range) {
    ranges()[static_cast<std::size_t>(row) * padded_cols_ + col] = range;
    const int tile = quotient(col, kFineWidth);
    Block& b = block(row, tile);
    b.fine_stale[fineSlot(row, tile)] = 1;
    b.coarse_stale = 1;
  }
  // False only if every beam in rect has a range below `near` (so nothing at distance >= near can
  // be seen through rect). May answer true when that holds too (a coarse tile overlaps the rect's
  // border), never false when some beam is at near or farther.
  bool anyOpen(const BeamRect& rect, float near) const {
    // A narrow window of one row, without branches; any other window of a one-row scan (a planar
    // fan: its coarse tiles are the row's own, so a window of it is read through them, exactly).
    const bool one_row = rect.row_lo == rect.row_hi;
    if (one_row & (rect.col_hi - rect.col_lo < kFineWidth)) {
      return narrowOpen(row(rect.row_lo), rect.col_lo, rect.col_hi, near);
    }
    if (one_row & (rows_ == 1)) {
      return !rect.empty() && anyOpenInRow(rect.row_lo, rect.col_lo, rect.col_hi, near);
    }
    return anyOpenInRows(rect, near);
  }

 private:
  float coarseMax(int tile_row, int tile) const;
  float fineMax(int row, int tile) const;
  bool anyOpenInRows(const BeamRect& rect, float near) const;
  // Windows narrower than this are read beam by beam, four at a time, row after row (cheaper than
  // their tiles' maxima, which may need refreshing).
  static constexpr int kDirectColumns = 32;
  // Beams first..last of a row, four at a time, against near; whole fine tiles by their maximum,
  // and in a one-row scan whole coarse tiles by theirs.
  bool anyOpenInRow(int row_index, int first, int last, float near) const {
    const float* r = row(row_index);
    const int t_lo = quotient(first, kFineWidth), t_hi = quotient(last, kFineWidth);
    if (t_lo != t_hi) {
      if (chunkOpen(r, first, t_lo * kFineWidth + kFineWidth - 1, near)) return true;
      for (int t = t_lo + 1; t < t_hi;) {
        // Written so that NaN counts as open.
        if (rows_ == 1 && remainder(t, kFinePerCoarse) == 0 && t + kFinePerCoarse <= t_hi) {
          if (!(coarseMax(0, quotient(t, kFinePerCoarse)) < near)) return true;
          t += kFinePerCoarse;
        } else {
          if (!(fineMax(row_index, t) < near)) return true;
          ++t;
        }
      }
      first = t_hi * kFineWidth;
    }
    return chunkOpen(r, first, last, near);
  }
  // Beams first..last of a row, four at a time: the lanes of the first and last group that lie in
  // the range are picked by masks.
  static bool chunkOpen(const float* r, int first, int last, float near) {
    const int base = first & ~3, end = (last & ~3) - base;
    const __m128 limit = _mm_set1_ps(near);
    r += base;
    // Not less than: a NaN (a beam that could not be cast) counts as open.
    __m128 open = _mm_and_ps(_mm_cmpnlt_ps(_mm_loadu_ps(r), limit), lanesFrom(first - base));
    if (end == 0) return _mm_movemask_ps(_mm_and_ps(open, lanesTo(last - base))) != 0;
    for (int b = 4; b < end; b += 4) {
      open = _mm_or_ps(open, _mm_cmpnlt_ps(_mm_loadu_ps(r + b), limit));
    }
    open = _mm_or_ps(
        open, _mm_and_ps(_mm_cmpnlt_ps(_mm_loadu_ps(r + end), limit), lanesTo(last - base - end)));
    return _mm_movemask_ps(open) != 0;
  }
  // Beams first..last of a row, fewer than kFineWidth (none if last < first), as five groups of
  // four whatever their number, each lane masked by its column: where a window starts and how wide
  // it is are coin tosses that the branches of chunkOpen's loop would mispredict. Groups past the
  // one holding last read that one again, so that nothing beyond it is read (another thread's).
  static bool narrowOpen(const float* r, int first, int last, float near) {
    static_assert(kFineWidth <= 17, "five groups of four cover a narrow window from first & ~3");
    if (last < first) return false;
    const int base = first & ~3, end = last & ~3;
    const __m128 limit = _mm_set1_ps(near);
    const __m128i after_first = _mm_set1_epi32(first - 1), before_last = _mm_set1_epi32(last + 1);
    const __m128i lane = _mm_setr_epi32(0, 1, 2, 3);
    __m128 open = _mm_setzero_ps();
    for (int g = 0; g < 5; ++g) {
      const int at = std::min(base + 4 * g, end);
      const __m128i column = _mm_add_epi32(_mm_set1_epi32(at), lane);
      const __m128i in =
          _mm_and_si128(_mm_cmpgt_epi32(column, after_first), _mm_cmpgt_epi32(before_last, column));
      // Not less than: a NaN (a beam that could not be cast) counts as open.
      const __m128 beam_open = _mm_cmpnlt_ps(_mm_loadu_ps(r + at), limit);
      open = _mm_or_ps(open, _mm_and_ps(_mm_castsi128_ps(in), beam_open));
    }
    return _mm_movemask_ps(open) != 0;
  }
  // Lanes j >= f, and j <= l, of four (f, l in [0, 3]).
  static __m128 lanesFrom(int f) { return lanes(kLanes + 4 - f); }
  static __m128 lanesTo(int l) { return lanes(kLanes + 7 - l); }
  static __m128 lanes(const std::int32_t* p) {
    return _mm_castsi128_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p)));
  }
  static constexpr std::int32_t kLanes[12] = {0, 0, 0, 0, -1, -1, -1, -1, 0, 0, 0, 0};

  static constexpr int kFinePerCoarse = kCoarseWidth / kFineWidth;
  static constexpr int kFinePerBlock = kCoarseRings * kFinePerCoarse;
  // A coarse tile's bookkeeping and its fine tiles' (row-major within the tile), in whole cache
  // lines. The maxima are refreshed when read (a query that reads a stale tile writes it).
  struct alignas(64) Block {
    float fine_max[kFinePerBlock];
    char fine_stale[kFinePerBlock];
    float coarse_max;
    char coarse_stale;
  };
  // Quotient and remainder of a row, column or tile index (never negative) by a power of two:
  // taken unsigned, they are a shift and a mask, without signed division's fix-ups (every hit
  // finds its tile).
  static int quotient(int index, int by) {
    return static_cast<int>(static_cast<unsigned>(index) / static_cast<unsigned>(by));
  }
  static int remainder(int index, int by) {
    return static_cast<int>(static_cast<unsigned>(index) % static_cast<unsigned>(by));
  }
  Block& block(int row, int fine_tile) const {
    return blocks_[static_cast<std::size_t>(quotient(row, kCoarseRings)) * coarse_cols_ +
                   quotient(fine_tile, kFinePerCoarse)];
  }
  static int fineSlot(int row, int fine_tile) {
    return remainder(row, kCoarseRings) * kFinePerCoarse + remainder(fine_tile, kFinePerCoarse);
  }

  // The ranges, rows_ x padded_cols_, a row in whole fine tiles of one cache line each.
  struct alignas(64) FineTile {
    float range[kFineWidth];
  };
  static_assert(sizeof(FineTile) == kFineWidth * sizeof(float), "a fine tile is one cache line");
  float* ranges() { return range_.data()->range; }
  const float* ranges() const { return range_.data()->range; }

  int rows_ = 0, cols_ = 0, padded_cols_ = 0, fine_cols_ = 0, coarse_rows_ = 0, coarse_cols_ = 0;
  std::vector<FineTile> range_;
  mutable std::vector<Block> blocks_;  // coarse_rows_ x coarse_cols_
};

}  // namespace core
}  // namespace laser_raycast
