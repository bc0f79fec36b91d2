// Which beams of a scan pattern can reach a thing: the azimuth and elevation windows of a bounding
// sphere or a segment as seen from the sensor, and the beam index ranges inside an azimuth window.
// Every window here is conservative (it may hold beams that miss; the exact tests decide), so these
// functions only decide how much work is done, never a range.
#pragma once

#include <emmintrin.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "laser_raycast/core/scan_pattern.h"

namespace laser_raycast {
namespace core {

// Relative slack for window tests, which round a few times: a thing is left out only if it is out
// by more than this fraction of the magnitudes compared. Not an absolute epsilon.
inline constexpr double kWindowSlack = 8 * std::numeric_limits<double>::epsilon();

// Beam index ranges of a fan that may see the angular interval [start, start + width] (rad, start
// measured from angle_min, width in [0, 2 pi]): every beam whose azimuth lies in the interval, and
// those within the rounding of the index arithmetic of its ends (a few ulps of the angles
// involved). The interval itself must already hold every error of how it was found. Calls
// f(first, last) for each index range (more than one when the fan spans more than a turn); the
// ranges are increasing and disjoint, so no beam is visited twice.
// floor(x) and ceil(x) for |x| < 2^31, without a call into libm (SSE2 has no rounding
// instruction).
inline int floorToInt(double x) {
  const int i = static_cast<int>(x);  // truncates towards zero
  return i - (x < i);
}
inline int ceilToInt(double x) {
  const int i = static_cast<int>(x);
  return i + (x > i);
}

template <class F>
void forEachBeamRange(const ScanPattern& fan, double start, double width, F&& f) {
  const double inc = fan.angleIncrement();
  const int n = fan.azimuthCount();
  const double span = (n - 1) * inc;
  const double pad = 64 * std::numeric_limits<double>::epsilon() * (span + width + 4 * M_PI);
  // Window positions in units of beams, clamped far beyond the fan so that the conversions to int
  // cannot overflow (a window never needs more than the fan's own index range).
  const double limit = n + 2.0;
  auto index = [&](double angle) { return std::max(-limit, std::min(limit, angle / inc)); };
  int next = 0;  // the first beam not yet visited
  for (int turn = -1;; ++turn) {
    const double lo = start + turn * 2 * M_PI - pad;
    const double hi = lo + width + 2 * pad;
    if (lo > span) break;
    if (hi < 0) continue;
    const int first = std::max(next, ceilToInt(index(lo)));
    const int last = std::min(n - 1, floorToInt(index(hi)));
    if (first <= last) {
      f(first, last);
      next = last + 1;
    }
  }
}

// atan2(y, x) to within kBearingError rad, much cheaper than std::atan2, for windows only. The
// polynomial is Abramowitz and Stegun's 4.4.49 (Handbook of Mathematical Functions, 1964): atan(a)
// for a in [0, 1] with an error of at most 1e-5 rad; the other octants follow by symmetry.
// kBearingError is twice that, which leaves room for the rounding of the division and the octant
// reflections (a few ulps of pi).
inline constexpr double kBearingError = 2e-5;
// The polynomial's coefficients, from a's on (approxAtan2 and approxAtan2Pair).
inline constexpr double kAtanPoly[5] = {0.9998660, -0.3302995, 0.1801410, -0.0851330, 0.0208351};
inline double approxAtan2(double y, double x) {
  const double ax = std::abs(x), ay = std::abs(y);
  const double big = std::max(ax, ay);
  if (!(big > 0)) return 0;
  const double a = std::min(ax, ay) / big;
  const double z = a * a;
  const double* c = kAtanPoly;
  double r = a * (c[0] + z * (c[1] + z * (c[2] + z * (c[3] + z * c[4]))));
  if (ay > ax) r = M_PI / 2 - r;
  if (x < 0) r = M_PI - r;
  return y < 0 ? -r : r;
}

// approxAtan2 of two points at once, (y0, x0) into *r0 and (y1, x1) into *r1: the same operations
// in the same order on SSE2's two doubles, so the same bits, with one division for both (a
// segment's two ends, forSegmentColumns in slice/slicer.h).
inline void approxAtan2Pair(double y0, double x0, double y1, double x1, double* r0, double* r1) {
  const __m128d sign = _mm_set1_pd(-0.0);
  const __m128d x = _mm_set_pd(x1, x0), y = _mm_set_pd(y1, y0);
  const __m128d ax = _mm_andnot_pd(sign, x), ay = _mm_andnot_pd(sign, y);
  // std::max(ax, ay) and std::min(ax, ay), NaN included: (ax < ay ? ay : ax), (ay < ax ? ay : ax).
  const __m128d big = _mm_max_pd(ay, ax), small = _mm_min_pd(ay, ax);
  const __m128d nonzero = _mm_cmpgt_pd(big, _mm_setzero_pd());
  const __m128d a = _mm_div_pd(small, big);
  const __m128d z = _mm_mul_pd(a, a);
  __m128d p = _mm_mul_pd(z, _mm_set1_pd(kAtanPoly[4]));
  for (int k = 3; k >= 1; --k) p = _mm_mul_pd(z, _mm_add_pd(_mm_set1_pd(kAtanPoly[k]), p));
  __m128d r = _mm_mul_pd(a, _mm_add_pd(_mm_set1_pd(kAtanPoly[0]), p));
  auto select = [](__m128d mask, __m128d if_set, __m128d if_clear) {
    return _mm_or_pd(_mm_and_pd(mask, if_set), _mm_andnot_pd(mask, if_clear));
  };
  r = select(_mm_cmpgt_pd(ay, ax), _mm_sub_pd(_mm_set1_pd(M_PI / 2), r), r);
  r = select(_mm_cmplt_pd(x, _mm_setzero_pd()), _mm_sub_pd(_mm_set1_pd(M_PI), r), r);
  r = _mm_xor_pd(r, _mm_and_pd(_mm_cmplt_pd(y, _mm_setzero_pd()), sign));
  r = _mm_and_pd(nonzero, r);  // 0 where !(big > 0)
  _mm_storel_pd(r0, r);
  _mm_storeh_pd(r1, r);
}

// angle wrapped into [0, 2 pi).
inline double wrapToTurn(double angle) {
  const double turns = angle / (2 * M_PI);
  const double whole = std::abs(turns) < 1e9 ? floorToInt(turns) : std::floor(turns);
  const double a = angle - 2 * M_PI * whole;
  return a < 2 * M_PI ? a : 0.0;
}

// The azimuth interval that a sphere at `center` (sensor frame) can occupy, as forEachBeamRange
// takes it: start measured from angle_min in [0, 2 pi), width less than pi. False if it spans half
// a turn or more, or surrounds the sensor's z axis: every azimuth. Conservative: the half-width is
// tan(asin(r / rho)) = r / sqrt(rho^2 - r^2) (cheaper than asin, and never smaller), widened by the
// bearing's error (twice: once for the centre's bearing, once more as margin for the rounding of
// the half-width).
inline bool azimuthWindow(const Eigen::Vector3d& center, double radius, double angle_min,
                          double* start, double* width) {
  const double rho2 = center.x() * center.x() + center.y() * center.y();
  const double r = radius * (1 + kWindowSlack);
  if (!(rho2 > r * r)) return false;
  const double half = r / std::sqrt(rho2 - r * r) * (1 + kWindowSlack) + 2 * kBearingError;
  if (!(half < M_PI / 2)) return false;
  *start = wrapToTurn(approxAtan2(center.y(), center.x()) - half - angle_min);
  *width = 2 * half;
  return true;
}

// The elevation interval (rad) that a sphere at `center` (sensor frame) can occupy; all of
// [-pi/2, pi/2] if it contains the sensor. Widened for the rounding of asin and its arguments:
// relatively, and by kWindowSlack rad, which is relative too since elevations are of order 1.
inline void elevationWindow(const Eigen::Vector3d& center, double radius, double* lo, double* hi) {
  const double dist = center.norm();
  if (!(dist > radius * (1 + kWindowSlack))) {
    *lo = -M_PI / 2;
    *hi = M_PI / 2;
    return;
  }
  const double half =
      std::asin(std::min(1.0, radius * (1 + kWindowSlack) / dist)) * (1 + kWindowSlack);
  const double middle = std::asin(std::max(-1.0, std::min(1.0, center.z() / dist)));
  *lo = middle - half - kWindowSlack;
  *hi = middle + half + kWindowSlack;
}

// How a sphere or a box looks from the sensor (sensor frame), conservatively.
struct View {
  double near;                          // no point of it is nearer to the sensor than this
  bool crosses;                         // it may meet the scan plane (sensor z = 0)
  bool azimuth_limited;                 // else it may be seen at any azimuth
  double azimuth_start, azimuth_width;  // as forEachBeamRange takes them
  double elevation_lo, elevation_hi;    // rad
};

// How far the beams of a block of a rotating sweep stray from the pose they are culled from
// (beams/column_motion.h): each beam leaves from its own column's pose, at most `shift` m from the
// reference origin and turned by at most `turn` rad from its pattern direction, its column's z axis
// tilted by at most `tilt` rad. A view of a box is widened to hold every such beam that meets it:
// the box grown by `shift` on each axis (which holds every origin's offset), its elevations by
// `turn`, its azimuths by `azimuth` (the most a turn of `turn` moves the azimuth of a direction at
// most `steepest` rad from the horizontal; infinite: every azimuth), and its crossing of the scan
// plane by the tilt. All zero: a scan from one pose, nothing widened.
struct Spread {
  double shift = 0, turn = 0, tilt = 0, azimuth = 0;
  bool any() const { return shift > 0 || turn > 0; }
  // From the largest offset, turn and tilt of a block's columns (each widened here for the
  // rounding of how they were found) and the steepest beam of the pattern (rad from horizontal).
  static Spread of(double shift, double turn, double tilt, double steepest);
};

// The view of a sphere; of a box given by its centre and half extents in a frame whose pose in the
// sensor frame is (rot, trans) (abs_rot: rot with its entries' magnitudes). The box view bounds the
// box by its sensor-frame bounding box; with a spread, the view holds every beam of it that meets
// the box.
View sphereView(const Eigen::Vector3d& center, double radius, double angle_min);
View boxView(const Eigen::Vector3d& center, const Eigen::Vector3d& half, const Eigen::Matrix3d& rot,
             const Eigen::Matrix3d& abs_rot, const Eigen::Vector3d& trans, double angle_min,
             bool elevations, const Spread& spread = Spread());
// The view of a triangle given in the sensor frame: its bounding box's.
View triangleView(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                  double angle_min, bool elevations, const Spread& spread = Spread());

}  // namespace core
}  // namespace laser_raycast
