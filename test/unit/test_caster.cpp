// Caster: ranges against hand formulas, the planar fast path against the per-beam path, culling,
// back faces, incidence, tmin and the config's validation. Expected values come from formulas or
// from the brute force of cast_reference.h.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "cast_reference.h"
#include "expect_invalid.h"
#include "fan_specs.h"
#include "laser_raycast/core/caster.h"
#include "mesh_builder.h"
#include "random.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast::core;

// -------------------------------------------------------------------------------------------------
// Hand formulas

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

// -------------------------------------------------------------------------------------------------
// Planar fast path against the per-beam path

// Bearings (sensor frame, rad) where the scan plane crosses a mesh edge: the silhouettes of the
// slices, near which hit/miss is decided by rounding and the two paths may legitimately differ.
std::vector<double> sliceBearings(const Scene& scene, const FramePoses& poses,
                                  const Eigen::Isometry3d& world_from_sensor) {
  std::vector<double> out;
  for (const Body& body : scene.bodies()) {
    const auto* mesh = std::get_if<std::shared_ptr<const Mesh>>(&body.shape);
    if (!mesh || !poses.valid[body.frame]) continue;
    const Eigen::Isometry3d sensor_from_body =
        world_from_sensor.inverse(Eigen::Isometry) * poses.pose[body.frame] * body.frame_from_body;
    for (const auto& t : (*mesh)->triangles()) {
      Eigen::Vector3d p[3];
      for (int k = 0; k < 3; ++k) p[k] = sensor_from_body * (*mesh)->vertices()[t[k]];
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d& a = p[k];
        const Eigen::Vector3d& b = p[(k + 1) % 3];
        if ((a.z() <= 0) == (b.z() <= 0) && a.z() != 0 && b.z() != 0) continue;
        const Eigen::Vector3d x = a.z() == b.z() ? a : a + (b - a) * (a.z() / (a.z() - b.z()));
        out.push_back(std::atan2(x.y(), x.x()));
      }
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

double angularDistance(double a, const std::vector<double>& sorted) {
  double best = kInf;
  for (const double shift : {-2 * M_PI, 0.0, 2 * M_PI}) {
    const auto it = std::lower_bound(sorted.begin(), sorted.end(), a + shift);
    if (it != sorted.end()) best = std::min(best, std::abs(*it - a - shift));
    if (it != sorted.begin()) best = std::min(best, std::abs(*(it - 1) - a - shift));
  }
  return best;
}

// Random scenes (closed spheres, boxes, triangle soups, a room, primitives) at random poses, random
// sensor poses (tilted, so the scan plane cuts the meshes obliquely) and random fans, with and
// without back-face culling and tmin: the fast path must give what the per-beam path gives, except
// within 1e-7 rad of a slice's silhouette, and both must match the brute force.
TEST(Caster, FastPathMatchesGeneralPath) {
  Rng rng(99);
  int compared = 0, hits = 0;
  for (int trial = 0; trial < 40; ++trial) {
    Scene scene;
    scene.addLabel("l");
    const int frames = 3;
    for (int f = 0; f < frames; ++f) scene.addFrame("f" + std::to_string(f));
    const auto room = gridBox(steps(-8, 9, 5), steps(-7, 8, 4), steps(-3, 4, 2), true);
    addBody(&scene, room, 0);
    for (int k = 0; k < 6; ++k) {
      const int frame = k % frames;
      const auto body_pose =
          pose(Eigen::Vector3d(uniform(rng, -5, 5), uniform(rng, -5, 5), uniform(rng, -1, 1)),
               randomRotation(rng).toRotationMatrix());
      switch (k % 6) {
        case 0:
          addBody(&scene, uvSphere(uniform(rng, 0.3, 1.5), 8 + k, 12 + k), frame, body_pose);
          break;
        case 1:
          addBody(&scene, gridBox(steps(-0.5, 0.7, 2), steps(-0.3, 0.4, 3), steps(-1, 1, 2), false),
                  frame, body_pose);
          break;
        case 2:
          addBody(&scene, randomSoup(rng, 300, 1.5, 0.4), frame, body_pose);
          break;
        case 3:
          addBody(&scene, Sphere{uniform(rng, 0.2, 1)}, frame, body_pose);
          break;
        case 4:
          addBody(&scene, Box{Eigen::Vector3d(0.5, 1, 1.5)}, frame, body_pose);
          break;
        default:
          addBody(&scene, prism(circle(17, 0.6), {-0.5, 0.0, 0.5}, false), frame, body_pose);
      }
    }
    FramePoses poses = FramePoses::identity(scene);
    for (int f = 1; f < frames; ++f) {
      poses.pose[f] =
          pose(Eigen::Vector3d(uniform(rng, -1, 1), uniform(rng, -1, 1), 0),
               rpy(uniform(rng, -0.2, 0.2), uniform(rng, -0.2, 0.2), uniform(rng, -3, 3)));
    }
    const auto sensor =
        pose(Eigen::Vector3d(uniform(rng, -2, 2), uniform(rng, -2, 2), uniform(rng, -0.5, 0.5)),
             rpy(uniform(rng, -0.5, 0.5), uniform(rng, -0.5, 0.5), uniform(rng, -3, 3)));
    // Fans: full turn, a partial window, more than a turn, coarse and fine.
    const double a0 = uniform(rng, -4, 1);
    const FanSpec fans[] = {
        fanBySamples(-M_PI, M_PI, 1000), fanBySamples(a0, a0 + uniform(rng, 0.3, 3), 333),
        fanByIncrement(a0, a0 + 7.5, uniform(rng, 0.005, 0.05)), fanBySamples(a0, a0 + 6, 17)};
    const ScanPattern pattern(fans[trial % 4]);
    CastConfig general = config(false, uniform(rng, 4, 30));
    general.cull_backfaces = trial % 3 == 1;
    general.tmin = trial % 5 == 2 ? uniform(rng, 0.1, 2) : 0.0;
    CastConfig fast = general;
    fast.planar_fast_path = true;

    const ScanResult rf = cast(scene, poses, sensor, pattern, fast);
    const ScanResult rg = cast(scene, poses, sensor, pattern, general);
    const auto truth = bruteForce(scene, poses, sensor, pattern, general);
    const auto bearings = sliceBearings(scene, poses, sensor);
    EXPECT_EQ(rf.stats.bodies_culled, rg.stats.bodies_culled);
    for (int i = 0; i < pattern.size(); ++i) {
      const double azimuth = pattern.azimuth(i);
      if (angularDistance(azimuth, bearings) < 1e-7) continue;
      // Hits within rounding of tmin or tmax may fall either side of it.
      if (near(truth[i].t, general.tmax, 1e-9) || near(truth[i].t, general.tmin, 1e-9)) continue;
      ++compared;
      ASSERT_TRUE(near(rf.range[i], rg.range[i], 1e-9))
          << "trial " << trial << " beam " << i << ": fast " << rf.range[i] << " general "
          << rg.range[i] << " truth " << truth[i].t;
      ASSERT_TRUE(near(rg.range[i], truth[i].t, 1e-9)) << "trial " << trial << " beam " << i;
      if (!near(truth[i].t, truth[i].second_body_t, 1e-9)) {
        ASSERT_EQ(rf.body[i], rg.body[i]) << "trial " << trial << " beam " << i;
        ASSERT_EQ(rg.body[i], truth[i].body) << "trial " << trial << " beam " << i;
      }
      if (std::isfinite(rf.range[i])) ++hits;
    }
  }
  EXPECT_GT(compared, 10000);
  EXPECT_GT(hits, 5000);
}

// -------------------------------------------------------------------------------------------------
// Culling

// Bodies beyond tmax, wholly nearer than tmin, off the scan plane, or outside the fan's window are
// counted in stats.bodies_culled (by hand below) and change nothing: both paths equal the brute
// force over every body.
TEST(Caster, CullingCountsAndChangesNothing) {
  Scene scene = sceneWithFrame();
  auto cube = gridBox(steps(-0.5, 0.5, 1), steps(-0.5, 0.5, 1), steps(-0.5, 0.5, 1), false);
  addBody(&scene, Sphere{0.5}, 0, pose(Eigen::Vector3d(3, 0, 0)));   // 0 visible
  addBody(&scene, Sphere{0.5}, 0, pose(Eigen::Vector3d(20, 0, 0)));  // 1 beyond tmax
  addBody(&scene, Sphere{0.5}, 0, pose(Eigen::Vector3d(3, 0, 2)));   // 2 above the plane
  addBody(&scene, Sphere{0.5}, 0, pose(Eigen::Vector3d(-3, 0, 0)));  // 3 behind the fan
  addBody(&scene, cube, 0, pose(Eigen::Vector3d(0, 15, 0)));         // 4 beyond tmax
  addBody(&scene, cube, 0, pose(Eigen::Vector3d(2, 2, 3)));  // 5 above the plane and every ring
  addBody(&scene, cube, 0, pose(Eigen::Vector3d(0.3, -4, 0), yaw(0.3)));  // 6 at the fan's edge
  addBody(&scene, Sphere{0.1}, 0, pose(Eigen::Vector3d(0.2, 0, 0)));      // 7 nearer than tmin
  addBody(&scene, Cylinder{0.4, 1}, 0, pose(Eigen::Vector3d(1, 3, 0)));   // 8 visible
  addBody(&scene, cube, 0, pose(Eigen::Vector3d(-2, -2, 0)));             // 9 behind the fan
  const FramePoses poses = FramePoses::identity(scene);
  CastConfig base = config(true, 10.0);
  base.tmin = 0.5;
  const ScanPattern planar(fanBySamples(-M_PI / 2, M_PI / 2, 361));
  const ScanPattern rings(fanBySamples(-M_PI / 2, M_PI / 2, 181), {-0.7, -0.3, 0.0, 0.3, 0.6});
  struct Case {
    const ScanPattern* pattern;
    int culled;
  };
  // Planar: 1, 2, 3, 4, 5, 7, 9. Rings: the plane test does not apply, so 2 stays; 5 lies above
  // the highest ring (its lowest point is at 0.615 rad, the ring at 0.6), so no beam reaches it.
  for (const Case& c : {Case{&planar, 7}, Case{&rings, 6}}) {
    const auto truth = bruteForce(scene, poses, Eigen::Isometry3d::Identity(), *c.pattern, base);
    for (const bool fast : {true, false}) {
      CastConfig cfg = base;
      cfg.planar_fast_path = fast;
      const ScanResult r = cast(scene, poses, Eigen::Isometry3d::Identity(), *c.pattern, cfg);
      EXPECT_EQ(r.stats.bodies, 10);
      EXPECT_EQ(r.stats.bodies_culled, c.culled) << (fast ? "fast" : "general");
      EXPECT_EQ(r.stats.bodies_skipped, 0);
      expectMatchesTruth(r, truth, 1e-9, fast ? "fast" : "general");
    }
    // The planar fan's first beam (azimuth -pi/2) sees body 6, at the fan's edge.
    if (c.pattern == &planar) {
      EXPECT_EQ(truth[0].body, 6);
    }
  }
  int sees_2 = 0;
  for (const auto& t : bruteForce(scene, poses, Eigen::Isometry3d::Identity(), rings, base)) {
    sees_2 += t.body == 2;
  }
  EXPECT_GT(sees_2, 0);
}

// Random scenes with everything culled or not: the result never depends on culling, checked
// against the brute force for both paths and both pattern kinds.
TEST(Caster, RandomScenesMatchBruteForce) {
  Rng rng(1234);
  for (int trial = 0; trial < 12; ++trial) {
    Scene scene = sceneWithFrame();
    for (int k = 0; k < 12; ++k) {
      const auto p =
          pose(Eigen::Vector3d(uniform(rng, -15, 15), uniform(rng, -15, 15), uniform(rng, -3, 3)),
               randomRotation(rng).toRotationMatrix());
      if (k % 3 == 0) addBody(&scene, uvSphere(uniform(rng, 0.3, 2), 6, 10), 0, p);
      if (k % 3 == 1) addBody(&scene, Cylinder{uniform(rng, 0.2, 1), uniform(rng, 0.5, 3)}, 0, p);
      if (k % 3 == 2) addBody(&scene, Box{Eigen::Vector3d(1, 2, 0.5)}, 0, p);
    }
    const FramePoses poses = FramePoses::identity(scene);
    const auto sensor =
        pose(Eigen::Vector3d(uniform(rng, -2, 2), uniform(rng, -2, 2), 0),
             rpy(uniform(rng, -0.2, 0.2), uniform(rng, -0.2, 0.2), uniform(rng, -3, 3)));
    const double a0 = uniform(rng, -3, 0);
    const ScanPattern planar(fanBySamples(a0, a0 + uniform(rng, 0.5, 3), 500));
    const ScanPattern rings(fanBySamples(a0, a0 + 2, 120), {-0.5, -0.1, 0.0, 0.3});
    CastConfig base = config(true, uniform(rng, 5, 20));
    base.tmin = uniform(rng, 0, 1);
    for (const ScanPattern* pattern : {&planar, &rings}) {
      const auto truth = bruteForce(scene, poses, sensor, *pattern, base);
      for (const bool fast : {true, false}) {
        CastConfig cfg = base;
        cfg.planar_fast_path = fast;
        expectMatchesTruth(cast(scene, poses, sensor, *pattern, cfg), truth, 1e-9,
                           "trial " + std::to_string(trial));
        if (HasFatalFailure()) return;
      }
    }
  }
}

// -------------------------------------------------------------------------------------------------
// Back faces, incidence, tmin

// A room wound inward is all front faces from inside; wound outward, all back faces. With
// cull_backfaces the outward room vanishes from inside but is seen from outside; both paths.
TEST(Caster, CullBackfaces) {
  const auto xs = steps(-3, 3, 4), ys = steps(-2, 4, 3), zs = steps(-1, 1, 2);
  const auto inward = gridBox(xs, ys, zs, true), outward = gridBox(xs, ys, zs, false);
  const ScanPattern planar(fanBySamples(-M_PI, M_PI, 720));
  const ScanPattern rings(fanBySamples(-M_PI, M_PI, 180), {-0.5, 0.0, 0.5});
  const auto inside = pose(Eigen::Vector3d(0.5, 0.25, 0.1), yaw(0.3));
  const auto outside = pose(Eigen::Vector3d(-6, 0.5, 0), yaw(0.05));
  for (const ScanPattern* pattern : {&planar, &rings}) {
    for (const bool fast : {true, false}) {
      for (const bool cull : {false, true}) {
        CastConfig c = config(fast);
        c.cull_backfaces = cull;
        for (const bool in : {true, false}) {
          Scene scene = sceneWithFrame();
          addBody(&scene, in ? inward : outward, 0);
          const FramePoses poses = FramePoses::identity(scene);
          const ScanResult r = cast(scene, poses, inside, *pattern, c);
          const int expected_misses = cull && !in ? pattern->size() : 0;
          EXPECT_EQ(misses(r), expected_misses)
              << (fast ? "fast" : "general") << (cull ? " cull" : "")
              << (in ? " inward" : " outward");
          // From outside, some walls face the sensor and some face away: against the brute force.
          const ScanResult o = cast(scene, poses, outside, *pattern, c);
          expectMatchesTruth(o, bruteForce(scene, poses, outside, *pattern, c), 1e-9, "outside");
          EXPECT_GT(pattern->size() - misses(o), 0);
        }
      }
    }
  }
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

// tmin: surfaces nearer than tmin are invisible and what lies beyond is reported; at exactly tmin a
// surface is visible (inclusive). A thin mesh panel and a small sphere in front of a wall.
TEST(Caster, TminHidesNearerSurfaces) {
  MeshBuilder panel;
  const auto a = panel.vertex(Eigen::Vector3d(1, -0.5, -0.5)),
             b = panel.vertex(Eigen::Vector3d(1, 0.5, -0.5)),
             c = panel.vertex(Eigen::Vector3d(1, 0.5, 0.5)),
             d = panel.vertex(Eigen::Vector3d(1, -0.5, 0.5));
  panel.quad(a, b, c, d, Eigen::Vector3d(-1, 0, 0));
  MeshBuilder wall;
  const auto e = wall.vertex(Eigen::Vector3d(3, -5, -5)),
             f = wall.vertex(Eigen::Vector3d(3, 5, -5)), g = wall.vertex(Eigen::Vector3d(3, 5, 5)),
             h = wall.vertex(Eigen::Vector3d(3, -5, 5));
  wall.quad(e, f, g, h, Eigen::Vector3d(-1, 0, 0));
  const ScanPattern fan(fanBySamples(-0.1, 0.1, 5));
  const ScanPattern rings(fanBySamples(-0.1, 0.1, 5), {-0.05, 0.0, 0.05});
  for (const bool use_sphere : {false, true}) {
    Scene scene = sceneWithFrame();
    const int wall_body = addBody(&scene, wall.build(), 0);
    const int near_body = use_sphere
                              ? addBody(&scene, Sphere{0.2}, 0, pose(Eigen::Vector3d(1, 0, 0)))
                              : addBody(&scene, panel.build(), 0);
    const FramePoses poses = FramePoses::identity(scene);
    const double near_t = use_sphere ? 0.8 : 1.0;  // the near body's first surface at azimuth 0
    for (const ScanPattern* pattern : {&fan, &rings}) {
      const int mid = pattern->size() / 2;  // azimuth 0, elevation 0
      for (const bool fast : {true, false}) {
        CastConfig cfg = config(fast);
        cfg.tmin = 0;
        ScanResult r = cast(scene, poses, Eigen::Isometry3d::Identity(), *pattern, cfg);
        EXPECT_NEAR(r.range[mid], near_t, 1e-12);
        EXPECT_EQ(r.body[mid], near_body);
        const double first = r.range[mid];
        cfg.tmin = first;  // exactly the computed distance: inclusive
        r = cast(scene, poses, Eigen::Isometry3d::Identity(), *pattern, cfg);
        EXPECT_EQ(r.range[mid], first);
        EXPECT_EQ(r.body[mid], near_body);
        cfg.tmin = 1.5;  // past the panel and the whole sphere
        r = cast(scene, poses, Eigen::Isometry3d::Identity(), *pattern, cfg);
        for (int i = 0; i < pattern->size(); ++i) {
          EXPECT_EQ(r.body[i], wall_body) << i;
          const Eigen::Vector3d w = pattern->directions()[i];
          EXPECT_NEAR(r.range[i], 3 / w.x(), 1e-12) << i;
        }
        cfg.tmin = 3.5;  // past everything
        r = cast(scene, poses, Eigen::Isometry3d::Identity(), *pattern, cfg);
        EXPECT_EQ(misses(r), pattern->size());
      }
    }
  }
  // A sensor inside a sphere with tmin past its far side sees nothing of it.
  Scene scene = sceneWithFrame();
  addBody(&scene, Sphere{0.5}, 0);
  CastConfig cfg = config(true);
  cfg.tmin = 0.6;
  EXPECT_EQ(
      misses(cast(scene, FramePoses::identity(scene), Eigen::Isometry3d::Identity(), fan, cfg)),
      fan.size());
  cfg.tmin = 0.4;
  const ScanResult r =
      cast(scene, FramePoses::identity(scene), Eigen::Isometry3d::Identity(), fan, cfg);
  EXPECT_NEAR(r.range[2], 0.5, 1e-12);
}

// CastConfig::validate names the field and the value; cast() validates.
TEST(CastConfig, ValidateNamesFieldAndValue) {
  auto message = [](const CastConfig& c) { return invalidMessage([&] { c.validate(); }); };
  CastConfig c;
  EXPECT_NO_THROW(c.validate());
  c.tmin = -0.5;
  expectMentions(message(c), {"tmin", "-0.5"});
  c.tmin = kNan;
  expectMentions(message(c), {"tmin", "nan"});
  c.tmin = kInf;
  expectMentions(message(c), {"tmin", "inf"});
  c = CastConfig{};
  c.tmax = 0;
  expectMentions(message(c), {"tmax", "0"});
  c.tmin = 2;
  c.tmax = 2;
  expectMentions(message(c), {"tmax", "tmin", "2"});
  c.tmax = 1.5;
  expectMentions(message(c), {"tmax", "1.5", "tmin"});
  c.tmax = kNan;
  expectMentions(message(c), {"tmax", "nan"});
  c = CastConfig{};
  c.tmax = kInf;  // no far limit is allowed
  EXPECT_NO_THROW(c.validate());

  Scene scene = sceneWithFrame();
  addBody(&scene, Sphere{1}, 0, pose(Eigen::Vector3d(3, 0, 0)));
  c = CastConfig{};
  c.tmin = -1;
  Caster caster;
  EXPECT_THROW(caster.cast(scene, FramePoses::identity(scene), Eigen::Isometry3d::Identity(),
                           ScanPattern(fanBySamples(-1, 1, 3)), c),
               std::invalid_argument);
}

}  // namespace
}  // namespace laser_raycast_test
