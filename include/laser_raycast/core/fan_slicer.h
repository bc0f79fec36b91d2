// The planar fast path: a 2D fan needs only the triangles that cross its plane. Each crossing
// triangle is cut into a segment in the scan plane and written into a 1D angular depth buffer, so
// the cost grows with the number of crossing triangles and beams, not with rays times tree depth.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "laser_raycast/core/mesh.h"
#include "laser_raycast/core/scan_pattern.h"

namespace laser_raycast {
namespace core {

// The per-beam nearest hit so far: distance, body and triangle.
struct DepthBuffer {
  std::vector<double>* range;
  std::vector<int>* body;
  std::vector<int>* triangle;
  // If set, every segment a beam crosses within [tmin, tmax] is counted, nearest or not: a closed
  // mesh's outline is crossed exactly once per beam from inside (the watertightness tests use it).
  std::vector<int>* crossings = nullptr;
};

// Beam index ranges of a fan that may see the angular interval [start, start + width] (rad, start
// measured from angle_min, width in [0, 2 pi]). Padded by one beam each side: the exact side test
// decides. Calls f(first, last) for each index range (more than one when the fan spans more than a
// turn); the ranges are increasing and disjoint, so no beam is visited twice even when the padding
// of a coarse fan makes consecutive turns' windows overlap.
template <class F>
void forEachBeamRange(const ScanPattern& fan, double start, double width, F&& f) {
  const double inc = fan.angleIncrement();
  const int n = fan.azimuthCount();
  const double span = (n - 1) * inc;
  int next = 0;  // the first beam not yet visited
  for (int turn = -1;; ++turn) {
    const double lo = start + turn * 2 * M_PI;
    const double hi = lo + width;
    if (lo > span + inc) break;
    if (hi < -inc) continue;
    const int first = std::max(next, static_cast<int>(std::ceil(lo / inc)) - 1);
    const int last = std::min(n - 1, static_cast<int>(std::floor(hi / inc)) + 1);
    if (first <= last) {
      f(first, last);
      next = last + 1;
    }
  }
}

// atan2(y, x) to within kBearingError rad, for the beam windows, which only need to be
// conservative (the exact side tests decide). The polynomial approximates atan on [0, 1] with an
// error of at most 1.15e-5 rad; kBearingError leaves room for rounding. Much cheaper than atan2.
inline constexpr double kBearingError = 2e-5;
inline double approxAtan2(double y, double x) {
  const double ax = std::abs(x), ay = std::abs(y);
  const double big = std::max(ax, ay);
  if (!(big > 0)) return 0;
  const double a = std::min(ax, ay) / big;
  const double z = a * a;
  double r =
      a * (0.9998660 + z * (-0.3302995 + z * (0.1801410 + z * (-0.0851330 + z * 0.0208351))));
  if (ay > ax) r = M_PI / 2 - r;
  if (x < 0) r = M_PI - r;
  return y < 0 ? -r : r;
}

// angle wrapped into [0, 2 pi).
inline double wrapToTurn(double angle) {
  double a = angle - 2 * M_PI * std::floor(angle / (2 * M_PI));
  return a < 2 * M_PI ? a : 0.0;
}

// The azimuth interval that a sphere at `center` (sensor frame) can occupy, as forEachBeamRange
// takes it: start measured from angle_min in [0, 2 pi), width less than pi. False if it spans half
// a turn or more, or surrounds the sensor's z axis: every azimuth. Conservative: the half-width is
// tan(asin(r / rho)) = r / sqrt(rho^2 - r^2) (cheaper than asin, and never smaller), widened by the
// bearing's error.
inline bool azimuthWindow(const Eigen::Vector3d& center, double radius, double angle_min,
                          double* start, double* width) {
  constexpr double kSlack = 8 * std::numeric_limits<double>::epsilon();
  const double rho2 = center.x() * center.x() + center.y() * center.y();
  const double r = radius * (1 + kSlack);
  if (!(rho2 > r * r)) return false;
  const double half = r / std::sqrt(rho2 - r * r) * (1 + kSlack) + 2 * kBearingError;
  if (!(half < M_PI / 2)) return false;
  *start = wrapToTurn(approxAtan2(center.y(), center.x()) - half - angle_min);
  *width = 2 * half;
  return true;
}

// Slices one mesh body by the fan's plane (the sensor's z = 0) and keeps, per beam, the nearest hit
// with t in [tmin, tmax]. Watertight: each crossing point is computed from its edge's two vertices
// in a fixed (lexicographic) order, so neighbouring triangles share bitwise-identical segment
// endpoints, and a beam is tested against a segment by the signs of two cross products with those
// endpoints. A beam exactly through a shared endpoint counts for one of the two segments (half-open
// segments), and a vertex exactly on the plane counts as just below it, so that an edge lying in
// the plane is cut once: a beam crosses a closed outline exactly once. A surface that only touches
// the plane from below (the top of a box at exactly the sensor's height) is therefore not seen;
// triangles lying in the plane are skipped, as the 3D tests skip a ray in a triangle's plane.
void sliceMesh(const Mesh& mesh, const Eigen::Isometry3d& sensor_from_mesh, const ScanPattern& fan,
               double tmin, double tmax, bool cull_backfaces, int body_index, DepthBuffer buffer);

}  // namespace core
}  // namespace laser_raycast
