// The planar fast path: a 2D fan needs only the triangles that cross its plane. Each crossing
// triangle is cut into a segment in the scan plane and tested against the beams of its angular
// window, so the cost grows with the number of crossing triangles and beams, not with rays times
// tree depth.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "beams/beam_window.h"
#include "laser_raycast/core/mesh.h"
#include "laser_raycast/core/scan_pattern.h"

namespace laser_raycast {
namespace core {

// The scan plane (the sensor's z = 0) in the frame that moves a group of bodies (scene_index.h):
// side(p) = n . p + offset is the sensor z of p (frame coordinates). Points of the plane are
// written in a basis (u, v) of it that depends on n alone, so that the same plane, met again from
// another sensor pose in it (a robot driving on a floor), gives the same plane coordinates bit for
// bit (kept_slice.h keeps them); toSensor() maps them to the sensor's x, y. Every planar test goes
// through these steps, a mesh's vertices by MeshCut.
//
// n and offset keep kKeptPlaneBits of their 53 (rounded to nearest): one plane met from poses that
// TF composed differently (a turning base) differs in the last bits, which would make every scan's
// plane a new one. The plane is then the sensor's moved by at most 2^-44 of its offset along n and
// turned by at most 2^-44 rad: 7e-14 m at 1.2 m, below any range's resolution by far.
struct ScanPlane {
  static constexpr int kKeptPlaneBits = 44;
  explicit ScanPlane(const Eigen::Isometry3d& sensor_from_frame);

  double side(const Eigen::Vector3d& p) const { return n.dot(p) + offset; }
  Eigen::Vector2d planeCoords(const Eigen::Vector3d& p) const { return {u.dot(p), v.dot(p)}; }
  Eigen::Vector2d toSensor(const Eigen::Vector2d& w) const {
    return {a * w.x() + b * w.y() + tx, c * w.x() + d * w.y() + ty};
  }
  // False if no point of box (a mesh's frame, placed in this frame by frame_from_mesh) can be cut:
  // the box moved into the frame, against side() with a slack for the rounding of moving a
  // vertex there and of side() (relative to the magnitudes involved), which also bounds the
  // rounding of MeshCut's heights (its rows are n turned into the mesh's frame).
  bool mayMeet(const Eigen::Isometry3d& frame_from_mesh, const Aabb& box) const;

  Eigen::Vector3d n;  // the sensor's z axis in the frame
  double offset;      // the frame origin's sensor z
  Eigen::Vector3d u, v;
  double a, b, c, d, tx, ty;  // sensor x = a pu + b pv + tx, y = c pu + d pv + ty
};

// The plane seen from a mesh placed in its frame (frame_from_mesh): a mesh point's side() and plane
// coordinates by one affine map, the plane's n, u and v turned into the mesh's frame, so a vertex
// is not moved into the frame first. Every planar test cuts a mesh's triangles through this
// (Slicer, KeptSlice), so neighbouring triangles share their crossings bit for bit, and the same
// plane met again in the frame (a robot driving on a floor) gives the same bits: the map depends on
// the plane's n and offset and the mesh's placement alone.
class MeshCut {
 public:
  MeshCut(const ScanPlane& plane, const Eigen::Isometry3d& frame_from_mesh);

  // Where a triangle (mesh coordinates) crosses the plane, in plane coordinates: false if it does
  // not (a vertex exactly on the plane counts as just below it, see Slicer).
  bool crossing(const std::array<Eigen::Vector3d, 3>& v, Eigen::Vector2d* p,
                Eigen::Vector2d* q) const;

