#include "slice/slicer.h"

#include <cmath>

namespace laser_raycast {
namespace core {
namespace {

bool lexicographicLess(const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
  if (p.x() != q.x()) return p.x() < q.x();
  if (p.y() != q.y()) return p.y() < q.y();
  return p.z() < q.z();
}

// Where edge (p, q) (mesh coordinates) crosses the plane, in plane coordinates, given the vertices'
// signed distances, sp <= 0 < sq or the other way round, and their plane coordinates wp, wq. A
// vertex on the plane (distance 0) is its own crossing, bit for bit. Otherwise the crossing is
// interpolated from the lexicographically first vertex, so both triangles sharing the edge get the
// same bits.
Eigen::Vector2d edgeCrossing(const Eigen::Vector3d& p, double sp, const Eigen::Vector2d& wp,
                             const Eigen::Vector3d& q, double sq, const Eigen::Vector2d& wq) {
  if (sp == 0) return wp;
  if (sq == 0) return wq;
  // sp and sq differ in sign: no cancellation.
  if (lexicographicLess(q, p)) return wq + (wp - wq) * (sq / (sq - sp));
  return wp + (wq - wp) * (sp / (sp - sq));
}

// A unit vector perpendicular to n, from n alone: n crossed with the axis it is least aligned with
// (the first of them on a tie).
Eigen::Vector3d perpendicular(const Eigen::Vector3d& n) {
  const Eigen::Vector3d m = n.cwiseAbs();
  const int axis = m.x() <= m.y() && m.x() <= m.z() ? 0 : (m.y() <= m.z() ? 1 : 2);
  return n.cross(Eigen::Vector3d::Unit(axis)).normalized();
}

// x to its kKeptPlaneBits most significant bits (to nearest): a plane met again differs by a few
// ulp in the last ones when TF composes its poses (a laser 1.2 m up on a base that turns: the
// rotation of its offset by a quaternion gives 1.2 (c^2 + s^2), the heading's c and s, so the
// plane's offset moves by ulps as the robot turns), and a kept slice is found by its plane's bits.
double keptBits(double x) {
  int e;
  const double m = std::frexp(x, &e);
  if (m == 0 || !std::isfinite(m)) return x;
  constexpr int kBits = ScanPlane::kKeptPlaneBits;
  return std::ldexp(std::nearbyint(std::ldexp(m, kBits)), e - kBits);
}

}  // namespace

ScanPlane::ScanPlane(const Eigen::Isometry3d& sensor_from_frame) {
  const Eigen::Matrix3d& rot = sensor_from_frame.linear();
  const Eigen::Vector3d& trans = sensor_from_frame.translation();
  n = rot.row(2).transpose().unaryExpr(&keptBits);
  offset = keptBits(trans.z());
  u = perpendicular(n);
  v = n.cross(u);
  a = rot.row(0).dot(u);
  b = rot.row(0).dot(v);
  c = rot.row(1).dot(u);
  d = rot.row(1).dot(v);
  tx = trans.x();
  ty = trans.y();
}

MeshCut::MeshCut(const ScanPlane& plane, const Eigen::Isometry3d& frame_from_mesh) {
  const Eigen::Matrix3d& rot = frame_from_mesh.linear();
  const Eigen::Vector3d& trans = frame_from_mesh.translation();
  const Eigen::Vector3d* axes[3] = {&plane.n, &plane.u, &plane.v};
  for (int r = 0; r < 3; ++r) {
    const Eigen::Vector3d row = rot.transpose() * *axes[r];
    for (int k = 0; k < 3; ++k) rows_[r][k] = row[k];
    offsets_[r] = axes[r]->dot(trans);
  }
  offsets_[0] += plane.offset;
}

bool MeshCut::crossing(const std::array<Eigen::Vector3d, 3>& v, Eigen::Vector2d* p,
                       Eigen::Vector2d* q) const {
  // Each row's value at a vertex, always summed in the same order (map()), so that a vertex gets
  // the same bits in every triangle.
  double s[3];
  for (int k = 0; k < 3; ++k) s[k] = map(0, v[k]);
  // A vertex exactly on the plane counts as just below it (the plane nudged up by an
  // infinitesimal): an edge lying in the plane is then cut once, by the triangle above it, not
  // twice; a triangle touching the plane from below, or lying in it, is not cut (as a ray in a
  // triangle's plane misses it); one touching it from above gives a zero-length segment, which no
  // beam crosses. Every crossing triangle has exactly two edges with one end below and one above.
  const bool above[3] = {s[0] > 0, s[1] > 0, s[2] > 0};
  if (above[0] == above[1] && above[1] == above[2]) return false;  // also NaN: never above
  Eigen::Vector2d w[3];
  for (int k = 0; k < 3; ++k) w[k] = {map(1, v[k]), map(2, v[k])};
  Eigen::Vector2d* out[2] = {p, q};
  int count = 0;
  for (int k = 0; k < 3; ++k) {
    const int j = k == 2 ? 0 : k + 1;
    if (above[k] != above[j]) *out[count++] = edgeCrossing(v[k], s[k], w[k], v[j], s[j], w[j]);
  }
  return true;
}

bool ScanPlane::mayMeet(const Eigen::Isometry3d& frame_from_mesh, const Aabb& box) const {
  Eigen::Vector3d c, e;
  boxInFrame(frame_from_mesh, box, &c, &e);
  const Eigen::Vector3d abs_n = n.cwiseAbs();
  // side() rounds a few times at magnitudes up to |n| (|c| + e) + |offset|.
  const double slack =
      2 * roundingGamma<double>(6) * (abs_n.dot(c.cwiseAbs() + e) + std::abs(offset));
  return std::abs(side(c)) <= abs_n.dot(e) + slack;
}

void boxInFrame(const Eigen::Isometry3d& frame_from_mesh, const Aabb& box, Eigen::Vector3d* center,
                Eigen::Vector3d* half) {
  const Eigen::Matrix3d abs_r = frame_from_mesh.linear().cwiseAbs();
  const Eigen::Vector3d c = box.center(), e = box.extent() * 0.5;
  *center = frame_from_mesh * c;
  // The product's rounding: a few ulps of the terms, for the centre and any point of the box.
  *half = abs_r * e;
  *half += 8 * std::numeric_limits<double>::epsilon() *
           (abs_r * (c.cwiseAbs() + e) + frame_from_mesh.translation().cwiseAbs() + *half);
}

Slicer::Slicer(const Mesh& mesh, const Eigen::Isometry3d& sensor_from_mesh, const ScanPattern& fan,
               double tmin, double tmax, bool cull_backfaces)
    : Slicer(mesh, ScanPlane(sensor_from_mesh), Eigen::Isometry3d::Identity(), sensor_from_mesh,
             fan, tmin, tmax, cull_backfaces) {}

Slicer::Slicer(const Mesh& mesh, const ScanPlane& plane, const Eigen::Isometry3d& frame_from_mesh,
               const Eigen::Isometry3d& sensor_from_mesh, const ScanPattern& fan, double tmin,
               double tmax, bool cull_backfaces)
    : mesh_(mesh),
      fan_(fan),
      rot_(sensor_from_mesh.linear()),
      trans_(sensor_from_mesh.translation()),
      plane_(plane),
      frame_from_mesh_(frame_from_mesh),
      cut_(plane, frame_from_mesh),
      sensor_in_mesh_(-(rot_.transpose() * trans_)),
      tmin_(tmin),
      tmax_(tmax),
      // Bound on the rounding of side() at a box centre and at a vertex, relative to the
      // magnitudes involved (not an absolute epsilon): a box is pruned only if it is off the plane
      // by more than that.
      gamma_(2 * roundingGamma<double>(6)),
      cull_backfaces_(cull_backfaces) {
  tmax2_ = tmax * tmax * (1 + gamma_);
}

bool Slicer::mayCross(const Aabb& box) const {
  if (!plane_.mayMeet(frame_from_mesh_, box)) return false;
  // Nearest point of the box to the sensor, against range_max.
  const Eigen::Vector3d nearest = sensor_in_mesh_.cwiseMax(box.lo).cwiseMin(box.hi);
  return (nearest - sensor_in_mesh_).squaredNorm() <= tmax2_;
}

}  // namespace core
}  // namespace laser_raycast
