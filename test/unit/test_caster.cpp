// Caster: ranges and incidence against hand formulas, on the fast path and the per-beam path.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "cast_reference.h"
#include "fan_specs.h"
#include "laser_raycast/core/caster.h"
#include "mesh_builder.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast::core;

// Exit distance from inside the axis-aligned box [lo, hi] along w (hand formula).
double boxExit(const Eigen::Vector3d& p, const Eigen::Vector3d& w, const Eigen::Vector3d& lo,
               const Eigen::Vector3d& hi) {
  double t = kInf;
  for (int k = 0; k < 3; ++k) {
    if (w[k] > 0) t = std::min(t, (hi[k] - p[k]) / w[k]);
    if (w[k] < 0) t = std::min(t, (lo[k] - p[k]) / w[k]);
  }
  return t;
}

// Barycentric containment of p in a mesh triangle, to within tol (relative to the triangle size).
bool onTriangle(const Mesh& mesh, int triangle, const Eigen::Vector3d& p, double tol) {
  const auto& t = mesh.triangles()[triangle];
  const Eigen::Vector3d a = mesh.vertices()[t[0]], b = mesh.vertices()[t[1]],
                        c = mesh.vertices()[t[2]];
  const Eigen::Vector3d n = (b - a).cross(c - a);
  const double area2 = n.squaredNorm();
  const double scale = std::max({(b - a).norm(), (c - a).norm(), (c - b).norm()});
  if (std::abs(n.normalized().dot(p - a)) > tol * scale) return false;
  const double u = n.dot((p - a).cross(c - a)) / area2;
  const double v = n.dot((b - a).cross(p - a)) / area2;
  return u >= -tol && v >= -tol && u + v <= 1 + tol;
}

// A sensor inside a box room made of triangles: the range along w is the exit distance from the box
// (e.g. the wall x = 4 at azimuth a is 4 / cos a away). Fast path, general path (every method),
// and a 3D pattern; the reported triangle must contain the hit point.
TEST(Caster, BoxRoomMeshMatchesHandFormula) {
  const Eigen::Vector3d lo(-3, -2, -1), hi(4, 5, 1.5);
  const auto room =
      gridBox(steps(lo.x(), hi.x(), 7), steps(lo.y(), hi.y(), 7), steps(lo.z(), hi.z(), 3), true);
  Scene scene = sceneWithFrame();
  addBody(&scene, room, 0);
  const FramePoses poses = FramePoses::identity(scene);
  const ScanPattern planar(fanBySamples(-M_PI, M_PI, 721));
  const ScanPattern rings(fanBySamples(-M_PI, M_PI, 181), {-0.7, -0.2, 0.0, 0.35, 1.2});
  for (const auto& sensor :
       {pose(Eigen::Vector3d::Zero()), pose(Eigen::Vector3d(0.5, -0.25, 0.3), yaw(0.3)),
        pose(Eigen::Vector3d(-1.2, 3.1, -0.4), rpy(0.2, -0.15, 2.0))}) {
    for (const ScanPattern* pattern : {&planar, &rings}) {
      for (const TriangleMethod method : kAllTriangleMethods) {
        for (const bool fast : {true, false}) {
          if (fast && method != TriangleMethod::kWatertight) continue;  // slicing has no method
          CastConfig c = config(fast);
          c.method = method;
          const ScanResult r = cast(scene, poses, sensor, *pattern, c);
          ASSERT_EQ(r.range.size(), static_cast<std::size_t>(pattern->size()));
          for (int i = 0; i < pattern->size(); ++i) {
            const Eigen::Vector3d w = sensor.linear() * pattern->directions()[i];
            const double expected = boxExit(sensor.translation(), w, lo, hi);
            ASSERT_NEAR(r.range[i], expected, 1e-9)
                << toString(method) << (fast ? " fast" : " general") << " beam " << i;
            ASSERT_EQ(r.body[i], 0);
            ASSERT_GE(r.triangle[i], 0);
            const Eigen::Vector3d p = sensor.translation() + r.range[i] * w;
            ASSERT_TRUE(onTriangle(*room, r.triangle[i], p, 1e-9)) << "beam " << i;
          }
          EXPECT_EQ(r.stats.bodies, 1);
          EXPECT_EQ(r.stats.bodies_culled, 0);
          EXPECT_EQ(r.stats.bodies_skipped, 0);
          EXPECT_FALSE(r.stats.reused);
          EXPECT_TRUE(r.cos_incidence.empty());
        }
      }
    }
  }
}

