// Caster: ranges against hand formulas, the planar fast path against the per-beam path, the fast
// path's watertightness, culling, frames, far-from-origin poses, reuse, back faces, incidence and
// tmin. Expected values come from formulas or from a brute force written here.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "expect_invalid.h"
#include "fan_specs.h"
#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/fan_slicer.h"
#include "laser_raycast/core/pose.h"
#include "random.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast::core;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

// --- Geometry builders ---

class MeshBuilder {
 public:
  std::uint32_t vertex(const Eigen::Vector3d& p) {
    vertices_.push_back(p);
    return static_cast<std::uint32_t>(vertices_.size() - 1);
  }
  // A triangle wound so that its front face looks along `front` (outward or inward).
  void triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c, const Eigen::Vector3d& front) {
    const Eigen::Vector3d n = (vertices_[b] - vertices_[a]).cross(vertices_[c] - vertices_[a]);
    if (n.dot(front) >= 0) {
      triangles_.push_back({a, b, c});
    } else {
      triangles_.push_back({a, c, b});
    }
  }
  void quad(std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d,
            const Eigen::Vector3d& front) {
    triangle(a, b, c, front);
    triangle(a, c, d, front);
  }
  std::shared_ptr<const Mesh> build() const {
    return std::make_shared<const Mesh>(vertices_, triangles_);
  }
  const std::vector<Eigen::Vector3d>& vertices() const { return vertices_; }

 private:
  std::vector<Eigen::Vector3d> vertices_;
  std::vector<TriangleIndices> triangles_;
};

// The surface of the box [lo, hi], each face a grid over the given coordinates (which must start at
// lo and end at hi on their axis), so that vertex rows lie exactly at chosen heights. Neighbouring
// faces use the same coordinates, so every edge is shared exactly. Front faces point inward
// (a room) or outward (an object).
std::shared_ptr<const Mesh> gridBox(const std::vector<double>& xs, const std::vector<double>& ys,
                                    const std::vector<double>& zs, bool inward) {
  MeshBuilder m;
  const std::vector<double>* coords[3] = {&xs, &ys, &zs};
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (const bool high : {false, true}) {
      const double w = high ? coords[axis]->back() : coords[axis]->front();
      Eigen::Vector3d out = Eigen::Vector3d::Zero();
      out[axis] = high ? 1 : -1;
      const Eigen::Vector3d front = inward ? -out : out;
      const auto& us = *coords[u];
      const auto& vs = *coords[v];
      std::vector<std::uint32_t> ids(us.size() * vs.size());
      for (std::size_t i = 0; i < us.size(); ++i) {
        for (std::size_t j = 0; j < vs.size(); ++j) {
          Eigen::Vector3d p;
          p[axis] = w;
          p[u] = us[i];
          p[v] = vs[j];
          ids[i * vs.size() + j] = m.vertex(p);
        }
      }
      for (std::size_t i = 0; i + 1 < us.size(); ++i) {
        for (std::size_t j = 0; j + 1 < vs.size(); ++j) {
          m.quad(ids[i * vs.size() + j], ids[(i + 1) * vs.size() + j],
                 ids[(i + 1) * vs.size() + j + 1], ids[i * vs.size() + j + 1], front);
        }
      }
    }
  }
  return m.build();
}

std::vector<double> steps(double lo, double hi, int n) {
  std::vector<double> out;
  for (int i = 0; i <= n; ++i) out.push_back(i == n ? hi : lo + (hi - lo) * i / n);
  return out;
}

// A closed prism over a polygon star-shaped about the origin (xy), with vertex rows at zs (first
// and last are the caps, fanned to the axis).
std::shared_ptr<const Mesh> prism(const std::vector<Eigen::Vector2d>& polygon,
                                  const std::vector<double>& zs, bool inward) {
  MeshBuilder m;
  const std::size_t n = polygon.size();
  std::vector<std::vector<std::uint32_t>> rows;
  for (const double z : zs) {
    rows.emplace_back();
    for (const auto& p : polygon) rows.back().push_back(m.vertex(Eigen::Vector3d(p.x(), p.y(), z)));
  }
  const double sign = inward ? -1 : 1;
  for (std::size_t r = 0; r + 1 < zs.size(); ++r) {
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t j = (i + 1) % n;
      const Eigen::Vector2d mid = 0.5 * (polygon[i] + polygon[j]);
      const Eigen::Vector2d edge = polygon[j] - polygon[i];
      Eigen::Vector3d out(edge.y(), -edge.x(), 0);
      if (out.head<2>().dot(mid) < 0) out = -out;
      m.quad(rows[r][i], rows[r][j], rows[r + 1][j], rows[r + 1][i], sign * out);
    }
  }
  for (const bool top : {false, true}) {
    const double z = top ? zs.back() : zs.front();
    const std::uint32_t c = m.vertex(Eigen::Vector3d(0, 0, z));
    const auto& row = top ? rows.back() : rows.front();
    for (std::size_t i = 0; i < n; ++i) {
      m.triangle(c, row[i], row[(i + 1) % n], sign * Eigen::Vector3d(0, 0, top ? 1 : -1));
    }
  }
  return m.build();
}

std::vector<Eigen::Vector2d> circle(int n, double radius, double phase = 0) {
  std::vector<Eigen::Vector2d> out;
  for (int i = 0; i < n; ++i) {
    const double a = phase + 2 * M_PI * i / n;
    out.emplace_back(radius * std::cos(a), radius * std::sin(a));
  }
  return out;
}

