#include "beams/node_views.h"

#include <cmath>
#include <limits>

#include "beams/beam_window.h"
#include "util/simd_math.h"

namespace laser_raycast {
namespace core {
namespace {

using simd::absPs;
using simd::atan2Ps;
using simd::CornerTangents;
using simd::kViewSlack;
using simd::selectPs;

// Elevations: a point of a box (sensor-frame centre c, half extents e) has height in [z_lo, z_hi]
// and horizontal distance in [rho_min, rho_max] (rho2, r2: the squares of the centre's horizontal
// distance and of the xy extent's radius); its elevation atan2(z, rho) is largest at the top and
// the nearest distance (the farthest if the top is below the sensor), smallest likewise.
void storeElevations(const __m128 c[3], const __m128 e[3], __m128 rho2, __m128 r2, float* el_lo,
                     float* el_hi) {
  const __m128 slack = _mm_set1_ps(kViewSlack);
  const __m128 one_minus = _mm_set1_ps(1 - 8 * kViewSlack),
               one_plus = _mm_set1_ps(1 + 8 * kViewSlack);
  const __m128 rho = _mm_sqrt_ps(rho2), r = _mm_sqrt_ps(r2);
  const __m128 rho_min = _mm_max_ps(_mm_mul_ps(_mm_sub_ps(rho, r), one_minus), _mm_setzero_ps());
  const __m128 rho_max = _mm_mul_ps(_mm_add_ps(rho, r), one_plus);
  const __m128 z_slack = _mm_mul_ps(slack, _mm_add_ps(absPs(c[2]), e[2]));
  const __m128 z_lo = _mm_sub_ps(_mm_sub_ps(c[2], e[2]), z_slack);
  const __m128 z_hi = _mm_add_ps(_mm_add_ps(c[2], e[2]), z_slack);
  const __m128 zero = _mm_setzero_ps();
  const __m128 pad = _mm_set1_ps(static_cast<float>(kBearingError));
  const __m128 hi_angle = atan2Ps(z_hi, selectPs(_mm_cmpgt_ps(z_hi, zero), rho_min, rho_max));
  const __m128 lo_angle = atan2Ps(z_lo, selectPs(_mm_cmplt_ps(z_lo, zero), rho_min, rho_max));
  _mm_store_ps(el_hi, _mm_add_ps(hi_angle, pad));
  _mm_store_ps(el_lo, _mm_sub_ps(lo_angle, pad));
}

}  // namespace

SpreadPs::SpreadPs(const Spread& spread)
    : any(spread.any()),
      every_azimuth(!(spread.azimuth < 1.5)),
      shift(_mm_set1_ps(floatAbove(spread.shift))),
      sin_tilt(_mm_set1_ps(floatAbove(std::sin(spread.tilt) * (1 + 1e-9)))),
      turn(_mm_set1_ps(floatAbove(spread.turn))),
      azimuth(_mm_set1_ps(every_azimuth ? 0.0f : floatAbove(spread.azimuth))) {}

ViewBasis::ViewBasis(const Eigen::Isometry3d& sensor_from_body, bool planar, double tmax,
                     const Spread& spread)
    : spread_(spread), planar_(planar) {
  const Eigen::Matrix3d& r = sensor_from_body.linear();
  const Eigen::Vector3d& t = sensor_from_body.translation();
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) {
      rot_[i][k] = _mm_set1_ps(static_cast<float>(r(i, k)));
      abs_rot_[i][k] = _mm_set1_ps(static_cast<float>(std::abs(r(i, k))));
    }
    trans_[i] = _mm_set1_ps(static_cast<float>(t[i]));
    abs_trans_[i] = _mm_set1_ps(static_cast<float>(std::abs(t[i])));
  }
  tmax_ = _mm_set1_ps(floatAbove(tmax));
}

