#include "beams/column_raster.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "util/float_rounding.h"

namespace laser_raycast {
namespace core {
namespace {

// Normals scaled to |m|_1 = 1 must stay far from float's underflow: a smaller triple product (a
// triangle of a few 1e-19 m, or one seen within 1e-20 of edge-on) tests every beam.
constexpr double kSmallest = 1e-30;

}  // namespace

ColumnRaster::ColumnRaster(const BeamSet& beams, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                           const Eigen::Vector3d& c, double widen, double shift, double turn) {
  // In double: a small or far triangle's edge normals cancel far beyond float's precision.
  const Eigen::Vector3d m[3] = {b.cross(c), c.cross(a), a.cross(b)};
  init(beams, a, b, c, m, widen, shift, turn);
}

ColumnRaster::ColumnRaster(const BeamSet& beams, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                           const Eigen::Vector3d& c, const ColumnMotion& motion, double near) {
  const double shift = motion.spread().shift, turn = motion.spread().turn;
  const Eigen::Vector3d m[3] = {b.cross(c), c.cross(a), a.cross(b)};
  // The plane's distance: its normal (b - a) x (c - a) is the edge normals' sum, whose dot product
  // with a is a . (b x c).
  if (shift == 0) {
    // Every beam from the sensor (a bundle's sub-rays, or a turn alone): the reference's edge
    // planes, widened by the turn.
    init(beams, a, b, c, m, motion.sinTurn(), 0, turn);
    return;
  }
  const double plane = std::abs(a.dot(m[0])) / (m[0] + m[1] + m[2]).norm() * (1 - 1e-9);
  if (std::isfinite(plane) && plane > 2 * shift) {
    motion_ = &motion;
    init(beams, a, b, c, m, motion.sinTurn(), shift, turn, motion.deviation());
    return;
  }
  // The plane passes near the sensor: every edge test widened by the shift, from the triangle's
  // nearest point (the larger of the leaf's near and the plane's distance).
  const double nearest = std::max(near, std::isfinite(plane) ? plane : 0.0);
  const double widen = nearest > 2 * shift
                           ? std::sin(std::min(M_PI / 2, turn + std::asin(shift / nearest)))
                           : 1;  // every beam of the rect
  init(beams, a, b, c, m, widen, shift, turn);
}

void ColumnRaster::init(const BeamSet& beams, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                        const Eigen::Vector3d& c, const Eigen::Vector3d (&m)[3], double widen,
                        double shift, double turn, double deviation) {
  const double det = a.dot(m[0]);
  const double abs_det = std::abs(det);
  // The 1-norms bound the 2-norms from above, so this flags a few more triangles than the ratio
  // says: they are tested with every beam of the rect.
  all_ = !(abs_det > kEdgeOnRatio * a.lpNorm<1>() * b.lpNorm<1>() * c.lpNorm<1>()) ||
         !(abs_det > kSmallest) || !(widen < 0.5);
  if (all_) return;
  const double sign = det > 0 ? 1 : -1;
  // The edges whose cross product with a column's origin moves m (m - o x e).
  const Eigen::Vector3d e[3] = {c - b, a - c, b - a};
  double moves = 0;  // the most |o x e|_2 <= shift |e|_1 moves a scaled normal
  // The most a beam's origin off its column's by at most `deviation` moves its column's normal
  // (|d x e|_2 <= deviation |e|_1): the edge tests' margin grows by it.
  double deviates = 0;
  for (int k = 0; k < 3; ++k) {
    const double scale = sign / (std::abs(m[k].x()) + std::abs(m[k].y()) + std::abs(m[k].z()));
    const float z = static_cast<float>(m[k].z() * scale);
    mx_[k] = _mm_set1_ps(static_cast<float>(m[k].x() * scale));
    my_[k] = _mm_set1_ps(static_cast<float>(m[k].y() * scale));
    inv_mz_[k] = _mm_set1_ps(z != 0 ? 1 / z : 0.0f);
    kind_[k] = z > 0 ? EdgeKind::kLower : z < 0 ? EdgeKind::kUpper : EdgeKind::kFlat;
    if (motion_) {
      const Eigen::Vector3d scaled = e[k] * scale;
      mz_[k] = _mm_set1_ps(z);
      ex_[k] = _mm_set1_ps(static_cast<float>(scaled.x()));
      ey_[k] = _mm_set1_ps(static_cast<float>(scaled.y()));
      ez_[k] = _mm_set1_ps(static_cast<float>(scaled.z()));
      const double edge_moves = shift * scaled.lpNorm<1>();
      moves = std::max(moves, edge_moves);
      deviates = std::max(deviates, deviation * scaled.lpNorm<1>());
      // Every column's m_z = z - (o x e)_z, which moves by at most edge_moves: with room to
      // spare for float, its sign is the reference's in every column.
      column_kind_[k] = std::abs(z) > 2 * edge_moves * (1 + 1e-6) ? kind_[k] : EdgeKind::kAny;
    }
  }
  // A column's normal's |m'|_1 <= 1 + |o x e|_1 <= 1 + sqrt(3) |o x e|_2, a beam's within the
  // deviation of it.
  const double factor = 1 + std::sqrt(3.0) * (moves + deviates);
  widen = (widen + deviates) * factor;
  if (!(widen < 0.5)) {
    all_ = true;
    return;
  }
  edge_margin_ = _mm_set1_ps(floatAbove((kMargin * factor + widen * (1 + 1e-6)) /
                                        beams.grid().smallestRowCos()));
  reference_margin_ =
      motion_ ? _mm_set1_ps(floatAbove((kMargin * factor + (widen + moves) * (1 + 1e-6)) /
                                       beams.grid().smallestRowCos()))
              : edge_margin_;
  // The plane's normal (b - a) x (c - a) is the sum of the edge normals, and its dot product with
  // a is det.
  const Eigen::Vector3d plane = m[0] + m[1] + m[2];
  const double scale = 1 / (std::abs(plane.x()) + std::abs(plane.y()) + std::abs(plane.z()));
  nx_ = _mm_set1_ps(static_cast<float>(plane.x() * scale));
  ny_ = _mm_set1_ps(static_cast<float>(plane.y() * scale));
  nz_ = static_cast<float>(plane.z() * scale);
  plane_distance_ = static_cast<float>(
      std::max(0.0, abs_det * scale * (1 - kMargin) - shift * (1 + 1e-6)));
  if (turn > 0) along_margin_ = floatAbove(kMargin + turn * (1 + 1e-6));
}

}  // namespace core
}  // namespace laser_raycast