// A lat-long sphere (closed, outward), for random scenes.
std::shared_ptr<const Mesh> uvSphere(double radius, int rings, int segments) {
  MeshBuilder m;
  const std::uint32_t south = m.vertex(Eigen::Vector3d(0, 0, -radius));
  const std::uint32_t north = m.vertex(Eigen::Vector3d(0, 0, radius));
  std::vector<std::vector<std::uint32_t>> row(rings - 1);
  for (int r = 1; r < rings; ++r) {
    const double phi = -M_PI / 2 + M_PI * r / rings;
    for (int s = 0; s < segments; ++s) {
      const double th = 2 * M_PI * s / segments;
      row[r - 1].push_back(
          m.vertex(radius * Eigen::Vector3d(std::cos(phi) * std::cos(th),
                                            std::cos(phi) * std::sin(th), std::sin(phi))));
    }
  }
  auto out = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    return (m.vertices()[a] + m.vertices()[b] + m.vertices()[c]).eval();
  };
  for (int s = 0; s < segments; ++s) {
    const int t = (s + 1) % segments;
    m.triangle(south, row[0][s], row[0][t], out(south, row[0][s], row[0][t]));
    m.triangle(north, row.back()[s], row.back()[t], out(north, row.back()[s], row.back()[t]));
    for (int r = 0; r + 1 < rings - 1; ++r) {
      m.quad(row[r][s], row[r][t], row[r + 1][t], row[r + 1][s],
             out(row[r][s], row[r][t], row[r + 1][t]));
    }
  }
  return m.build();
}

std::shared_ptr<const Mesh> randomSoup(Rng& rng, int n, double spread, double size) {
  MeshBuilder m;
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d c(spread * u(rng), spread * u(rng), spread * u(rng));
    const auto a = m.vertex(c + size * Eigen::Vector3d(u(rng), u(rng), u(rng)));
    const auto b = m.vertex(c + size * Eigen::Vector3d(u(rng), u(rng), u(rng)));
    const auto d = m.vertex(c + size * Eigen::Vector3d(u(rng), u(rng), u(rng)));
    m.triangle(a, b, d, Eigen::Vector3d(u(rng), u(rng), u(rng)));
  }
  return m.build();
}

// --- Poses ---

Eigen::Isometry3d pose(const Eigen::Vector3d& t,
                       const Eigen::Matrix3d& r = Eigen::Matrix3d::Identity()) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.linear() = r;
  p.translation() = t;
  return p;
}

// A rotation about z with exact zeros and one, so that z is preserved bit for bit.
Eigen::Matrix3d yaw(double a) {
  Eigen::Matrix3d r;
  r << std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a), 0, 0, 0, 1;
  return r;
}