// The same room as a Box primitive, placed by the body's pose in its frame.
TEST(Caster, BoxPrimitiveRoomMatchesHandFormula) {
  Scene scene = sceneWithFrame();
  // Size (6, 8, 4) centred at (0.5, 1, 0): faces x in [-2.5, 3.5], y in [-3, 5], z in [-2, 2].
  addBody(&scene, Box{Eigen::Vector3d(6, 8, 4)}, 0, pose(Eigen::Vector3d(0.5, 1, 0)));
  const Eigen::Vector3d lo(-2.5, -3, -2), hi(3.5, 5, 2);
  const FramePoses poses = FramePoses::identity(scene);
  const ScanPattern planar(fanByIncrement(-M_PI, M_PI, 0.01));
  const ScanPattern rings(fanBySamples(-3, 3, 200), {-1.0, 0.0, 0.5});
  const auto sensor = pose(Eigen::Vector3d(0.3, -0.7, 0.2), rpy(0.1, 0.2, -0.4));
  for (const ScanPattern* pattern : {&planar, &rings}) {
    for (const bool fast : {true, false}) {
      const ScanResult r = cast(scene, poses, sensor, *pattern, config(fast));
      for (int i = 0; i < pattern->size(); ++i) {
        const Eigen::Vector3d w = sensor.linear() * pattern->directions()[i];
        ASSERT_NEAR(r.range[i], boxExit(sensor.translation(), w, lo, hi), 1e-9) << i;
        ASSERT_EQ(r.body[i], 0);
        ASSERT_EQ(r.triangle[i], -1);
      }
    }
  }
}

// Nearest root >= tmin of |o + t w - c|^2 = r^2 (hand formula), or +inf; *disc receives the
// discriminant so that callers can skip near-silhouette beams.
double sphereRange(const Eigen::Vector3d& o, const Eigen::Vector3d& w, const Eigen::Vector3d& c,
                   double r, double* disc) {
  const Eigen::Vector3d oc = o - c;
  const double b = w.dot(oc);
  *disc = b * b - (oc.squaredNorm() - r * r);
  if (*disc < 0) return kInf;
  const double s = std::sqrt(*disc);
  if (-b - s >= 0) return -b - s;
  if (-b + s >= 0) return -b + s;
  return kInf;
}

// Ray against a finite cylinder (axis z in its own frame, centred) placed at world_from_cylinder:
// the ray is moved into the cylinder's frame with Eigen's inverse, then side and caps are solved
// directly. *margin is how far the nearest side/cap hit is from a rim, relative, for skipping
// grazing beams.
double cylinderRange(const Eigen::Vector3d& o, const Eigen::Vector3d& w,
                     const Eigen::Isometry3d& world_from_cylinder, double r, double length,
                     double* margin) {
  const Eigen::Isometry3d inv = world_from_cylinder.inverse(Eigen::Isometry);
  const Eigen::Vector3d p = inv * o, d = inv.linear() * w;
  const double h = length / 2;
  double best = kInf;
  *margin = kInf;
  const double a = d.x() * d.x() + d.y() * d.y();
  if (a > 0) {
    const double b = p.x() * d.x() + p.y() * d.y();
    const double c = p.x() * p.x() + p.y() * p.y() - r * r;
    const double disc = b * b - a * c;
    if (disc >= 0) {
      for (const double t : {(-b - std::sqrt(disc)) / a, (-b + std::sqrt(disc)) / a}) {
        const double z = p.z() + t * d.z();
        if (t >= 0 && std::abs(z) <= h && t < best) {
          best = t;
          *margin = std::min((h - std::abs(z)) / h, disc / (a * r * r));
        }
      }
    }
  }
  if (d.z() != 0) {
    for (const double zc : {-h, h}) {
      const double t = (zc - p.z()) / d.z();
      const double x = p.x() + t * d.x(), y = p.y() + t * d.y();
      if (t >= 0 && x * x + y * y <= r * r && t < best) {
        best = t;
        *margin = (r * r - x * x - y * y) / (r * r);
      }
    }
  }
  return best;
}

