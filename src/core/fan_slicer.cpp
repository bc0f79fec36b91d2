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

void sliceMesh(const Mesh& mesh, const Eigen::Isometry3d& sensor_from_mesh, const ScanPattern& fan,
               double tmin, double tmax, bool cull_backfaces, int body_index, DepthBuffer buffer) {
  const Eigen::Matrix3d& rot = sensor_from_mesh.linear();
  const Eigen::Vector3d& trans = sensor_from_mesh.translation();
  // The scan plane (sensor z = 0) in the mesh frame: s(p) = normal . p + offset is p's sensor z.
  const Eigen::Vector3d normal = rot.row(2).transpose();
  const double offset = trans.z();
  const Eigen::Vector3d sensor_in_mesh = -(rot.transpose() * trans);
  const Eigen::Vector3d abs_normal = normal.cwiseAbs();
  // Bound on the rounding of s() at a box centre and at a vertex, relative to the magnitudes
  // involved (not an absolute epsilon): a box is pruned only if it is off the plane by more than
  // that.
  const double gamma = 2 * roundingGamma<double>(6);
  const double tmax2 = tmax * tmax * (1 + gamma);

  const Bvh& bvh = mesh.bvh();
  const auto& slots = bvh.triangleVertices();
  const auto& ids = bvh.triangleIds();
  const std::vector<Eigen::Vector3d>& dirs = fan.directions();
  std::vector<double>& range = *buffer.range;

  auto descend = [&](const Aabb& box) {
    const Eigen::Vector3d c = box.center();
    const Eigen::Vector3d e = box.extent() * 0.5;
    const double s = normal.dot(c) + offset;
    const double reach = abs_normal.dot(e);
    const double slack = gamma * (abs_normal.dot(c.cwiseAbs() + e) + std::abs(offset));
    if (!(std::abs(s) <= reach + slack)) return false;
    // Nearest point of the box to the sensor, against range_max.
    const Eigen::Vector3d nearest = sensor_in_mesh.cwiseMax(box.lo).cwiseMin(box.hi);
    return (nearest - sensor_in_mesh).squaredNorm() <= tmax2;
  };

  auto leaf = [&](std::uint32_t slot) {
    const auto& v = slots[slot];
    const double s[3] = {normal.dot(v[0]) + offset, normal.dot(v[1]) + offset,
                         normal.dot(v[2]) + offset};
    // A vertex exactly on the plane counts as just below it (the plane nudged up by an
    // infinitesimal): an edge lying in the plane is then cut once, by the triangle above it, not
    // twice; a triangle touching the plane from below, or lying in it, is not cut (as a ray in a
    // triangle's plane misses it); one touching it from above gives a zero-length segment, skipped
    // below. Every crossing triangle has exactly two edges with one end below and one above.
    const bool above[3] = {s[0] > 0, s[1] > 0, s[2] > 0};
    if (above[0] == above[1] && above[1] == above[2]) return;  // also NaN: never above
    Eigen::Vector3d points[2];
    int count = 0;
    for (int k = 0; k < 3; ++k) {
      const int j = k == 2 ? 0 : k + 1;
      if (above[k] != above[j]) points[count++] = edgeCrossing(v[k], s[k], v[j], s[j]);
    }

    // Endpoints in the scan plane (sensor x, y).
    const Eigen::Vector2d p(rot.row(0).dot(points[0]) + trans.x(),
                            rot.row(1).dot(points[0]) + trans.y());
    const Eigen::Vector2d q(rot.row(0).dot(points[1]) + trans.x(),
                            rot.row(1).dot(points[1]) + trans.y());
    Eigen::Vector3d front = Eigen::Vector3d::Zero();
    if (cull_backfaces) front = rot * (v[1] - v[0]).cross(v[2] - v[0]);

    // The beams that can see the segment: the shorter arc between its endpoints' bearings, widened
    // by one bearing error each side. Each true bearing lies within kBearingError of its
    // approximation, so the arc from the lower approximation minus the error to the higher plus the
    // error holds the true arc, also when the approximation flipped the sign of a tiny sweep (the
    // window spans both approximations either way). The shorter arc is the true one unless the
    // sweep is within two errors of half a turn (a segment passing beside the sensor): then every
    // beam is tried.
    const double bearing_p = approxAtan2(p.y(), p.x());
    const double bearing_q = approxAtan2(q.y(), q.x());
    double sweep = bearing_q - bearing_p;
    if (sweep > M_PI) sweep -= 2 * M_PI;
    if (sweep < -M_PI) sweep += 2 * M_PI;
    const double pad = kBearingError;
    const bool ambiguous = std::abs(sweep) > M_PI - 2 * pad;
    const double start =
        ambiguous ? 0.0 : wrapToTurn((sweep >= 0 ? bearing_p : bearing_q) - pad - fan.angleMin());
    const double width = ambiguous ? 2 * M_PI : std::abs(sweep) + 2 * pad;
    forEachBeamRange(fan, start, width, [&](int first, int last) {
      for (int i = first; i <= last; ++i) {
        const double dx = dirs[i].x(), dy = dirs[i].y();
        // Which side of the beam's line each endpoint is on; a shared endpoint gives the same value
        // to both of its segments.
        const double side_p = dx * p.y() - dy * p.x();
        const double side_q = dx * q.y() - dy * q.x();
        if (!((side_p <= 0 && side_q >= 0) || (side_p >= 0 && side_q <= 0))) continue;
        // Both on the line: the beam runs along the triangle's plane.
        if (side_p == side_q) continue;
        // Exactly through an endpoint: the beam counts for the segment whose other end lies on its
        // left (as if nudged to the right), so for exactly one of the two segments sharing a point
        // where the outline crosses the beam.
        if (side_p == 0 ? !(side_q > 0) : (side_q == 0 && !(side_p > 0))) continue;
        const double along_p = dx * p.x() + dy * p.y();
        const double along_q = dx * q.x() + dy * q.y();
        const double t = along_p + (side_p / (side_p - side_q)) * (along_q - along_p);
        if (!(t >= tmin && t <= tmax)) continue;
        if (cull_backfaces && dx * front.x() + dy * front.y() > 0) continue;
        if (buffer.crossings) ++(*buffer.crossings)[i];
        if (!(t < range[i])) continue;
        range[i] = t;
        (*buffer.body)[i] = body_index;
        (*buffer.triangle)[i] = static_cast<int>(ids[slot]);
        if (buffer.normal) (*buffer.normal)[i] = rot * mesh.normal(ids[slot]);
      }
    });
  };

  bvh.visit(descend, leaf);
}

}  // namespace core
}  // namespace laser_raycast