Eigen::Matrix3d rpy(double roll, double pitch, double yaw_angle) {
  return (Eigen::AngleAxisd(yaw_angle, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

// --- Scenes ---

int addBody(Scene* scene, Shape shape, int frame,
            const Eigen::Isometry3d& frame_from_body = Eigen::Isometry3d::Identity(),
            int label = 0) {
  Body body;
  body.shape = std::move(shape);
  body.frame = frame;
  body.label = label;
  body.frame_from_body = frame_from_body;
  return scene->addBody(body);
}

Scene sceneWithFrame(const std::string& frame = "world") {
  Scene scene;
  scene.addFrame(frame);
  scene.addLabel("thing");
  return scene;
}

CastConfig config(bool fast_path, double tmax = 30.0) {
  CastConfig c;
  c.planar_fast_path = fast_path;
  c.tmax = tmax;
  return c;
}

ScanResult cast(const Scene& scene, const FramePoses& poses, const Eigen::Isometry3d& sensor,
                const ScanPattern& pattern, const CastConfig& c) {
  Caster caster;
  return caster.cast(scene, poses, sensor, pattern, c);
}

// --- Independent reference ---

struct BeamTruth {
  double t = kInf;
  int body = -1;
  int triangle = -1;
  double second_body_t = kInf;  // nearest hit on any other body
};

// Every beam against every body (no culling, no BVH): triangles with intersectTriangle, primitives
// with intersect(), rays transformed with Eigen's own inverse.
std::vector<BeamTruth> bruteForce(const Scene& scene, const FramePoses& poses,
                                  const Eigen::Isometry3d& world_from_sensor,
                                  const ScanPattern& pattern, const CastConfig& c) {
  std::vector<BeamTruth> out(pattern.size());
  const auto& bodies = scene.bodies();
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    const Body& body = bodies[b];
    if (!poses.valid[body.frame]) continue;
    const Eigen::Isometry3d body_from_sensor =
        (poses.pose[body.frame] * body.frame_from_body).inverse(Eigen::Isometry) *
        world_from_sensor;
    for (int i = 0; i < pattern.size(); ++i) {
      Ray ray;
      ray.origin = body_from_sensor.translation();
      ray.dir = body_from_sensor.linear() * pattern.directions()[i];
      ray.tmin = c.tmin;
      ray.tmax = c.tmax;
      double t = kInf;
      int tri = -1;
      if (const auto* mesh = std::get_if<std::shared_ptr<const Mesh>>(&body.shape)) {
        const auto& v = (*mesh)->vertices();
        const auto& ts = (*mesh)->triangles();
        for (std::size_t k = 0; k < ts.size(); ++k) {
          const auto hit = intersectTriangle(c.method, ray, v[ts[k][0]], v[ts[k][1]], v[ts[k][2]],
                                             c.cull_backfaces);
          if (hit && hit->t < t) {
            t = hit->t;
            tri = static_cast<int>(k);
          }
        }
      } else {
        std::optional<PrimitiveHit> hit;
        if (const auto* box = std::get_if<Box>(&body.shape)) hit = intersect(ray, *box);
        if (const auto* cyl = std::get_if<Cylinder>(&body.shape)) hit = intersect(ray, *cyl);
        if (const auto* sph = std::get_if<Sphere>(&body.shape)) hit = intersect(ray, *sph);
        if (hit) t = hit->t;
      }
      BeamTruth& truth = out[i];
      if (t < truth.t) {
        truth.second_body_t = truth.t;
        truth.t = t;
        truth.body = static_cast<int>(b);
        truth.triangle = tri;
      } else if (t < truth.second_body_t) {
        truth.second_body_t = t;
      }
    }
  }
  return out;
}

bool near(double a, double b, double rel) {
  if (std::isinf(a) || std::isinf(b)) return a == b;
  return std::abs(a - b) <= rel * std::max(std::abs(a), std::abs(b));
}

// result against the brute force: same hit/miss, range within rel, same body unless two bodies are
// hit within rel of each other.
void expectMatchesTruth(const ScanResult& result, const std::vector<BeamTruth>& truth, double rel,
                        const std::string& what) {
  ASSERT_EQ(result.range.size(), truth.size()) << what;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    ASSERT_TRUE(near(result.range[i], truth[i].t, rel))
        << what << " beam " << i << ": " << result.range[i] << " vs " << truth[i].t;
    if (!near(truth[i].t, truth[i].second_body_t, rel)) {
      ASSERT_EQ(result.body[i], truth[i].body) << what << " beam " << i;
    }
  }
}

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

// -------------------------------------------------------------------------------------------------
// Hand formulas

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
// Watertightness of the fast path

int misses(const ScanResult& r) {
  int n = 0;
  for (const double t : r.range) n += !std::isfinite(t);
  return n;
}

// How many of the mesh's outline segments each beam crosses, nearest or not. From a point of a
// star-shaped outline's kernel it is exactly one per beam: more would be a shared segment endpoint
// counted twice (a double hit), fewer a leak.
std::vector<int> crossingsPerBeam(const Mesh& mesh, const Eigen::Isometry3d& world_from_sensor,
                                  const ScanPattern& pattern) {
  const int n = pattern.size();
  std::vector<double> range(n, std::numeric_limits<double>::infinity());
  std::vector<int> body(n, -1), triangle(n, -1), crossings(n, 0);
  sliceMesh(mesh, relativePose(world_from_sensor, Eigen::Isometry3d::Identity()), pattern, 0.0,
            std::numeric_limits<double>::infinity(), false, 0,
            DepthBuffer{&range, &body, &triangle, &crossings});
  return crossings;
}

// Closed meshes with a vertex row exactly at the sensor's height: the scan plane runs through rows
// of vertices and along horizontal edges. From inside, every beam must hit, for many fans and
// sensor positions; and the fast path must agree with the general path.
TEST(Caster, FastPathIsWatertightThroughVertexRows) {
  Rng rng(7);
  const double h = 0.375;  // the sensor's height, and a vertex row
  std::vector<std::shared_ptr<const Mesh>> meshes;
  for (const int n : {3, 4, 5, 8, 31, 97, 256}) {
    meshes.push_back(prism(circle(n, 2.0, 0.1 * n), {h - 1, h, h + 0.25, h + 1}, true));
  }
  meshes.push_back(gridBox(steps(-3, 4, 7), steps(-2, 2.5, 9), {h - 1, h, h + 1.5}, true));
  // The same closed surfaces wound outward: culling is off, so they must be as tight.
  meshes.push_back(prism(circle(12, 2.0), {h - 2, h - 1, h, h + 1}, false));
  const std::vector<int> sample_counts = {2, 3, 7, 64, 360, 361, 720, 1000, 1441};
  int casts = 0;
  for (const auto& mesh : meshes) {
    Scene scene = sceneWithFrame();
    addBody(&scene, mesh, 0);
    const FramePoses poses = FramePoses::identity(scene);
    for (int s = 0; s < 12; ++s) {
      // Inside: within 0.9 m of the axis (every prism's inradius is at least 2 cos(60 deg) = 1).
      const double rho = 0.9 * std::sqrt(uniform(rng, 0, 1)), phi = uniform(rng, -M_PI, M_PI);
      const auto sensor = pose(Eigen::Vector3d(rho * std::cos(phi), rho * std::sin(phi), h),
                               yaw(uniform(rng, -4, 4)));
      const int samples = sample_counts[(s + casts) % sample_counts.size()];
      const double a0 = s % 3 == 0 ? -M_PI : uniform(rng, -7, 7);
      const ScanPattern pattern(fanBySamples(a0, a0 + (s % 2 ? 2 * M_PI : 5.0), samples));
      const ScanResult fast = cast(scene, poses, sensor, pattern, config(true));
      const ScanResult general = cast(scene, poses, sensor, pattern, config(false));
      ASSERT_EQ(misses(fast), 0) << "mesh " << casts << " sensor " << s;
      ASSERT_EQ(misses(general), 0) << "mesh " << casts << " sensor " << s;
      const std::vector<int> crossings = crossingsPerBeam(*mesh, sensor, pattern);
      for (int i = 0; i < pattern.size(); ++i) {
        ASSERT_EQ(crossings[i], 1) << "mesh " << casts << " sensor " << s << " beam " << i;
      }
      for (int i = 0; i < pattern.size(); ++i)
        ASSERT_TRUE(near(fast.range[i], general.range[i], 1e-9));
    }
    ++casts;
  }
}

// Beams aimed exactly at vertices: a star polygon whose corners are placed at the beams' own
// directions times a power of two (so r * cos a and r * sin a are exact and the beam's line passes
// through the corner without rounding), with a vertex row at the sensor's height.
TEST(Caster, FastPathIsWatertightThroughVertices) {
  for (const int n : {6, 24, 180, 720}) {
    for (const int every : {1, 2, 3}) {
      const ScanPattern pattern(
          fanByIncrement(-M_PI + 0.01, -M_PI + 0.01 + 2 * M_PI * (n - 1) / n, 2 * M_PI / n));
      ASSERT_EQ(pattern.size(), n);
      std::vector<Eigen::Vector2d> star;
      for (int i = 0; i < n; i += every) {
        const double r = (i / every) % 2 ? 2.0 : 4.0;
        star.emplace_back(r * pattern.directions()[i].x(), r * pattern.directions()[i].y());
      }
      if (star.size() < 3) continue;
      Scene scene = sceneWithFrame();
      addBody(&scene, prism(star, {-1.0, 0.0, 1.0}, true), 0);
      const FramePoses poses = FramePoses::identity(scene);
      for (const bool fast : {true, false}) {
        const ScanResult r =
            cast(scene, poses, Eigen::Isometry3d::Identity(), pattern, config(fast));
        ASSERT_EQ(misses(r), 0) << "n " << n << " every " << every << (fast ? " fast" : " general");
        if (fast) {
          // Every corner is a shared endpoint that a beam runs through exactly.
          const std::vector<int> crossings =
              crossingsPerBeam(*std::get<std::shared_ptr<const Mesh>>(scene.bodies()[0].shape),
                               Eigen::Isometry3d::Identity(), pattern);
          for (int i = 0; i < n; ++i) ASSERT_EQ(crossings[i], 1) << "n " << n << " beam " << i;
        }
        // The beams through a corner measure exactly its radius.
        for (int i = 0; i < n; i += every) {
          ASSERT_NEAR(r.range[i], (i / every) % 2 ? 2.0 : 4.0, 1e-12) << i;
        }
      }
    }
  }
}

// A tilted sensor in a closed room: generic crossings, every beam must still hit.
TEST(Caster, FastPathIsWatertightWhenTilted) {
  Rng rng(21);
  const auto room = gridBox(steps(-3, 4, 9), steps(-2, 5, 11), steps(-1, 2, 5), true);
  const auto drum = prism(circle(40, 2.5), steps(-1, 1, 6), true);
  for (const auto& mesh : {room, drum}) {
    Scene scene = sceneWithFrame();
    addBody(&scene, mesh, 0);
    const FramePoses poses = FramePoses::identity(scene);
    for (int s = 0; s < 30; ++s) {
      const auto sensor =
          pose(Eigen::Vector3d(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -0.5, 0.5)),
               rpy(uniform(rng, -0.3, 0.3), uniform(rng, -0.3, 0.3), uniform(rng, -4, 4)));
      const ScanPattern pattern(fanBySamples(-M_PI, M_PI, 500 + 37 * s));
      const ScanResult r = cast(scene, poses, sensor, pattern, config(true));
      ASSERT_EQ(misses(r), 0) << "sensor " << s;
    }
  }
}