// A sphere and an upright cylinder at known places (primitives), planar and 3D; beams within a
// small margin of a silhouette are skipped, where the range is ill-conditioned.
TEST(Caster, SphereAndCylinderMatchHandFormulas) {
  Scene scene = sceneWithFrame();
  const Eigen::Vector3d sphere_c(5, 1, 0.2);
  const double sphere_r = 1.3;
  addBody(&scene, Sphere{sphere_r}, 0, pose(sphere_c));
  const auto cyl_pose = pose(Eigen::Vector3d(-1, 3, 0.5));
  addBody(&scene, Cylinder{0.5, 2.0}, 0, cyl_pose);
  const FramePoses poses = FramePoses::identity(scene);
  const ScanPattern planar(fanBySamples(-M_PI, M_PI, 3601));
  const ScanPattern rings(fanBySamples(-M_PI, M_PI, 721), {-0.6, -0.1, 0.0, 0.2, 0.5});
  const auto sensor = pose(Eigen::Vector3d(0.1, -0.2, 0.3));
  int hits_sphere = 0, hits_cylinder = 0;
  for (const ScanPattern* pattern : {&planar, &rings}) {
    for (const bool fast : {true, false}) {
      const ScanResult r = cast(scene, poses, sensor, *pattern, config(fast));
      for (int i = 0; i < pattern->size(); ++i) {
        const Eigen::Vector3d w = sensor.linear() * pattern->directions()[i];
        double disc, margin;
        const double ts = sphereRange(sensor.translation(), w, sphere_c, sphere_r, &disc);
        const double tc = cylinderRange(sensor.translation(), w, cyl_pose, 0.5, 2.0, &margin);
        if (std::abs(disc) < 1e-6 || margin < 1e-6) continue;  // grazing a silhouette
        const double expected = std::min(ts, tc);
        if (std::isinf(expected)) {
          ASSERT_EQ(r.range[i], kInf) << i;
          ASSERT_EQ(r.body[i], -1);
          continue;
        }
        ASSERT_NEAR(r.range[i], expected, 1e-9 * expected) << i;
        ASSERT_EQ(r.body[i], ts < tc ? 0 : 1) << i;
        ASSERT_EQ(r.triangle[i], -1);
        (ts < tc ? hits_sphere : hits_cylinder)++;
      }
    }
  }
  EXPECT_GT(hits_sphere, 500);
  EXPECT_GT(hits_cylinder, 200);
}

