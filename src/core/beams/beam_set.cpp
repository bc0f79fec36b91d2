#include "beams/beam_set.h"

#include <limits>

namespace laser_raycast {
namespace core {

void BeamSet::reset(const ScanPattern& pattern, const CastConfig& config, ScanResult* result,
                    const Bundle* bundle) {
  grid_.reset(pattern, config);
  result_ = result;
  bundle_ = bundle;
  with_normals_ = bundle ? !bundle->result->normal.empty() : !result->normal.empty();
  occlusion_culling_ = config.occlusion_culling;
  // resetResult left every range +inf (or NaN for a sensor pose that is not valid, and then
  // nothing is cast): the farthest hit a beam keeps is tmax.
  tiles_.reset(grid_.rows(), grid_.cols(), floatAbove(config.tmax));
  first_ = nullptr;
  sub_rays_ = 0;
  use_shears_ = false;
  if (!bundle) return;
  first_ = bundle->first;
  sub_rays_ = bundle->per_beam;
  sub_direction_ = bundle->directions->data();
  if (bundle->from_origin && !(bundle->owner && bundle->owner == float_owner_)) {
    float_owner_ = bundle->owner;
    const std::size_t n = first_ ? first_->back() : pattern.size() * sub_rays_;
    for (std::vector<float>* axis :
         {&sub_direction_float_.x, &sub_direction_float_.y, &sub_direction_float_.z}) {
      axis->assign(n + 3, 0.0f);
    }
    for (std::size_t s = 0; s < n; ++s) {
      sub_direction_float_.x[s] = static_cast<float>(sub_direction_[s].x());
      sub_direction_float_.y[s] = static_cast<float>(sub_direction_[s].y());
      sub_direction_float_.z[s] = static_cast<float>(sub_direction_[s].z());
    }
  }
  use_shears_ =
      bundle->from_origin && bundle->owner && config.method == TriangleMethod::kWatertight;
  if (use_shears_ && bundle->owner != shear_owner_) {
    shear_owner_ = bundle->owner;
    sub_shears_.resize(first_ ? first_->back() : pattern.size() * sub_rays_);
    for (std::size_t s = 0; s < sub_shears_.size(); ++s) {
      sub_shears_[s] = PreparedRay<double, TriangleMethod::kWatertight>::shearOf(sub_direction_[s]);
    }
  }
  sub_range_ = bundle->result->range.data();
  sub_body_ = bundle->result->body.data();
  sub_triangle_ = bundle->result->triangle.data();
  sub_normal_ = bundle->result->normal.data();
  // A grid beam without sub-rays is never open.
  if (!first_) return;
  for (int row = 0; row < grid_.rows(); ++row) {
    for (int col = 0; col < grid_.cols(); ++col) {
      const int i = grid_.beam(row, col);
      if ((*first_)[i] != (*first_)[i + 1]) continue;
      result_->range[i] = -std::numeric_limits<double>::infinity();
      tiles_.lower(row, col, -std::numeric_limits<float>::infinity());
    }
  }
}

}  // namespace core
}  // namespace laser_raycast