// The beam windows' helpers: approxAtan2 stays within its stated bound of std::atan2 over every
// direction (both lie in (-pi, pi]; compared on the circle), and azimuthWindow contains the bearing
// of every point of the sphere it is given (sampled on its surface, the extreme bearings included).
TEST(BeamWindow, ApproxAtan2IsWithinItsBound) {
  Rng rng(41);
  double worst = 0;
  for (int i = 0; i < 200000; ++i) {
    const double a = uniform(rng, -M_PI, M_PI);
    const double r = std::pow(10.0, uniform(rng, -6, 6));
    const double x = r * std::cos(a), y = r * std::sin(a);
    double diff = std::abs(approxAtan2(y, x) - std::atan2(y, x));
    diff = std::min(diff, 2 * M_PI - diff);
    worst = std::max(worst, diff);
  }
  for (const double x : {1.0, -1.0, 0.0}) {  // the axes and the diagonals exactly
    for (const double y : {1.0, -1.0, 0.0}) {
      if (x == 0 && y == 0) continue;
      double diff = std::abs(approxAtan2(y, x) - std::atan2(y, x));
      worst = std::max(worst, std::min(diff, 2 * M_PI - diff));
    }
  }
  EXPECT_LE(worst, kBearingError);
  EXPECT_GT(worst, 0.0);  // it is an approximation: the bound is what matters
}