// A cylinder lying along x (tilted by frame_from_body), cut lengthwise by the scan plane: the
// planar section is the rectangle x in [3, 5], |y| <= 0.5. From the origin a beam at azimuth a
// enters through the cap x = 3 at 3 / cos a while |3 tan a| <= 0.5, and misses otherwise. From
// (4.5, -2) a beam at azimuth a in (0, pi) meets the side y = -0.5 at 1.5 / sin a, a hit while that
// point has x in [3, 5]. Then the same cylinder tilted about two axes, against the general formula.
TEST(Caster, TiltedCylinder) {
  Scene scene = sceneWithFrame();
  const auto lying = pose(Eigen::Vector3d(4, 0, 0), rpy(0, M_PI / 2, 0));
  addBody(&scene, Cylinder{0.5, 2.0}, 0, lying);
  const FramePoses poses = FramePoses::identity(scene);
  const ScanPattern towards_cap(fanBySamples(-0.6, 0.6, 1201));
  const ScanPattern towards_side(fanBySamples(0.2, M_PI - 0.2, 1201));
  const auto below = pose(Eigen::Vector3d(4.5, -2, 0));
  for (const bool fast : {true, false}) {
    const ScanResult caps =
        cast(scene, poses, Eigen::Isometry3d::Identity(), towards_cap, config(fast));
    const ScanResult sides = cast(scene, poses, below, towards_side, config(fast));
    int cap_hits = 0, side_hits = 0, side_misses = 0;
    for (int i = 0; i < towards_cap.size(); ++i) {
      const double a = towards_cap.azimuth(i);
      const double y3 = std::abs(3 * std::tan(a));
      if (std::abs(y3 - 0.5) < 1e-6) continue;  // the cap's rim
      if (y3 <= 0.5) {
        ASSERT_NEAR(caps.range[i], 3 / std::cos(a), 1e-9) << i;
        ASSERT_EQ(caps.body[i], 0);
        ++cap_hits;
      } else {
        ASSERT_EQ(caps.range[i], kInf) << i;
      }
    }
    for (int i = 0; i < towards_side.size(); ++i) {
      const double a = towards_side.azimuth(i);
      const double t = 1.5 / std::sin(a);
      const double x = 4.5 + t * std::cos(a);
      if (std::abs(x - 3) < 1e-6 || std::abs(x - 5) < 1e-6) continue;  // a rim
      if (x >= 3 && x <= 5) {
        ASSERT_NEAR(sides.range[i], t, 1e-9 * t) << i;
        ++side_hits;
      } else {
        ASSERT_EQ(sides.range[i], kInf) << i;
        ++side_misses;
      }
    }
    EXPECT_GT(cap_hits, 100);
    EXPECT_GT(side_hits, 100);
    EXPECT_GT(side_misses, 100);
  }

  // Tilted both ways, placed in a moved frame; checked against cylinderRange in 3D.
  Scene tilted;
  tilted.addFrame("base");
  tilted.addLabel("l");
  const auto frame_from_body = pose(Eigen::Vector3d(0.5, 0.2, -0.1), rpy(M_PI / 4, M_PI / 4, 0.3));
  addBody(&tilted, Cylinder{0.4, 1.5}, 0, frame_from_body);
  FramePoses moved = FramePoses::identity(tilted);
  moved.pose[0] = pose(Eigen::Vector3d(2.5, -0.5, 0.1), yaw(0.4));
  const auto world_from_cyl = moved.pose[0] * frame_from_body;
  const ScanPattern planar(fanBySamples(-1.5, 1.5, 1201));
  const ScanPattern rings(fanBySamples(-1.5, 1.5, 601), {-0.4, -0.2, 0.0, 0.2, 0.4});
  const auto sensor = pose(Eigen::Vector3d(-0.2, 0.1, 0.05), rpy(0.05, -0.1, 0.2));
  int hits = 0;
  for (const ScanPattern* pattern : {&planar, &rings}) {
    for (const bool fast : {true, false}) {
      const ScanResult r = cast(tilted, moved, sensor, *pattern, config(fast));
      for (int i = 0; i < pattern->size(); ++i) {
        const Eigen::Vector3d w = sensor.linear() * pattern->directions()[i];
        double margin;
        const double expected =
            cylinderRange(sensor.translation(), w, world_from_cyl, 0.4, 1.5, &margin);
        if (margin < 1e-6) continue;
        if (std::isinf(expected)) {
          ASSERT_EQ(r.range[i], kInf) << i;
        } else {
          ASSERT_NEAR(r.range[i], expected, 1e-9 * expected) << i;
          ++hits;
        }
      }
    }
  }
  EXPECT_GT(hits, 300);
}

