#include "walk/primitive_cast.h"

#include <emmintrin.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <type_traits>
#include <variant>

#include "beams/column_motion.h"
#include "laser_raycast/core/primitives.h"
#include "util/float_rounding.h"
#include "util/simd_math.h"

namespace laser_raycast {
namespace core {
namespace {

// The relative margin of the float test: each quantity is a few float roundings (6e-8 each) from
// its exact value; the directions' absolute error is below kDirectionError.
constexpr float kMargin = 1e-5f;
constexpr float kDirectionError = 1e-6f;

// Which beams of four certainly miss the primitive's box (body frame, centred, half extents h), or
// meet it only beyond their current range. A beam d (sensor frame) is d_b = R d in the body frame,
// from the sensor at o. On an axis where the sensor lies outside the box's slab, a beam moving away
// from the slab never enters it, and one moving towards it enters no sooner than the gap over its
// speed there, which a larger speed bounds from below. Never says "miss" for a beam whose exact ray
// enters the box before its range.
//
// A sweep's beam leaves from within spread.shift of o along a direction within spread.turn of d
// (ColumnMotion): where it meets the box, the same direction from o meets the box grown by the
// shift on every side, and each component of its direction is within the turn of d's. So the test
// of d from o against the grown box, with the turn added to the directions' error, never says
// "miss" for it either.
class BoxPrefilter {
 public:
  BoxPrefilter(const PlacedBody& a, const Eigen::Vector3d& half, const Spread& spread)
      : shift_(spread.shift),
        error_(_mm_set1_ps(floatAbove(double(kDirectionError) + spread.turn))),
        error_value_(double(kDirectionError) + spread.turn) {
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) r_[i][j] = _mm_set1_ps(float(a.body_from_sensor_rot(i, j)));
      const double o = a.sensor_in_body[i];
      // The gap to the slab, rounded down by the margin (negative: inside the slab).
      const double h = (half[i] + shift_) * (1 + kMargin) + kMargin * std::abs(o);
      gap_[i] = _mm_set1_ps(static_cast<float>(std::abs(o) - h));
      // The sign of the side the sensor is on (0 inside): a beam moving that way moves away.
      side_[i] = _mm_set1_ps(std::abs(o) > h ? (o > 0 ? 1.0f : -1.0f) : 0.0f);
    }
  }

  // A cylinder's tube (radius r about the body's z axis) as well: a beam whose line passes farther
  // from the axis than r misses it. The line's distance from the axis is |o x d| / |d| in x, y;
  // the float cross product is off by at most 3 |o| kDirectionError (the directions' error and its
  // own rounding), |d| by 2 kDirectionError, and kMargin covers the exact test's rounding at the
  // tube's rim. So a beam is let through unless |o x d| > r' (|d| + 2 error) + 3 |o| error.
  void addTube(const PlacedBody& a, double radius) {
    tube_ = true;
    const double ox = a.sensor_in_body.x(), oy = a.sensor_in_body.y();
    ox_ = _mm_set1_ps(static_cast<float>(ox));
    oy_ = _mm_set1_ps(static_cast<float>(oy));
    const double r = (radius + shift_) * (1 + kMargin), o = std::hypot(ox, oy);
    tube_r_ = _mm_set1_ps(static_cast<float>(r));
    tube_pad_ =
        _mm_set1_ps(static_cast<float>((2 * r + 3 * o) * error_value_ + kMargin * (r + o)));
  }

  // Bit j: beam j of the four (directions x, y, z; ranges rounded up) cannot hit.
  int misses(__m128 dx, __m128 dy, __m128 dz, __m128 range) const {
    const __m128 error = error_;
    const __m128 zero = _mm_setzero_ps();
    __m128 miss = zero;
    __m128 body[3];  // the directions in the body's frame
    for (int i = 0; i < 3; ++i) {
      const __m128 d = _mm_add_ps(_mm_add_ps(_mm_mul_ps(r_[i][0], dx), _mm_mul_ps(r_[i][1], dy)),
                                  _mm_mul_ps(r_[i][2], dz));
      // Moving away from the slab the sensor is outside of, beyond the direction's error.
      const __m128 away = _mm_cmpgt_ps(_mm_mul_ps(d, side_[i]), error);
      // Entering it no sooner than gap / (|d| + error): beyond the range.
      const __m128 beyond = _mm_cmpgt_ps(_mm_mul_ps(gap_[i], _mm_set1_ps(1 - kMargin)),
                                         _mm_mul_ps(range, _mm_add_ps(simd::absPs(d), error)));
      miss = _mm_or_ps(miss, _mm_or_ps(away, _mm_and_ps(beyond, _mm_cmpgt_ps(gap_[i], zero))));
      body[i] = d;
    }
    if (tube_) {
      const __m128 cross =
          simd::absPs(_mm_sub_ps(_mm_mul_ps(ox_, body[1]), _mm_mul_ps(oy_, body[0])));
      const __m128 speed =
          _mm_sqrt_ps(_mm_add_ps(_mm_mul_ps(body[0], body[0]), _mm_mul_ps(body[1], body[1])));
      miss =
          _mm_or_ps(miss, _mm_cmpgt_ps(cross, _mm_add_ps(_mm_mul_ps(tube_r_, speed), tube_pad_)));
    }
    return _mm_movemask_ps(miss);
  }