TEST(BeamWindow, AzimuthWindowContainsTheSphere) {
  Rng rng(43);
  int limited = 0;
  for (int i = 0; i < 3000; ++i) {
    const Eigen::Vector3d c(uniform(rng, -20, 20), uniform(rng, -20, 20), uniform(rng, -5, 5));
    const double radius = std::pow(10.0, uniform(rng, -3, 1.2));
    const double angle_min = uniform(rng, -10, 10);
    double start, width;
    if (!azimuthWindow(c, radius, angle_min, &start, &width)) continue;
    ++limited;
    ASSERT_GE(start, 0.0);
    ASSERT_LT(start, 2 * M_PI);
    // The two tangent bearings of the sphere's horizontal disc, and random points of the sphere.
    const double rho = std::hypot(c.x(), c.y());
    const double centre = std::atan2(c.y(), c.x());
    std::vector<double> bearings = {centre + std::asin(radius / rho),
                                    centre - std::asin(radius / rho)};
    for (int k = 0; k < 20; ++k) {
      Eigen::Vector3d u(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
      if (u.norm() == 0) continue;
      const Eigen::Vector3d p = c + radius * u.normalized();
      bearings.push_back(std::atan2(p.y(), p.x()));
    }
    for (const double b : bearings) {
      // Offset from the window's start, on the circle.
      double offset = std::fmod(b - angle_min - start, 2 * M_PI);
      if (offset < 0) offset += 2 * M_PI;
      EXPECT_LE(offset, width) << "sphere " << i;
    }
  }
  EXPECT_GT(limited, 2000);
}

// -------------------------------------------------------------------------------------------------
// Culling

// Bodies beyond tmax, wholly nearer than tmin, off the scan plane, or outside the fan's window are
// counted in stats.bodies_culled (by hand below) and change nothing: both paths equal the brute
// force over every body.
TEST(Caster, CullingCountsAndChangesNothing) {
  Scene scene = sceneWithFrame();
  auto cube = gridBox(steps(-0.5, 0.5, 1), steps(-0.5, 0.5, 1), steps(-0.5, 0.5, 1), false);
  addBody(&scene, Sphere{0.5}, 0, pose(Eigen::Vector3d(3, 0, 0)));        // 0 visible
  addBody(&scene, Sphere{0.5}, 0, pose(Eigen::Vector3d(20, 0, 0)));       // 1 beyond tmax
  addBody(&scene, Sphere{0.5}, 0, pose(Eigen::Vector3d(3, 0, 2)));        // 2 above the plane
  addBody(&scene, Sphere{0.5}, 0, pose(Eigen::Vector3d(-3, 0, 0)));       // 3 behind the fan
  addBody(&scene, cube, 0, pose(Eigen::Vector3d(0, 15, 0)));              // 4 beyond tmax
  addBody(&scene, cube, 0, pose(Eigen::Vector3d(2, 2, 3)));               // 5 above the plane
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
  // Planar: 1, 2, 3, 4, 5, 7, 9. Rings: the plane test does not apply, so 2 and 5 stay.
  for (const Case& c : {Case{&planar, 7}, Case{&rings, 5}}) {
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
// Frames

// A frame with valid = 0 skips its bodies (counted), and the result is that of the other bodies.
TEST(Caster, InvalidFrameSkipsItsBodies) {
  Scene scene;
  scene.addLabel("l");
  const int base = scene.addFrame("base");
  const int arm = scene.addFrame("arm");
  addBody(&scene, Sphere{0.5}, base, pose(Eigen::Vector3d(4, 0, 0)));
  addBody(&scene, Sphere{0.5}, arm, pose(Eigen::Vector3d(2, 0, 0)));
  addBody(&scene, Box{Eigen::Vector3d(1, 1, 1)}, arm, pose(Eigen::Vector3d(0, 3, 0)));
  FramePoses poses = FramePoses::identity(scene);
  poses.valid[arm] = 0;
  const ScanPattern pattern(fanBySamples(-M_PI, M_PI, 361));
  for (const bool fast : {true, false}) {
    const ScanResult r = cast(scene, poses, Eigen::Isometry3d::Identity(), pattern, config(fast));
    EXPECT_EQ(r.stats.bodies_skipped, 2);
    EXPECT_EQ(r.stats.bodies, 3);
    expectMatchesTruth(
        r, bruteForce(scene, poses, Eigen::Isometry3d::Identity(), pattern, config(fast)), 1e-12,
        "skipped arm");
    for (const int b : r.body) EXPECT_NE(b, 1);
    EXPECT_NEAR(r.range[180], 3.5, 1e-12);  // azimuth 0 sees the base sphere, not the arm's
  }
}

// resolveFramePoses asks the lookup for every frame; unknown, non-rigid and non-finite poses make
// the frame invalid, and the count of invalid frames is returned.
TEST(Caster, ResolveFramePosesWithLambda) {
  Scene scene;
  scene.addLabel("l");
  for (const char* name : {"base", "missing", "scaled", "nan", "sheared", "mirrored", "arm"}) {
    scene.addFrame(name);
  }
  const auto base_pose = pose(Eigen::Vector3d(1, 2, 3), rpy(0.1, 0.2, 0.3));
  const auto arm_pose = pose(Eigen::Vector3d(-1, 0, 0.5), yaw(1.0));
  std::vector<std::string> asked;
  const PoseLookup lookup = [&](const std::string& frame, Eigen::Isometry3d& p) {
    asked.push_back(frame);
    if (frame == "missing") return false;
    p = Eigen::Isometry3d::Identity();
    if (frame == "base") p = base_pose;
    if (frame == "arm") p = arm_pose;
    if (frame == "scaled") p.linear() *= 1.01;
    if (frame == "nan") p.translation().x() = kNan;
    if (frame == "sheared") p.linear()(0, 1) = 0.05;
    if (frame == "mirrored") p.linear()(2, 2) = -1;
    return true;
  };
  FramePoses poses;
  EXPECT_EQ(resolveFramePoses(scene, lookup, &poses), 5);
  EXPECT_EQ(asked, scene.frames());
  ASSERT_EQ(poses.valid.size(), 7u);
  ASSERT_EQ(poses.pose.size(), 7u);
  EXPECT_EQ(poses.valid, (std::vector<char>{1, 0, 0, 0, 0, 0, 1}));
  EXPECT_TRUE(poses.pose[0].isApprox(base_pose, 0));
  EXPECT_TRUE(poses.pose[6].isApprox(arm_pose, 0));

  // The resolved poses cast: a body on the arm at (2, 0, 0) in the arm frame.
  addBody(&scene, Sphere{0.25}, 6, pose(Eigen::Vector3d(2, 0, 0)));
  addBody(&scene, Sphere{0.25}, 2, pose(Eigen::Vector3d(1, 0, 0)));  // on "scaled": skipped
  resolveFramePoses(scene, lookup, &poses);
  const ScanPattern pattern(fanBySamples(-M_PI, M_PI, 90));
  const auto sensor = pose(Eigen::Vector3d(0, 0, 0.5));
  const ScanResult r = cast(scene, poses, sensor, pattern, config(true));
  EXPECT_EQ(r.stats.bodies_skipped, 1);
  expectMatchesTruth(r, bruteForce(scene, poses, sensor, pattern, config(true)), 1e-9, "arm");
  // The sphere sits at arm_pose * (2, 0, 0), in the scan plane z = 0.5: some beams see it.
  int seen = 0;
  for (int i = 0; i < pattern.size(); ++i) seen += r.body[i] == 0;
  EXPECT_GT(seen, 0);
}

// A sensor pose that is not a finite rigid transform gives every beam NaN (REP 117: erroneous).
TEST(Caster, InvalidSensorPoseGivesNan) {
  Scene scene = sceneWithFrame();
  addBody(&scene, Sphere{1}, 0, pose(Eigen::Vector3d(3, 0, 0)));
  const FramePoses poses = FramePoses::identity(scene);
  const ScanPattern pattern(fanBySamples(-1, 1, 50));
  Eigen::Isometry3d nan_pose = Eigen::Isometry3d::Identity();
  nan_pose.translation().y() = kNan;
  Eigen::Isometry3d inf_pose = Eigen::Isometry3d::Identity();
  inf_pose.linear()(1, 1) = kInf;
  Eigen::Isometry3d scaled = Eigen::Isometry3d::Identity();
  scaled.linear() *= 2;
  Eigen::Isometry3d mirrored = Eigen::Isometry3d::Identity();
  mirrored.linear()(0, 0) = -1;
  Eigen::Isometry3d sheared = Eigen::Isometry3d::Identity();
  sheared.linear()(0, 2) = 1e-3;
  for (const auto& bad : {nan_pose, inf_pose, scaled, mirrored, sheared}) {
    for (const bool fast : {true, false}) {
      Caster caster;
      // A good cast first, so that a stale result cannot pass for the NaN one.
      caster.cast(scene, poses, Eigen::Isometry3d::Identity(), pattern, config(fast));
      const ScanResult& r = caster.cast(scene, poses, bad, pattern, config(fast));
      ASSERT_EQ(r.range.size(), 50u);
      for (int i = 0; i < 50; ++i) {
        EXPECT_TRUE(std::isnan(r.range[i]));
        EXPECT_EQ(r.body[i], -1);
        EXPECT_EQ(r.triangle[i], -1);
      }
      EXPECT_FALSE(r.stats.reused);
    }
  }
  // Slightly off (a float quaternion's rounding) is still rigid.
  Eigen::Isometry3d almost = Eigen::Isometry3d::Identity();
  almost.linear() =
      Eigen::Quaterniond(
          Eigen::Quaternionf(Eigen::AngleAxisf(0.3f, Eigen::Vector3f::UnitZ())).cast<double>())
          .toRotationMatrix();
  const ScanResult r = cast(scene, poses, almost, pattern, config(true));
  EXPECT_FALSE(std::isnan(r.range[25]));
}

// A frame pose marked valid but not rigid (scaled, sheared, mirrored, NaN) cannot be used: the
// caster treats it as unknown and skips the frame's bodies, as resolveFramePoses would have.
// Regression: the caster used such poses, inverting them by transposing the rotation; the scaled
// one put the sensor on the near sphere's surface and reported 0 m.
TEST(Caster, NonRigidFramePoseIsSkipped) {
  Scene scene;
  scene.addLabel("l");
  const int good = scene.addFrame("good");
  const int bad = scene.addFrame("bad");
  addBody(&scene, Sphere{0.5}, good, pose(Eigen::Vector3d(5, 0, 0)));
  addBody(&scene, Sphere{0.5}, bad, pose(Eigen::Vector3d(2, 0, 0)));
  const ScanPattern pattern(fanBySamples(-0.5, 0.5, 101));
  std::vector<Eigen::Matrix4d> broken;
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m(0, 0) = 0.5;  // scaled
  broken.push_back(m);
  m = Eigen::Matrix4d::Identity();
  m(1, 0) = 0.2;  // sheared
  broken.push_back(m);
  m = Eigen::Matrix4d::Identity();
  m(2, 2) = -1;  // mirrored
  broken.push_back(m);
  m = Eigen::Matrix4d::Identity();
  m(0, 3) = kNan;
  broken.push_back(m);
  for (const auto& matrix : broken) {
    FramePoses poses = FramePoses::identity(scene);
    poses.pose[bad].matrix() = matrix;
    for (const bool fast : {true, false}) {
      const ScanResult r = cast(scene, poses, Eigen::Isometry3d::Identity(), pattern, config(fast));
      EXPECT_EQ(r.stats.bodies_skipped, 1) << matrix;
      EXPECT_EQ(r.range[50], 4.5) << matrix;  // the good sphere, as if "bad" were unknown
      EXPECT_EQ(r.body[50], 0);
    }
  }
}

// FramePoses sized for another scene is an error, not a silent misread.
TEST(Caster, FramePosesSizeMismatchThrows) {
  Scene scene = sceneWithFrame();
  scene.addFrame("second");
  FramePoses poses = FramePoses::identity(scene);
  poses.pose.pop_back();
  const ScanPattern pattern(fanBySamples(-1, 1, 5));
  Caster caster;
  EXPECT_THROW(caster.cast(scene, poses, Eigen::Isometry3d::Identity(), pattern, config(true)),
               std::invalid_argument);
  poses = FramePoses::identity(scene);
  poses.valid.push_back(1);
  EXPECT_THROW(caster.cast(scene, poses, Eigen::Isometry3d::Identity(), pattern, config(true)),
               std::invalid_argument);
}

// -------------------------------------------------------------------------------------------------
// Far from the origin

struct FarScene {
  Scene scene;
  FramePoses poses;
  Eigen::Isometry3d sensor;
};

// A room, boxes (mesh and primitive) and, when curved is set, a sphere and a tilted cylinder,
// spread over three frames.
FarScene farScene(bool curved, const Eigen::Vector3d& sensor_at,
                  const Eigen::Matrix3d& sensor_rot) {
  FarScene s;
  s.scene.addLabel("l");
  const int room_frame = s.scene.addFrame("room");
  const int a = s.scene.addFrame("a");
  const int b = s.scene.addFrame("b");
  addBody(&s.scene, gridBox(steps(-4, 5, 3), steps(-3, 4, 3), steps(-1, 1.5, 2), true), room_frame);
  addBody(&s.scene, Box{Eigen::Vector3d(0.6, 0.6, 1)}, a, pose(Eigen::Vector3d(0.5, 0.5, 0)));
  addBody(&s.scene, gridBox(steps(-0.4, 0.4, 2), steps(-0.4, 0.4, 2), steps(-0.5, 0.5, 1), false),
          b, pose(Eigen::Vector3d(-0.5, 0.5, 0)));
  if (curved) {
    addBody(&s.scene, Sphere{0.4}, a, pose(Eigen::Vector3d(0.25, -2, 0.125)));
    addBody(&s.scene, Cylinder{0.3, 1.2}, b, pose(Eigen::Vector3d(-1, -2, 0), rpy(0.7, 0.4, 0)));
    addBody(&s.scene, uvSphere(0.5, 9, 14), b,
            pose(Eigen::Vector3d(3, -1, 0.25), rpy(0.3, 0.2, 0.1)));
  }
  s.poses = FramePoses::identity(s.scene);
  s.poses.pose[a] = pose(Eigen::Vector3d(2, 1.5, 0), yaw(0.25));
  s.poses.pose[b] = pose(Eigen::Vector3d(-2, -1.5, 0), yaw(-0.6));
  s.sensor = pose(sensor_at, sensor_rot);
  return s;
}

void translateAll(FarScene* s, const Eigen::Vector3d& offset) {
  for (auto& p : s->poses.pose) p.pretranslate(offset);
  s->sensor.pretranslate(offset);
}

// The same scene and sensor moved 10^6 m away (frame poses and sensor pose alike) give the same
// ranges. With dyadic coordinates the translated poses are exact, so any difference would be the
// caster's own loss; with arbitrary coordinates the poses themselves round by ~1e-10 m, which the
// flat-faced scene turns into < 1e-9 relative.
TEST(Caster, FarFromOriginGivesSameRanges) {
  const Eigen::Vector3d offset(1e6, -1e6, 1e6);
  const ScanPattern planar(fanBySamples(-M_PI, M_PI, 1440));
  const ScanPattern rings(fanBySamples(-M_PI, M_PI, 360), {-0.3, -0.1, 0.0, 0.15, 0.3});
  struct Case {
    bool curved;
    Eigen::Vector3d at;
  };
  // 0.125 / 0.0625 are exact at 1e6; 0.1234567 / 0.0987654 are not.
  for (const Case& c : {Case{true, Eigen::Vector3d(0.125, -0.0625, 0.03125)},
                        Case{false, Eigen::Vector3d(0.1234567, -0.0987654, 0.0456789)}}) {
    const FarScene near_origin = farScene(c.curved, c.at, rpy(0.05, -0.08, 0.7));
    FarScene far = farScene(c.curved, c.at, rpy(0.05, -0.08, 0.7));
    translateAll(&far, offset);
    ASSERT_GT(far.sensor.translation().norm(), 1e6);
    for (const ScanPattern* pattern : {&planar, &rings}) {
      for (const bool fast : {true, false}) {
        const ScanResult a =
            cast(near_origin.scene, near_origin.poses, near_origin.sensor, *pattern, config(fast));
        const ScanResult b = cast(far.scene, far.poses, far.sensor, *pattern, config(fast));
        int hits = 0;
        for (int i = 0; i < pattern->size(); ++i) {
          ASSERT_TRUE(std::isfinite(a.range[i]));  // closed room
          ASSERT_TRUE(near(a.range[i], b.range[i], 1e-9))
              << (fast ? "fast" : "general") << " beam " << i << ": " << a.range[i] << " vs "
              << b.range[i] << ", difference " << a.range[i] - b.range[i];
          ASSERT_EQ(a.body[i], b.body[i]) << i;
          hits += a.body[i] != 0;
        }
        EXPECT_GT(hits, 10);  // the objects are seen, not just the room
      }
    }
  }
}

// -------------------------------------------------------------------------------------------------
// Reuse

void expectSameResult(const ScanResult& a, const ScanResult& b) {
  ASSERT_EQ(a.range.size(), b.range.size());
  for (std::size_t i = 0; i < a.range.size(); ++i) {
    ASSERT_TRUE(a.range[i] == b.range[i] || (std::isnan(a.range[i]) && std::isnan(b.range[i])));
  }
  EXPECT_EQ(a.body, b.body);
  EXPECT_EQ(a.triangle, b.triangle);
  EXPECT_EQ(a.cos_incidence, b.cos_incidence);
}

// Casting again with nothing moved returns the previous result (stats.reused); any change that can
// alter the result (a frame, the sensor, validity, config, pattern, the scene) recomputes.
TEST(Caster, ReuseOnlyWhenNothingChanged) {
  Scene scene;
  scene.addLabel("l");
  const int base = scene.addFrame("base");
  const int arm = scene.addFrame("arm");
  addBody(&scene, gridBox(steps(-4, 4, 2), steps(-4, 4, 2), steps(-1, 1, 1), true), base);
  addBody(&scene, Sphere{0.5}, arm, pose(Eigen::Vector3d(2, 0, 0)));
  FramePoses poses = FramePoses::identity(scene);
  const ScanPattern pattern(fanBySamples(-M_PI, M_PI, 360));
  const auto sensor = pose(Eigen::Vector3d(0.25, 0.5, 0), yaw(0.1));
  for (const bool fast : {true, false}) {
    CastConfig cfg = config(fast);
    cfg.compute_incidence = true;
    Caster caster;
    const ScanResult first = caster.cast(scene, poses, sensor, pattern, cfg);
    EXPECT_FALSE(first.stats.reused);
    const ScanResult& again = caster.cast(scene, poses, sensor, pattern, cfg);
    EXPECT_TRUE(again.stats.reused);
    EXPECT_EQ(again.stats.bodies, 2);
    expectSameResult(first, again);
    // An equal pattern built anew, an equal config copy: still reused.
    const ScanPattern same_pattern(fanBySamples(-M_PI, M_PI, 360));
    const CastConfig same_cfg = cfg;
    EXPECT_TRUE(caster.cast(scene, poses, sensor, same_pattern, same_cfg).stats.reused);

    auto expectRecomputed = [&](const ScanResult& r, const FramePoses& p,
                                const Eigen::Isometry3d& s, const ScanPattern& pat,
                                const CastConfig& c, const char* what) {
      EXPECT_FALSE(r.stats.reused) << what;
      expectMatchesTruth(r, bruteForce(scene, p, s, pat, c), 1e-9, what);
    };
    // Move one frame.
    FramePoses moved = poses;
    moved.pose[arm].translation().y() = 0.5;
    expectRecomputed(caster.cast(scene, moved, sensor, pattern, cfg), moved, sensor, pattern, cfg,
                     "frame moved");
    EXPECT_TRUE(caster.cast(scene, moved, sensor, pattern, cfg).stats.reused);
    // Move the sensor.
    const auto sensor2 = pose(Eigen::Vector3d(0.25, 0.5, 0), yaw(0.2));
    expectRecomputed(caster.cast(scene, moved, sensor2, pattern, cfg), moved, sensor2, pattern, cfg,
                     "sensor moved");
    // Invalidate a frame, then restore it.
    FramePoses invalid = moved;
    invalid.valid[arm] = 0;
    expectRecomputed(caster.cast(scene, invalid, sensor2, pattern, cfg), invalid, sensor2, pattern,
                     cfg, "frame invalid");
    expectRecomputed(caster.cast(scene, moved, sensor2, pattern, cfg), moved, sensor2, pattern, cfg,
                     "frame valid again");
    // Change the config.
    CastConfig shorter = cfg;
    shorter.tmax = 2.0;
    expectRecomputed(caster.cast(scene, moved, sensor2, pattern, shorter), moved, sensor2, pattern,
                     shorter, "config tmax");
    CastConfig culled = shorter;
    culled.cull_backfaces = true;
    expectRecomputed(caster.cast(scene, moved, sensor2, pattern, culled), moved, sensor2, pattern,
                     culled, "config cull");
    CastConfig no_incidence = culled;
    no_incidence.compute_incidence = false;
    EXPECT_FALSE(caster.cast(scene, moved, sensor2, pattern, no_incidence).stats.reused);
    EXPECT_TRUE(caster.cast(scene, moved, sensor2, pattern, no_incidence).cos_incidence.empty());
    // Change the pattern: increment, first angle, count, rings.
    for (const ScanPattern& other :
         {ScanPattern(fanBySamples(-M_PI, M_PI, 361)), ScanPattern(fanBySamples(-3, M_PI, 360)),
          ScanPattern(fanBySamples(-M_PI, 3, 360)),
          ScanPattern(fanBySamples(-M_PI, M_PI, 360), {0.0, 0.1})}) {
      expectRecomputed(caster.cast(scene, moved, sensor2, other, no_incidence), moved, sensor2,
                       other, no_incidence, "pattern");
    }
    // Modify the scene: a new body in front of the sensor appears.
    caster.cast(scene, moved, sensor2, pattern, cfg);
    EXPECT_TRUE(caster.cast(scene, moved, sensor2, pattern, cfg).stats.reused);
    const auto version = scene.version();
    addBody(&scene, Sphere{0.2}, base, pose(Eigen::Vector3d(-2, 0.5, 0)));
    EXPECT_NE(scene.version(), version);
    expectRecomputed(caster.cast(scene, moved, sensor2, pattern, cfg), moved, sensor2, pattern, cfg,
                     "scene modified");
    EXPECT_EQ(caster.cast(scene, moved, sensor2, pattern, cfg).stats.bodies, 3);
    // After a NaN sensor, the same good inputs recompute.
    Eigen::Isometry3d nan_sensor = sensor2;
    nan_sensor.translation().x() = kNan;
    caster.cast(scene, moved, nan_sensor, pattern, cfg);
    expectRecomputed(caster.cast(scene, moved, sensor2, pattern, cfg), moved, sensor2, pattern, cfg,
                     "after NaN");
    // Remove the body again for the other path's loop.
    scene = Scene();
    scene.addLabel("l");
    scene.addFrame("base");
    scene.addFrame("arm");
    addBody(&scene, gridBox(steps(-4, 4, 2), steps(-4, 4, 2), steps(-1, 1, 1), true), base);
    addBody(&scene, Sphere{0.5}, arm, pose(Eigen::Vector3d(2, 0, 0)));
  }
}

// Moving the sensor and every frame together leaves every relative pose unchanged (exactly, with
// dyadic offsets): nothing moved relative to the sensor, so the result is reused.
TEST(Caster, ReuseWhenEverythingMovesTogether) {
  Scene scene = sceneWithFrame();
  addBody(&scene, Sphere{0.5}, 0, pose(Eigen::Vector3d(2, 0, 0)));
  FramePoses poses = FramePoses::identity(scene);
  poses.pose[0] = pose(Eigen::Vector3d(0.5, 0.25, 0));
  auto sensor = pose(Eigen::Vector3d(0.125, 0, 0));
  const ScanPattern pattern(fanBySamples(-1, 1, 21));
  Caster caster;
  const ScanResult first = caster.cast(scene, poses, sensor, pattern, config(true));
  poses.pose[0].pretranslate(Eigen::Vector3d(8, -4, 2));
  sensor.pretranslate(Eigen::Vector3d(8, -4, 2));
  const ScanResult& second = caster.cast(scene, poses, sensor, pattern, config(true));
  EXPECT_TRUE(second.stats.reused);
  expectSameResult(first, second);
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
