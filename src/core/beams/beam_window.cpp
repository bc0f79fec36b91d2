#include "beams/beam_window.h"

#include <algorithm>
#include <cmath>

namespace laser_raycast {
namespace core {

namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();
// A hit's t and the distance to its box round differently (as BvhT::traverse notes): a box's near
// distance is lowered by this many ulps of the magnitudes involved before it hides anything.
constexpr double kNearSlack = 64 * kEps;

}  // namespace

View sphereView(const Eigen::Vector3d& center, double radius, double angle_min) {
  View v;
  const double dist = center.norm();
  const double slack = kWindowSlack * (dist + radius);
  v.near = std::max(0.0, dist - radius - slack - kNearSlack * (dist + radius));
  v.crosses = std::abs(center.z()) <= radius + slack;
  v.azimuth_limited = azimuthWindow(center, radius, angle_min, &v.azimuth_start, &v.azimuth_width);
  elevationWindow(center, radius, &v.elevation_lo, &v.elevation_hi);
  return v;
}

Spread Spread::of(double shift, double turn, double tilt, double steepest) {
  Spread s;
  // The beams start exactly at the offsets the shift was taken from (widened for the rounding of
  // the norm); the angles come from differences R - I of entries of order 1, each a few ulps off,
  // and the beams' directions are rounded once more when turned: a relative widening and 16 ulps
  // of 1.
  s.shift = shift > 0 ? shift * (1 + 1e-9) : 0;
  s.turn = turn > 0 ? turn * (1 + 1e-9) + 16 * kEps : 0;
  s.tilt = tilt > 0 ? tilt * (1 + 1e-9) + 16 * kEps : 0;
  // Two unit vectors at most `turn` apart, both within E of the horizontal, have horizontal
  // parts of length >= cos E whose angle b satisfies cos E sin b <= 2 sin(turn / 2) (the chord).
  const double e = std::min(M_PI / 2, steepest + s.turn);
  const double chord = 2 * std::sin(s.turn / 2) * (1 + 4 * kEps);
  const double cos_e = std::cos(e) * (1 - 4 * kEps);
  s.azimuth = s.turn == 0 ? 0
              : chord < 0.5 * cos_e ? std::asin(chord / cos_e) * (1 + 4 * kEps) + 4 * kEps
                                    : std::numeric_limits<double>::infinity();
  return s;
}

View boxView(const Eigen::Vector3d& center, const Eigen::Vector3d& half, const Eigen::Matrix3d& rot,
             const Eigen::Matrix3d& abs_rot, const Eigen::Vector3d& trans, double angle_min,
             bool elevations, const Spread& spread) {
  View v;
  const Eigen::Vector3d c = rot * center + trans;
  // The sensor-frame bounding box, widened for the rounding of c and e (a few ulps of the terms),
  // and by the spread's shift.
  Eigen::Vector3d e = abs_rot * half;
  e += 4 * kEps * (abs_rot * center.cwiseAbs() + trans.cwiseAbs() + e);
  e.array() += spread.shift;
  const Eigen::Vector3d gap = (c.cwiseAbs() - e).cwiseMax(0.0);
  const double magnitude = c.cwiseAbs().sum() + e.sum();
  v.near = std::max(0.0, gap.norm() * (1 - 4 * kEps) - kNearSlack * magnitude);
  // A point of a tilted column's plane is at most (its distance + shift) sin(tilt) above the
  // reference plane (beyond the shift, which e holds).
  v.crosses = std::abs(c.z()) <= e.z() + (magnitude + spread.shift) * std::sin(spread.tilt);
  const double r_xy = std::sqrt(e.x() * e.x() + e.y() * e.y()) * (1 + 4 * kEps);
  v.azimuth_limited = azimuthWindow(c, r_xy, angle_min, &v.azimuth_start, &v.azimuth_width);
  if (v.azimuth_limited && spread.azimuth > 0) {
    v.azimuth_width += 2 * spread.azimuth;
    v.azimuth_start = wrapToTurn(v.azimuth_start - spread.azimuth);
    v.azimuth_limited = v.azimuth_width < M_PI;
  }
  if (!elevations) {
    v.elevation_lo = -M_PI / 2;
    v.elevation_hi = M_PI / 2;
    return v;
  }
  // Any point has height in [z_lo, z_hi] and horizontal distance in [rho_min, rho_max]; its
  // elevation atan2(z, rho) is largest at the top and the nearest distance (farthest if the top is
  // below the sensor), and likewise for the smallest.
  const double rho = std::sqrt(c.x() * c.x() + c.y() * c.y());
  const double rho_min = std::max(0.0, (rho - r_xy) * (1 - 4 * kEps));
  const double rho_max = (rho + r_xy) * (1 + 4 * kEps);
  const double z_lo = c.z() - e.z(), z_hi = c.z() + e.z();
  v.elevation_hi = approxAtan2(z_hi, z_hi > 0 ? rho_min : rho_max) + kBearingError + spread.turn;
  v.elevation_lo = approxAtan2(z_lo, z_lo < 0 ? rho_min : rho_max) - kBearingError - spread.turn;
  return v;
}

View triangleView(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                  double angle_min, bool elevations, const Spread& spread) {
  const Eigen::Vector3d lo = a.cwiseMin(b).cwiseMin(c), hi = a.cwiseMax(b).cwiseMax(c);
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  return boxView((lo + hi) * 0.5, (hi - lo) * 0.5, identity, identity, Eigen::Vector3d::Zero(),
                 angle_min, elevations, spread);
}

}  // namespace core
}  // namespace laser_raycast