// cos_incidence is |cos| of the angle between beam and surface normal: 1 head-on, 0.5 at 60
// degrees; for meshes (both paths) and primitives (box face, sphere); 0 where nothing is hit.
TEST(Caster, Incidence) {
  const ScanPattern pattern(fanBySamples(-M_PI / 3, M_PI / 3, 3));  // -60, 0, +60 degrees
  const double c60 = 0.5;
  // A wall mesh in x = 3, front face towards the sensor, and a box primitive whose face is x = 3.
  MeshBuilder wall;
  const auto a = wall.vertex(Eigen::Vector3d(3, -10, -10)),
             b = wall.vertex(Eigen::Vector3d(3, 10, -10)),
             c = wall.vertex(Eigen::Vector3d(3, 10, 10)),
             d = wall.vertex(Eigen::Vector3d(3, -10, 10));
  wall.quad(a, b, c, d, Eigen::Vector3d(-1, 0, 0));
  std::vector<Shape> shapes = {wall.build(), Box{Eigen::Vector3d(1, 20, 20)}};
  std::vector<Eigen::Isometry3d> placements = {Eigen::Isometry3d::Identity(),
                                               pose(Eigen::Vector3d(3.5, 0, 0))};
  for (std::size_t k = 0; k < shapes.size(); ++k) {
    Scene scene = sceneWithFrame();
    addBody(&scene, shapes[k], 0, placements[k]);
    const FramePoses poses = FramePoses::identity(scene);
    for (const bool fast : {true, false}) {
      CastConfig cfg = config(fast);
      cfg.compute_incidence = true;
      const ScanResult r = cast(scene, poses, Eigen::Isometry3d::Identity(), pattern, cfg);
      ASSERT_EQ(r.cos_incidence.size(), 3u);
      EXPECT_NEAR(r.cos_incidence[1], 1.0, 1e-12) << k;
      EXPECT_NEAR(r.cos_incidence[0], c60, 1e-12) << k;
      EXPECT_NEAR(r.cos_incidence[2], c60, 1e-12) << k;
      EXPECT_NEAR(r.range[0], 6.0, 1e-12);  // 3 / cos 60
      EXPECT_NEAR(r.range[1], 3.0, 1e-12);
    }
  }
  // A sphere at (5, 0, 0), r = 1: head-on cos 1; off-centre the hand formula |w . n|; a miss 0.
  Scene scene = sceneWithFrame();
  addBody(&scene, Sphere{1}, 0, pose(Eigen::Vector3d(5, 0, 0)));
  const FramePoses poses = FramePoses::identity(scene);
  const ScanPattern fan(fanBySamples(-0.3, 0.3, 61));
  for (const bool fast : {true, false}) {
    CastConfig cfg = config(fast);
    cfg.compute_incidence = true;
    const ScanResult r = cast(scene, poses, Eigen::Isometry3d::Identity(), fan, cfg);
    EXPECT_NEAR(r.cos_incidence[30], 1.0, 1e-12);
    for (int i = 0; i < fan.size(); ++i) {
      const Eigen::Vector3d w = fan.directions()[i];
      double disc;
      const double t = sphereRange(Eigen::Vector3d::Zero(), w, Eigen::Vector3d(5, 0, 0), 1, &disc);
      if (std::isinf(t)) {
        EXPECT_EQ(r.cos_incidence[i], 0.0) << i;
        continue;
      }
      const Eigen::Vector3d n = t * w - Eigen::Vector3d(5, 0, 0);
      EXPECT_NEAR(r.cos_incidence[i], std::abs(w.dot(n)), 1e-9) << i;
    }
  }
}

// A tilted cylinder's side: the normal is perpendicular to the axis.
TEST(Caster, IncidenceOnTiltedCylinder) {
  Scene scene = sceneWithFrame();
  // Axis along y (rotated 90 degrees about x) through (3, 0, 0), radius 1: in the scan plane the
  // side facing the sensor is the line x = 2 with normal (-1, 0, 0), so a beam at azimuth a hits
  // at 2 / cos a with cos incidence cos a.
  const auto cyl = pose(Eigen::Vector3d(3, 0, 0), rpy(M_PI / 2, 0, 0));
  addBody(&scene, Cylinder{1.0, 10.0}, 0, cyl);
  const FramePoses poses = FramePoses::identity(scene);
  const ScanPattern fan(fanBySamples(-0.8, 0.8, 33));
  for (const bool fast : {true, false}) {
    CastConfig cfg = config(fast);
    cfg.compute_incidence = true;
    const ScanResult r = cast(scene, poses, Eigen::Isometry3d::Identity(), fan, cfg);
    for (int i = 0; i < fan.size(); ++i) {
      const Eigen::Vector3d w = fan.directions()[i];
      // The axis is the line x = 3, z = 0 (along y): in the plane z = 0 the side is x = 2.
      const double t = 2 / w.x();
      EXPECT_NEAR(r.range[i], t, 1e-9 * t) << i;
      EXPECT_NEAR(r.cos_incidence[i], w.x(), 1e-9) << i;  // normal (-1, 0, 0)
    }
  }
}

}  // namespace
}  // namespace laser_raycast_test