void NodeViews::compute(const WideBvh::Node& node, const ViewBasis& f) {
  const __m128 half_ps = _mm_set1_ps(0.5f);
  const __m128 slack = _mm_set1_ps(kViewSlack);
  __m128 cb[3], eb[3];
  for (int k = 0; k < 3; ++k) {
    const __m128 lo = _mm_load_ps(node.lo[k]), hi = _mm_load_ps(node.hi[k]);
    cb[k] = _mm_mul_ps(_mm_add_ps(lo, hi), half_ps);
    eb[k] = _mm_mul_ps(_mm_sub_ps(hi, lo), half_ps);
  }
  // The sensor-frame centre c and half extents e of the child boxes, e widened by the rounding.
  __m128 c[3], e[3], mag[3];
  for (int i = 0; i < 3; ++i) {
    __m128 ci = f.trans_[i], ei = _mm_setzero_ps(), m = f.abs_trans_[i];
    for (int k = 0; k < 3; ++k) {
      ci = _mm_add_ps(ci, _mm_mul_ps(f.rot_[i][k], cb[k]));
      ei = _mm_add_ps(ei, _mm_mul_ps(f.abs_rot_[i][k], eb[k]));
      m = _mm_add_ps(m, _mm_mul_ps(f.abs_rot_[i][k], _mm_add_ps(absPs(cb[k]), eb[k])));
    }
    c[i] = ci;
    mag[i] = m;
    e[i] = _mm_add_ps(ei, _mm_mul_ps(slack, _mm_add_ps(m, ei)));
    if (f.spread_.any) e[i] = _mm_add_ps(e[i], f.spread_.shift);  // every origin of the block's beams
  }
  // Nearest distance: the norm of the gap between the sensor and the box, lowered by the slack.
  // If the squares overflow, the largest gap is still a lower bound.
  __m128 sum = _mm_setzero_ps(), biggest = _mm_setzero_ps(), magnitude = _mm_setzero_ps();
  for (int i = 0; i < 3; ++i) {
    const __m128 gap = _mm_max_ps(_mm_sub_ps(absPs(c[i]), e[i]), _mm_setzero_ps());
    sum = _mm_add_ps(sum, _mm_mul_ps(gap, gap));
    biggest = _mm_max_ps(biggest, gap);
    magnitude = _mm_add_ps(magnitude, _mm_add_ps(absPs(c[i]), e[i]));
  }
  const __m128 finite = _mm_cmplt_ps(sum, _mm_set1_ps(std::numeric_limits<float>::infinity()));
  __m128 near = selectPs(finite, _mm_sqrt_ps(sum), biggest);
  near = _mm_max_ps(_mm_sub_ps(near, _mm_mul_ps(slack, _mm_add_ps(near, magnitude))),
                    _mm_setzero_ps());
  _mm_store_ps(this->near, near);

  // Present, within tmax, and (planar) meeting the plane.
  __m128 ok = _mm_cmple_ps(near, f.tmax_);
  if (f.planar_ && !f.spread_.any) ok = _mm_and_ps(ok, _mm_cmple_ps(absPs(c[2]), e[2]));
  if (f.planar_ && f.spread_.any) {
    // A tilted column's plane rises at most (distance + shift) sin(tilt) above the reference one;
    // magnitude bounds the distance, and the factor the rounding of the product.
    const __m128 rise = _mm_mul_ps(_mm_add_ps(magnitude, f.spread_.shift), f.spread_.sin_tilt);
    const __m128 reach = _mm_mul_ps(_mm_add_ps(e[2], rise), _mm_set1_ps(1 + 8 * kViewSlack));
    ok = _mm_and_ps(ok, _mm_cmple_ps(absPs(c[2]), reach));
  }
  mask = _mm_movemask_ps(ok) & node.presentMask();
  if (!mask) return;

  // Azimuths: the box's xy extent lies in a disc of radius r around (cx, cy); seen from the
  // sensor the disc spans half-angle asin(r / rho) <= r / sqrt(rho^2 - r^2), unless it holds the
  // z axis (or nearly: then every azimuth).
  const __m128 rho2 = _mm_add_ps(_mm_mul_ps(c[0], c[0]), _mm_mul_ps(c[1], c[1]));
  const __m128 r2 = _mm_add_ps(_mm_mul_ps(e[0], e[0]), _mm_mul_ps(e[1], e[1]));
  const __m128 limited = _mm_cmpgt_ps(rho2, _mm_mul_ps(r2, _mm_set1_ps(1 + 8 * kViewSlack)));
  const __m128 denom = _mm_sqrt_ps(_mm_max_ps(_mm_sub_ps(rho2, r2), _mm_set1_ps(1e-30f)));
  __m128 half = _mm_mul_ps(_mm_div_ps(_mm_sqrt_ps(r2), denom), _mm_set1_ps(1 + 8 * kViewSlack));
  __m128 center = atan2Ps(c[1], c[0]);
  // The circle is loose (up to 1.4 times a square box's azimuths, many times a long box's seen end
  // on): the corners narrow it.
  narrowByCorners(f, c, eb, mag, rho2, &center, &half);
  half = _mm_add_ps(half, _mm_set1_ps(static_cast<float>(2 * kBearingError)));
  half = f.spread_.widenHalf(half);
  const __m128 narrow =
      f.spread_.keepLimited(_mm_and_ps(limited, _mm_cmplt_ps(half, _mm_set1_ps(1.5f))));
  _mm_store_ps(az_half, selectPs(narrow, half, _mm_set1_ps(-1)));
  _mm_store_ps(az_center, center);
  if (f.planar_) return;
  storeElevations(c, e, rho2, r2, el_lo, el_hi);
  if (!f.spread_.any) return;
  _mm_store_ps(el_lo, _mm_sub_ps(_mm_load_ps(el_lo), f.spread_.turn));
  _mm_store_ps(el_hi, _mm_add_ps(_mm_load_ps(el_hi), f.spread_.turn));
}

