// Which parts of a scan are still open: an upper bound of the current range over tiles of beams, in
// two levels (fine tiles of one ring by kFineWidth azimuths, coarse tiles of kCoarseRings rings by
// kCoarseWidth azimuths), so that "is every beam of this window already nearer than d?" costs a few
// tile reads instead of one read per beam. The caster asks it before it walks a body or a BVH node:
// if every beam the node's window holds has hit something nearer than the node, the node is hidden.
//
// Ranges only ever decrease while a scan is cast, so a stale tile maximum is still an upper bound:
// a write only marks its tiles stale, and a query refreshes the stale tiles it reads.
#pragma once

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

  // range(row, col) is range[beam_of_row[row] * cols + col]; all tiles start stale.
  void reset(const std::vector<double>* range, const std::vector<int>* beam_of_row, int rows,
             int cols);
  // range of the beam at (row, col) decreased.
  void touched(int row, int col) {
    fine_stale_[row * fine_cols_ + col / kFineWidth] = 1;
    coarse_stale_[(row / kCoarseRings) * coarse_cols_ + col / kCoarseWidth] = 1;
  }
  // False only if every beam in rect has a range below `near` (so nothing at distance >= near can
  // be seen through rect). May answer true when that holds too (the tiles overlap the rect's
  // border), never false when some beam is at near or farther. NaN ranges count as open.
  bool anyOpen(const BeamRect& rect, double near);
  // Tiles read so far (a cost measure for tests and tuning).
  std::uint64_t tileReads() const { return tile_reads_; }

 private:
  double rangeAt(int row, int col) const {
    return (*range_)[static_cast<std::size_t>((*beam_of_row_)[row]) * cols_ + col];
  }
  double fineMax(int row, int tile);
  double coarseMax(int tile_row, int tile);

  const std::vector<double>* range_ = nullptr;
  const std::vector<int>* beam_of_row_ = nullptr;
  int rows_ = 0, cols_ = 0, fine_cols_ = 0, coarse_rows_ = 0, coarse_cols_ = 0;
  std::vector<double> fine_max_, coarse_max_;
  std::vector<char> fine_stale_, coarse_stale_;
  std::uint64_t tile_reads_ = 0;
};

}  // namespace core
}  // namespace laser_raycast
