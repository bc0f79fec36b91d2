#include "beams/beam_grid.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace laser_raycast {
namespace core {

void ringsByElevation(const ScanPattern& pattern, std::vector<int>* order) {
  const std::vector<double>& elevations = pattern.elevations();
  order->resize(elevations.size());
  std::iota(order->begin(), order->end(), 0);
  std::stable_sort(order->begin(), order->end(),
                   [&](int a, int b) { return elevations[a] < elevations[b]; });
}

void BeamGrid::reset(const ScanPattern& pattern, const CastConfig& config) {
  pattern_ = &pattern;
  planar_ = pattern.planar();
  ringsByElevation(pattern, &beam_of_row_);
  col_start_ = pattern.angleMin();
  col_inv_increment_ = 1 / pattern.angleIncrement();
  col_turn_ = 2 * M_PI * col_inv_increment_;
  const double span = (pattern.azimuthCount() - 1) * pattern.angleIncrement();
  one_turn_ = span <= 2 * M_PI && col_turn_ < 1e9;
  // The rounding of the few operations from an angle to a column index, with room to spare.
  col_pad_ = 64 * std::numeric_limits<double>::epsilon() * (col_turn_ + cols() + 8);
  prepareSensorRays(config);
}

void BeamGrid::prepareSensorRays(const CastConfig& config) {
  PreparedKey key;
  key.angle_min = pattern_->angleMin();
  key.angle_increment = pattern_->angleIncrement();
  key.azimuths = pattern_->azimuthCount();
  key.elevations = pattern_->elevations();
  key.tmin = config.tmin;
  key.cull_backfaces = config.cull_backfaces;
  key.method = config.method;
  tmin_ = config.tmin;
  cull_backfaces_ = config.cull_backfaces;
  if (prepared_key_ && *prepared_key_ == key) return;
  prepared_key_ = key;
  // As ScanPattern computes each direction: (cos e cos a, cos e sin a, sin e).
  row_ce_.clear();
  row_se_.clear();
  for (const int ring : beam_of_row_) {
    row_ce_.push_back(std::cos(pattern_->elevations()[ring]));
    row_se_.push_back(std::sin(pattern_->elevations()[ring]));
  }
  column_cos_d_.resize(cols());
  column_sin_d_.resize(cols());
  for (int col = 0; col < cols(); ++col) {
    column_cos_d_[col] = std::cos(pattern_->azimuth(col));
    column_sin_d_[col] = std::sin(pattern_->azimuth(col));
  }
  padded_cols_ = (cols() + 3) / 4 * 4;
  prepareRows();
  direction_x_.assign(static_cast<std::size_t>(rows()) * padded_cols_, 0.0f);
  direction_y_.assign(direction_x_.size(), 0.0f);
  direction_z_.assign(rows(), 0.0f);
  for (int row = 0; row < rows(); ++row) {
    direction_z_[row] = static_cast<float>(direction(row, 0).z());
    for (int col = 0; col < cols(); ++col) {
      direction_x_[row * padded_cols_ + col] = static_cast<float>(direction(row, col).x());
      direction_y_[row * padded_cols_ + col] = static_cast<float>(direction(row, col).y());
    }
  }
}

void RowTable::build(std::vector<double> values) {
  values_ = std::move(values);
  const double lo = values_.front(), hi = values_.back();
  const double span = std::max(hi - lo, std::abs(lo) * 1e-6 + 1e-9);
  base_ = static_cast<float>(lo - span / kBins);
  scale_ = static_cast<float>(kBins / (span * (1 + 2.0 / kBins)));
  first_at_or_above_.resize(kBins + 1);
  last_at_or_below_.resize(kBins + 1);
  for (int b = 0; b <= kBins; ++b) {
    const double bin_lo = base_ + b / double(scale_), bin_hi = base_ + (b + 1) / double(scale_);
    first_at_or_above_[b] = static_cast<int>(
        std::lower_bound(values_.begin(), values_.end(), bin_lo) - values_.begin());
    last_at_or_below_[b] =
        static_cast<int>(std::upper_bound(values_.begin(), values_.end(), bin_hi) -
                         values_.begin()) -
        1;
  }
}

void BeamGrid::prepareRows() {
  std::vector<double> elevations, tangents;
  column_raster_ = true;
  row_cos_.clear();
  row_sin_.clear();
  smallest_row_cos_ = 1;
  for (const int ring : beam_of_row_) {
    const double e = pattern_->elevations()[ring];
    elevations.push_back(e);
    column_raster_ = column_raster_ && std::abs(e) <= kMaxColumnRasterElevation;
    tangents.push_back(
        std::tan(std::max(-kMaxColumnRasterElevation, std::min(kMaxColumnRasterElevation, e))));
    row_cos_.push_back(static_cast<float>(std::cos(e)));
    row_sin_.push_back(static_cast<float>(std::sin(e)));
    smallest_row_cos_ = std::min(smallest_row_cos_, row_cos_.back());
  }
  row_tan_below_.clear();
  row_tan_above_.clear();
  for (const double t : tangents) {
    row_tan_below_.push_back(floatBelow(t));
    row_tan_above_.push_back(floatAbove(t));
  }
  // Room to read kRowBlock values from any row (NaN: no comparison holds).
  row_tan_below_.resize(row_tan_below_.size() + kRowBlock, std::numeric_limits<float>::quiet_NaN());
  row_tan_above_.resize(row_tan_above_.size() + kRowBlock, std::numeric_limits<float>::quiet_NaN());
  row_elevation_.build(std::move(elevations));
  row_tan_.build(std::move(tangents));
  column_cos_.assign(padded_cols_, 0.0f);
  column_sin_.assign(padded_cols_, 0.0f);
  for (int col = 0; col < cols(); ++col) {
    column_cos_[col] = static_cast<float>(std::cos(pattern_->azimuth(col)));
    column_sin_[col] = static_cast<float>(std::sin(pattern_->azimuth(col)));
  }
}

}  // namespace core
}  // namespace laser_raycast
