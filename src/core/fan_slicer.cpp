#include "laser_raycast/core/fan_slicer.h"

#include <cmath>

namespace laser_raycast {
namespace core {
namespace {

bool lexicographicLess(const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
  if (p.x() != q.x()) return p.x() < q.x();
  if (p.y() != q.y()) return p.y() < q.y();
  return p.z() < q.z();
}

// Where edge (p, q) crosses the plane, given the vertices' signed distances, sp <= 0 < sq or the
// other way round. A vertex on the plane (distance 0) is its own crossing, bit for bit. Otherwise
// the vertices are put in lexicographic order first, so both triangles sharing the edge get the
// same bits.
Eigen::Vector3d edgeCrossing(Eigen::Vector3d p, double sp, Eigen::Vector3d q, double sq) {
  if (sp == 0) return p;
  if (sq == 0) return q;
  if (lexicographicLess(q, p)) {
    std::swap(p, q);
    std::swap(sp, sq);
  }
  return p + (q - p) * (sp / (sp - sq));  // sp and sq differ in sign: no cancellation
}

}  // namespace

PlaneSlicer::PlaneSlicer(const Mesh& mesh, const Eigen::Isometry3d& sensor_from_mesh,
                         const ScanPattern& fan, double tmin, double tmax, bool cull_backfaces)
    : mesh_(mesh),
      fan_(fan),
      rot_(sensor_from_mesh.linear()),
      trans_(sensor_from_mesh.translation()),
      // The scan plane (sensor z = 0) in the mesh frame: s(p) = normal . p + offset is p's sensor
      // z.
      normal_(rot_.row(2).transpose()),
      abs_normal_(normal_.cwiseAbs()),
      sensor_in_mesh_(-(rot_.transpose() * trans_)),
      offset_(trans_.z()),
      tmin_(tmin),
      tmax_(tmax),
      // Bound on the rounding of s() at a box centre and at a vertex, relative to the magnitudes
      // involved (not an absolute epsilon): a box is pruned only if it is off the plane by more
      // than that.
      gamma_(2 * roundingGamma<double>(6)),
      cull_backfaces_(cull_backfaces) {
  tmax2_ = tmax * tmax * (1 + gamma_);
}

bool PlaneSlicer::mayCross(const Aabb& box) const {
  const Eigen::Vector3d c = box.center();
  const Eigen::Vector3d e = box.extent() * 0.5;
  const double s = normal_.dot(c) + offset_;
  const double reach = abs_normal_.dot(e);
  const double slack = gamma_ * (abs_normal_.dot(c.cwiseAbs() + e) + std::abs(offset_));
  if (!(std::abs(s) <= reach + slack)) return false;
  // Nearest point of the box to the sensor, against range_max.
  const Eigen::Vector3d nearest = sensor_in_mesh_.cwiseMax(box.lo).cwiseMin(box.hi);
  return (nearest - sensor_in_mesh_).squaredNorm() <= tmax2_;
}

bool PlaneSlicer::segment(std::uint32_t slot, Eigen::Vector2d* p, Eigen::Vector2d* q) const {
  const auto& v = mesh_.bvh().triangleVertices()[slot];
  const double s[3] = {normal_.dot(v[0]) + offset_, normal_.dot(v[1]) + offset_,
                       normal_.dot(v[2]) + offset_};
  // A vertex exactly on the plane counts as just below it (the plane nudged up by an
  // infinitesimal): an edge lying in the plane is then cut once, by the triangle above it, not
  // twice; a triangle touching the plane from below, or lying in it, is not cut (as a ray in a
  // triangle's plane misses it); one touching it from above gives a zero-length segment, which no
  // beam crosses. Every crossing triangle has exactly two edges with one end below and one above.
  const bool above[3] = {s[0] > 0, s[1] > 0, s[2] > 0};
  if (above[0] == above[1] && above[1] == above[2]) return false;  // also NaN: never above
  Eigen::Vector3d points[2];
  int count = 0;
  for (int k = 0; k < 3; ++k) {
    const int j = k == 2 ? 0 : k + 1;
    if (above[k] != above[j]) points[count++] = edgeCrossing(v[k], s[k], v[j], s[j]);
  }
  // Endpoints in the scan plane (sensor x, y).
  *p = Eigen::Vector2d(rot_.row(0).dot(points[0]) + trans_.x(),
                       rot_.row(1).dot(points[0]) + trans_.y());
  *q = Eigen::Vector2d(rot_.row(0).dot(points[1]) + trans_.x(),
                       rot_.row(1).dot(points[1]) + trans_.y());
  return true;
}

void sliceMesh(const Mesh& mesh, const Eigen::Isometry3d& sensor_from_mesh, const ScanPattern& fan,
               double tmin, double tmax, bool cull_backfaces, int body_index, DepthBuffer buffer) {
  const PlaneSlicer slicer(mesh, sensor_from_mesh, fan, tmin, tmax, cull_backfaces);
  const auto& ids = mesh.bvh().triangleIds();
  std::vector<double>& range = *buffer.range;
  const int last = fan.azimuthCount() - 1;
  mesh.bvh().visit([&](const Aabb& box) { return slicer.mayCross(box); },
                   [&](std::uint32_t slot) {
                     slicer.sliceSlot(slot, 0, last, [&](int i, double t) {
                       if (buffer.crossings) ++(*buffer.crossings)[i];
                       if (!(t < range[i])) return;
                       range[i] = t;
                       (*buffer.body)[i] = body_index;
                       (*buffer.triangle)[i] = static_cast<int>(ids[slot]);
                       if (buffer.normal) (*buffer.normal)[i] = slicer.sensorNormal(slot);
                     });
                   });
}

}  // namespace core
}  // namespace laser_raycast