 private:
  double shift_;
  __m128 error_;
  double error_value_;
  __m128 r_[3][3], gap_[3], side_[3];
  bool tube_ = false;
  __m128 ox_, oy_, tube_r_, tube_pad_;
};

// The beam at (row, col) along sensor-frame direction d as a ray in the body's frame, out to tmax:
// from the sensor, or for a sweep's block (and a bundle's) from the beam's own pose.
Ray bodyRay(const PlacedBody& a, const CastConfig& config, int row, int col,
            const Eigen::Vector3d& d, double tmax) {
  Ray ray;
  if (a.motion) {
    const Ray beam = a.motion->ray(row, col, d, config.tmin);
    ray.origin = a.body_from_sensor_rot * beam.origin + a.sensor_in_body;
    ray.dir = a.body_from_sensor_rot * beam.dir;
  } else {
    ray.origin = a.sensor_in_body;
    ray.dir = a.body_from_sensor_rot * d;
  }
  ray.tmin = config.tmin;
  ray.tmax = tmax;
  return ray;
}

// A hit's normal n (body frame) in the frame of the beam at (row, col), as ScanResult has it.
Eigen::Vector3d beamNormal(const PlacedBody& a, int row, int col, const Eigen::Vector3d& n) {
  const Eigen::Vector3d sensor_n = a.sensor_from_body.linear() * n;
  return a.motion ? a.motion->toBeam(row, col, sensor_n) : sensor_n;
}

// One beam (its range so far: current) against the primitive, analytically: every hit of a beam on
// a primitive is found here. The beams are valid rays (a unit direction, a finite pose): no check
// needed.
template <class Primitive>
void testBeam(BeamSet& beams, const Primitive& shape, const PlacedBody& a,
              const CastConfig& config, int row, int col, double current) {
  if (beams.bundle()) {
    for (int s = beams.subBegin(row, col), end = beams.subEnd(row, col); s < end; ++s) {
      const Ray ray = bodyRay(a, config, row, col, beams.subDirection(s),
                              std::min(config.tmax, beams.subRange(s)));
      const std::optional<PrimitiveHit> hit = detail::intersectValid(ray, shape);
      if (!hit) continue;
      beams.keepNearestSubHit(s, row, col, hit->t, a.index, -1,
                              [&] { return beamNormal(a, row, col, hit->normal); });
    }
    return;
  }
  const Ray ray = bodyRay(a, config, row, col, beams.grid().direction(row, col),
                          std::min(config.tmax, current));
  const std::optional<PrimitiveHit> hit = detail::intersectValid(ray, shape);
  if (!hit) return;
  beams.keepNearestHit(row, col, hit->t, a.index, -1,
                       [&] { return beamNormal(a, row, col, hit->normal); });
}

// The open beams of rect that the pre-test lets through against one primitive, analytically.
template <class Primitive>
void castShape(BeamSet& beams, const Primitive& shape, const PlacedBody& a,
               const BoxPrefilter& filter, const CastConfig& config, const BeamRect& rect) {
  const __m128 near = _mm_set1_ps(floatBelow(a.view.near));
  for (int row = rect.row_lo; row <= rect.row_hi; ++row) {
    const float* x = beams.grid().directionX(row);
    const float* y = beams.grid().directionY(row);
    const float* range = beams.rangeAbove(row);
    const __m128 z = _mm_set1_ps(beams.grid().directionZ(row));
    for (int base = rect.col_lo & ~3; base <= rect.col_hi; base += 4) {
      const __m128 r = _mm_loadu_ps(range + base);
      // Beams whose range (rounded up) is below the primitive's nearest distance are closed to it:
      // skipped before the pre-test (not less than: NaN counts as open).
      int open = _mm_movemask_ps(_mm_cmpnlt_ps(r, near));
      if (!open) continue;
      open &= ~filter.misses(_mm_loadu_ps(x + base), _mm_loadu_ps(y + base), z, r);
      while (open) {
        const int col = base + __builtin_ctz(static_cast<unsigned>(open));
        open &= open - 1;
        if (col < rect.col_lo || col > rect.col_hi) continue;
        const double current = beams.range(row, col);
        if (current >= a.view.near) testBeam(beams, shape, a, config, row, col, current);
      }
    }
  }
}

}  // namespace

void DeferredPrimitives::cast(BeamSet& beams, const Scene& scene, const CastConfig& config) {
  std::stable_sort(items_.begin(), items_.end(), [](const auto& x, const auto& y) {
    return x.first.view.near < y.first.view.near;
  });
  for (const auto& [a, rect] : items_) {
    if (beams.anyOpen(rect, a.view.near)) castPrimitive(beams, scene, a, config, rect);
  }
  items_.clear();
}

void castPrimitive(BeamSet& beams, const Scene& scene, const PlacedBody& a,
                   const CastConfig& config, const BeamRect& rect) {
  const Shape& shape = scene.bodies()[a.index].shape;
  BoxPrefilter filter(a, scene.boxHalf(a.index), a.motion ? a.motion->spread() : Spread());
  if (const auto* box = std::get_if<Box>(&shape)) {
    castShape(beams, *box, a, filter, config, rect);
  } else if (const auto* cylinder = std::get_if<Cylinder>(&shape)) {
    filter.addTube(a, cylinder->radius);
    castShape(beams, *cylinder, a, filter, config, rect);
  } else if (const auto* sphere = std::get_if<Sphere>(&shape)) {
    castShape(beams, *sphere, a, filter, config, rect);
  }
}

void castPrimitiveBeam(BeamSet& beams, const Scene& scene, const PlacedBody& a,
                       const CastConfig& config, int row, int col) {
  const double current = beams.range(row, col);
  if (std::isnan(current)) return;  // a beam that could not be cast, as castShape skips it
  std::visit(
      [&](const auto& shape) {
        using S = std::decay_t<decltype(shape)>;
        if constexpr (!std::is_same_v<S, std::shared_ptr<const Mesh>>) {
          testBeam(beams, shape, a, config, row, col, current);
        }
      },
      scene.bodies()[a.index].shape);
}

}  // namespace core
}  // namespace laser_raycast
