#include "beams/beam_set.h"

#include <limits>

namespace laser_raycast {
namespace core {

void BeamSet::reset(const ScanPattern& pattern, const CastConfig& config, ScanResult* result,
                    const Bundle* bundle) {
  grid_.reset(pattern, config);
  result_ = result;
  bundle_ = bundle;
  with_normals_ = bundle ? !bundle->results.front()->normal.empty() : !result->normal.empty();
  occlusion_culling_ = config.occlusion_culling;
  // resetResult left every range +inf (or NaN for a sensor pose that is not valid, and then
  // nothing is cast): the farthest hit a beam keeps is tmax.
  tiles_.reset(grid_.rows(), grid_.cols(), floatAbove(config.tmax));
  first_ = nullptr;
  sub_rays_ = 0;
  use_shears_ = false;
  if (!bundle) return;
  first_ = bundle->first;
  sub_rays_ =
      bundle->per_beam > 0 ? bundle->per_beam : static_cast<int>(bundle->directions.size());
  ScanResult* own = bundle->results.front();
  if (first_ || bundle->per_beam > 0 || sub_rays_ == 1) {
    // Already sub-ray by sub-ray: cast in place.
    sub_direction_ = bundle->directions.front()->data();
  } else {
    const std::size_t beams = pattern.size(), n = beams * sub_rays_;
    interleaved_directions_.resize(n);
    own = &interleaved_;
    own->range.resize(n);
    own->body.resize(n);
    own->triangle.resize(n);
    own->normal.resize(with_normals_ ? n : 0);
    for (int k = 0; k < sub_rays_; ++k) {
      const std::vector<Eigen::Vector3d>& directions = *bundle->directions[k];
      const ScanResult& r = *bundle->results[k];
      for (std::size_t i = 0, s = k; i < beams; ++i, s += sub_rays_) {
        interleaved_directions_[s] = directions[i];
        own->range[s] = r.range[i];
        own->body[s] = r.body[i];
        own->triangle[s] = r.triangle[i];
        if (with_normals_) own->normal[s] = r.normal[i];
      }
    }
    sub_direction_ = interleaved_directions_.data();
  }
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
  use_shears_ = bundle->per_beam > 0 && bundle->from_origin && bundle->owner &&
                config.method == TriangleMethod::kWatertight;
  if (use_shears_ && bundle->owner != shear_owner_) {
    shear_owner_ = bundle->owner;
    sub_shears_.resize(pattern.size() * sub_rays_);
    for (std::size_t s = 0; s < sub_shears_.size(); ++s) {
      sub_shears_[s] = PreparedRay<double, TriangleMethod::kWatertight>::shearOf(sub_direction_[s]);
    }
  }
  sub_range_ = own->range.data();
  sub_body_ = own->body.data();
  sub_triangle_ = own->triangle.data();
  sub_normal_ = own->normal.data();
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

void BeamSet::finish() {
  if (!bundle_ || first_ || bundle_->per_beam > 0 || sub_rays_ == 1) return;  // cast in place
  const std::size_t beams = grid_.pattern().size();
  for (int k = 0; k < sub_rays_; ++k) {
    ScanResult& r = *bundle_->results[k];
    for (std::size_t i = 0, s = k; i < beams; ++i, s += sub_rays_) {
      r.range[i] = interleaved_.range[s];
      r.body[i] = interleaved_.body[s];
      r.triangle[i] = interleaved_.triangle[s];
      if (with_normals_) r.normal[i] = interleaved_.normal[s];
    }
  }
}

}  // namespace core
}  // namespace laser_raycast