 private:
  // Row r's value at mesh point x.
  double map(int r, const Eigen::Vector3d& x) const {
    return rows_[r][0] * x.x() + rows_[r][1] * x.y() + rows_[r][2] * x.z() + offsets_[r];
  }
  // Row 0 gives side(), rows 1 and 2 the plane coordinates along u and v.
  double rows_[3][3];
  double offsets_[3];
};

// A box given in a mesh's frame as a box in the frame that places the mesh (frame_from_mesh):
// centre and half extents, widened for the rounding of moving a point there.
void boxInFrame(const Eigen::Isometry3d& frame_from_mesh, const Aabb& box, Eigen::Vector3d* center,
                Eigen::Vector3d* half);

// Slices a mesh by the fan's plane: each triangle that crosses it becomes a segment in the plane,
// tested against the beams. Watertight: each crossing point is computed from its edge's two
// vertices in a fixed (lexicographic) order, so neighbouring triangles share bitwise-identical
// segment endpoints, and a beam is tested against a segment by the signs of two cross products with
// those endpoints. A beam exactly through a shared endpoint counts for one of the two segments
// (half-open segments), and a vertex exactly on the plane counts as just below it, so that an edge
// lying in the plane is cut once: a beam crosses a closed outline exactly once. A surface that only
// touches the plane from below (the top of a box at exactly the sensor's height) is therefore not
// seen; triangles lying in the plane are skipped, as the 3D tests skip a ray in a triangle's plane.
// A triangle's front normal ((b - a) x (c - a), from its vertices v in a body's frame) rotated into
// the sensor frame by sensor_rot, its x and y: what a planar test culls back faces by.
inline Eigen::Vector2d planarFront(const Eigen::Matrix3d& sensor_rot,
                                   const std::array<Eigen::Vector3d, 3>& v) {
  return (sensor_rot * (v[1] - v[0]).cross(v[2] - v[0])).head<2>();
}

class Slicer {
 public:
  // A mesh placed in a frame (frame_from_mesh) cut by that frame's plane (plane): how the walk
  // slices a body, so that it gets the bits a kept slice of the frame holds.
  Slicer(const Mesh& mesh, const ScanPlane& plane, const Eigen::Isometry3d& frame_from_mesh,
         const Eigen::Isometry3d& sensor_from_mesh, const ScanPattern& fan, double tmin,
         double tmax, bool cull_backfaces);
  // A mesh in its own frame.
  Slicer(const Mesh& mesh, const Eigen::Isometry3d& sensor_from_mesh, const ScanPattern& fan,
         double tmin, double tmax, bool cull_backfaces);

  const ScanPlane& plane() const { return plane_; }

  // False if the box (mesh frame) certainly neither crosses the plane nor comes within tmax.
  bool mayCross(const Aabb& box) const;

  // Slices the triangle in BVH slot `slot` and calls hit(beam, t) for every beam with index in
  // [first, last] that crosses its segment with t in [tmin, tmax]. open(beam, near) may say that a
  // beam needs no test: it has hit something nearer than `near`, the segment's nearest distance.
  template <class Hit>
  void sliceSlot(std::uint32_t slot, int first, int last, Hit&& hit) const {
    sliceSlot(slot, first, last, std::forward<Hit>(hit), [](int, double) { return true; });
  }
  template <class Hit, class Open>
  void sliceSlot(std::uint32_t slot, int first, int last, Hit&& hit, Open&& open) const {
    Eigen::Vector2d p, q;
    if (!cut(slot, &p, &q)) return;
    testSegment(p, q, slot, first, last, std::forward<Hit>(hit), std::forward<Open>(open));
  }
  // Where the triangle in `slot` meets the one beam `beam` with t in [tmin, tmax], into *t: the
  // test sliceSlot makes for that beam, without finding which beams the segment can reach (for a
  // beam traced on its own, that costs more than the test).
  bool sliceBeam(std::uint32_t slot, int beam, double* t) const;
  // The same for a segment given in plane coordinates (a cached slice's): the triangle in `slot`
  // crosses the plane there.
  template <class Hit, class Open>
  void testSegment(const Eigen::Vector2d& plane_p, const Eigen::Vector2d& plane_q,
                   std::uint32_t slot, int first, int last, Hit&& hit, Open&& open) const;

  // The triangle in a slot (its index in the mesh).
  std::uint32_t triangleOf(std::uint32_t slot) const { return mesh_.bvh().triangleIds()[slot]; }
  // The hit triangle's front normal in the sensor frame.
  Eigen::Vector3d sensorNormal(std::uint32_t slot) const {
    return rot_ * mesh_.normal(mesh_.bvh().triangleIds()[slot]);
  }