void NodeViews::narrowByCorners(const ViewBasis& f, const __m128 c[3], const __m128 eb[3],
                                const __m128 mag[3], __m128 rho2, __m128* center, __m128* half) {
  // A corner is the centre plus or minus the three rotated half extents; each of its x, y is a
  // few roundings off, at most the slack times that axis's magnitude.
  __m128 px[3], py[3];
  for (int k = 0; k < 3; ++k) {
    px[k] = _mm_mul_ps(f.rot_[0][k], eb[k]);
    py[k] = _mm_mul_ps(f.rot_[1][k], eb[k]);
  }
  CornerTangents corners;
  for (int s = 0; s < 8; ++s) {
    __m128 x = c[0], y = c[1];
    for (int k = 0; k < 3; ++k) {
      x = (s >> k) & 1 ? _mm_add_ps(x, px[k]) : _mm_sub_ps(x, px[k]);
      y = (s >> k) & 1 ? _mm_add_ps(y, py[k]) : _mm_sub_ps(y, py[k]);
    }
    corners.add(x, y, c[0], c[1], rho2);
  }
  __m128 error = _mm_mul_ps(_mm_set1_ps(kViewSlack), _mm_add_ps(mag[0], mag[1]));
  if (f.spread_.any) {
    // The box grown by the shift: each corner's x, y moves by up to sqrt(2) shift more. The bound
    // of narrow() (four times the turn of a corner within 60 degrees of the centre) holds for a
    // corner moved a little beyond 60 degrees if the factor is 5 (sec^2 of 63.4 degrees): kept
    // only where the move is below 5 % of the nearest corner's distance (so within 3 degrees).
    error = _mm_add_ps(error, _mm_mul_ps(f.spread_.shift, _mm_set1_ps(1.5f)));
    const __m128 small = _mm_cmple_ps(
        _mm_mul_ps(_mm_mul_ps(error, _mm_sqrt_ps(rho2)), _mm_set1_ps(20.0f)), corners.min_dot);
    corners.ok = _mm_and_ps(corners.ok, small);
    error = _mm_mul_ps(error, _mm_set1_ps(1.25f));
  }
  corners.narrow(error, rho2, center, half);
}

int planeMask(const WideBvh::Node& node, const ViewBasis& f) {
  const __m128 half_ps = _mm_set1_ps(0.5f);
  const __m128 slack = _mm_set1_ps(kViewSlack);
  __m128 cz = f.trans_[2], ez = _mm_setzero_ps(), mag = f.abs_trans_[2];
  for (int k = 0; k < 3; ++k) {
    const __m128 lo = _mm_load_ps(node.lo[k]), hi = _mm_load_ps(node.hi[k]);
    const __m128 cb = _mm_mul_ps(_mm_add_ps(lo, hi), half_ps);
    const __m128 eb = _mm_mul_ps(_mm_sub_ps(hi, lo), half_ps);
    cz = _mm_add_ps(cz, _mm_mul_ps(f.rot_[2][k], cb));
    ez = _mm_add_ps(ez, _mm_mul_ps(f.abs_rot_[2][k], eb));
    mag = _mm_add_ps(mag, _mm_mul_ps(f.abs_rot_[2][k], _mm_add_ps(absPs(cb), eb)));
  }
  ez = _mm_add_ps(ez, _mm_mul_ps(slack, _mm_add_ps(mag, ez)));
  return _mm_movemask_ps(_mm_cmple_ps(absPs(cz), ez)) & node.presentMask();
}

}  // namespace core
}  // namespace laser_raycast