 private:
  // Where the triangle in `slot` crosses the plane (plane coordinates, by MeshCut);
  // false if it does not.
  bool cut(std::uint32_t slot, Eigen::Vector2d* p, Eigen::Vector2d* q) const {
    return cut_.crossing(mesh_.bvh().triangleVertices()[slot], p, q);
  }
  // The triangle's front normal's sensor x, y into *front, which is returned, where back faces are
  // culled; else null.
  const Eigen::Vector2d* frontOf(std::uint32_t slot, Eigen::Vector2d* front) const {
    if (!cull_backfaces_) return nullptr;
    *front = planarFront(rot_, mesh_.bvh().triangleVertices()[slot]);
    return front;
  }

  const Mesh& mesh_;
  const ScanPattern& fan_;
  Eigen::Matrix3d rot_;
  Eigen::Vector3d trans_;
  ScanPlane plane_;
  Eigen::Isometry3d frame_from_mesh_;
  MeshCut cut_;
  Eigen::Vector3d sensor_in_mesh_;
  double tmin_, tmax_, tmax2_, gamma_;
  bool cull_backfaces_;
};

// Whether the beam with direction (dx, dy) (sensor frame) crosses the segment with ends p != q
// (sensor x, y) with t in [tmin, tmax], and where. With front (the triangle's front normal's
// sensor x, y), a beam meeting its back does not.
LASER_RAYCAST_HOT_INLINE bool beamCrossesSegment(double dx, double dy, const Eigen::Vector2d& p,
                                                 const Eigen::Vector2d& q, double tmin, double tmax,
                                                 const Eigen::Vector2d* front, double* t) {
  // Which side of the beam's line each endpoint is on; a shared endpoint gives the same value to
  // both of its segments.
  const double side_p = dx * p.y() - dy * p.x();
  const double side_q = dx * q.y() - dy * q.x();
  if (!((side_p <= 0 && side_q >= 0) || (side_p >= 0 && side_q <= 0))) return false;
  // Both on the line: the beam runs along the triangle's plane.
  if (side_p == side_q) return false;
  // Exactly through an endpoint: the beam counts for the segment whose other end lies on its left
  // (as if nudged to the right), so for exactly one of the two segments sharing a point where the
  // outline crosses the beam.
  if (side_p == 0 ? !(side_q > 0) : (side_q == 0 && !(side_p > 0))) return false;
  const double along_p = dx * p.x() + dy * p.y();
  const double along_q = dx * q.x() + dy * q.y();
  *t = along_p + (side_p / (side_p - side_q)) * (along_q - along_p);
  if (!(*t >= tmin && *t <= tmax)) return false;
  return !(front && dx * front->x() + dy * front->y() > 0);
}

// The beams of fan [first, last] that may cross the segment with ends p != q (x, y in the sensor
// frame of a reference pose): test(lo, hi, near) for column ranges holding every such beam, near a
// distance below which no point of the segment lies from any beam's origin. Each beam leaves from
// within `shift` of the reference origin along its pattern direction turned in the plane by at most
// `turn` (a rotating sweep's block, beams/column_motion.h; both 0 for a scan from one pose).
//
// A few beams are all tested directly; for more, only those the segment's bearings can reach: the
// shorter arc between the endpoints' bearings, widened by one bearing error each side (each true
// bearing lies within kBearingError of its approximation, so the arc from the lower approximation
// minus the error to the higher plus the error holds the true arc, also when the approximation
// flipped the sign of a tiny sweep). The shorter arc is the true one unless the sweep is within two
// errors of half a turn (a segment passing beside the sensor): then every beam is tried. A beam
// that meets the segment at x from an origin o at most `shift` from the reference's points at most
// asin(shift / |x|) from x's bearing, and its column's pattern azimuth is at most `turn` from the
// beam's: the arc is widened by both, unless the segment comes within twice the shift (then every
// beam is tried).
template <class Test>
void forSegmentColumns(const ScanPattern& fan, const Eigen::Vector2d& p, const Eigen::Vector2d& q,
                       int first, int last, double shift, double turn, Test&& test) {
  // Below this many beams in the window, every one is tested without computing bearings.
  constexpr int kDirectBeams = 8;
  if (p == q) return;  // touches the plane at a vertex: no beam crosses it
  // No point of the segment is nearer to the reference origin than this (the distance to its line
  // where the foot of the perpendicular falls inside it, else to the nearer end), lowered for
  // rounding; from a beam's origin, no nearer than that less the shift. A beam that has already
  // hit something nearer needs no test.
  const Eigen::Vector2d pq = q - p;
  const double along = -p.dot(pq), length2 = pq.squaredNorm();
  // (The rounding's bound takes |x| + |y| for each end's norm, which is no less.)
  const double reference_near =
      (along > 0 && along < length2 ? std::abs(p.x() * pq.y() - p.y() * pq.x()) / std::sqrt(length2)
                                    : std::sqrt(std::min(p.squaredNorm(), q.squaredNorm()))) *
          (1 - 16 * std::numeric_limits<double>::epsilon()) -
      16 * std::numeric_limits<double>::epsilon() * (p.cwiseAbs().sum() + q.cwiseAbs().sum());
  const double near =
      shift > 0 ? std::max(0.0, reference_near - shift * (1 + 1e-9)) : reference_near;
  auto clipped = [&](int lo, int hi) {
    lo = std::max(lo, first);
    hi = std::min(hi, last);
    if (lo <= hi) test(lo, hi, near);
  };
  if (last - first < kDirectBeams || (shift > 0 && !(reference_near > 2 * shift))) {
    clipped(first, last);
    return;
  }
  double bearing_p, bearing_q;
  approxAtan2Pair(p.y(), p.x(), q.y(), q.x(), &bearing_p, &bearing_q);
  double sweep = bearing_q - bearing_p;
  if (sweep > M_PI) sweep -= 2 * M_PI;
  if (sweep < -M_PI) sweep += 2 * M_PI;
  double pad = kBearingError;
  if (shift > 0 || turn > 0) {
    pad += (turn + (shift > 0 ? std::asin(shift / reference_near) : 0.0)) * (1 + 1e-9) + 1e-15;
  }
  if (std::abs(sweep) > M_PI - 2 * pad) {
    clipped(first, last);
    return;
  }
  const double start = wrapToTurn((sweep >= 0 ? bearing_p : bearing_q) - pad - fan.angleMin());
  forEachBeamRange(fan, start, std::abs(sweep) + 2 * pad, clipped);
}

// Tests the beams [first, last] of fan against a segment with ends p, q (sensor x, y): hit(beam, t)
// for every beam that crosses it with t in [tmin, tmax]; open(beam, near) may say that a beam needs
// no test (it has hit something nearer than `near`, the segment's nearest distance). With front
// (the triangle's front normal's sensor x, y), a beam meeting its back is not hit.
template <class Hit, class Open>
void testSegmentInFan(const ScanPattern& fan, const Eigen::Vector2d& p, const Eigen::Vector2d& q,
                      double tmin, double tmax, const Eigen::Vector2d* front, int first, int last,
                      Hit&& hit, Open&& open) {
  const auto& dirs = fan.directions();
  forSegmentColumns(fan, p, q, first, last, 0.0, 0.0, [&](int lo, int hi, double near) {
    for (int i = lo; i <= hi; ++i) {
      if (!open(i, near)) continue;
      double t;
      if (beamCrossesSegment(dirs[i].x(), dirs[i].y(), p, q, tmin, tmax, front, &t)) hit(i, t);
    }
  });
}

template <class Hit, class Open>
void Slicer::testSegment(const Eigen::Vector2d& plane_p, const Eigen::Vector2d& plane_q,
                         std::uint32_t slot, int first, int last, Hit&& hit, Open&& open) const {
  Eigen::Vector2d front;
  testSegmentInFan(fan_, plane_.toSensor(plane_p), plane_.toSensor(plane_q), tmin_, tmax_,
                   frontOf(slot, &front), first, last, std::forward<Hit>(hit),
                   std::forward<Open>(open));
}

inline bool Slicer::sliceBeam(std::uint32_t slot, int beam, double* t) const {
  Eigen::Vector2d p, q;
  // p == q: the triangle touches the plane at a vertex, which no beam crosses (forSegmentColumns).
  if (!cut(slot, &p, &q) || p == q) return false;
  Eigen::Vector2d front;
  const Eigen::Vector3d& dir = fan_.directions()[beam];
  return beamCrossesSegment(dir.x(), dir.y(), plane_.toSensor(p), plane_.toSensor(q), tmin_, tmax_,
                            frontOf(slot, &front), t);
}

}  // namespace core
}  // namespace laser_raycast
