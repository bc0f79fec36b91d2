// libFuzzer harness: numbers -> the core's triangle tests, BVH and caster, with the invariants
// the README promises (docs/testing.md says how to run it):
// - every hit of every triangle method and primitive is finite and within [tmin, tmax];
// - the BVH returns what brute force returns, for every method and precision and every interval
//   (the one exception: a reference method's hit outside its triangle's box, bvh_agreement.h);
// - the watertight method never lets a ray out of a closed mesh, through the BVH and through the
//   caster's planar fan;
// - the caster never crashes, and its ranges are NaN (sensor pose not finite), +Inf, or within
//   [tmin, tmax] with a body.
// The last byte picks the check (FuzzedDataProvider takes integers from the end); the rest are its
// numbers. The seed corpus (corpus/core/seed_<check>) has one input per check.
#include <fuzzer/FuzzedDataProvider.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include "bvh_agreement.h"
#include "laser_raycast/core/bvh.h"
#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/pose.h"
#include "laser_raycast/core/primitives.h"
#include "laser_raycast/core/triangle.h"
#include "triangle_soup.h"

namespace {

using namespace laser_raycast::core;
using Eigen::Vector3d;
using laser_raycast_test::Soup;

constexpr double kInf = std::numeric_limits<double>::infinity();

// A broken invariant: report and abort, which libFuzzer records as a crash with its input.
[[noreturn]] void fail(const char* what, double a = 0, double b = 0) {
  std::fprintf(stderr, "fuzz_core: invariant broken: %s (%.17g, %.17g)\n", what, a, b);
  std::abort();
}

// Numbers that make geometry hard: exact small integers and halves (shared edges, axis-aligned
// faces, rays in box faces), signed zeros, extremes, or any double at all.
double number(FuzzedDataProvider* in) {
  static const double kSpecial[] = {0.0,
                                    -0.0,
                                    1.0,
                                    -1.0,
                                    0.5,
                                    2.0,
                                    3.0,
                                    1e-300,
                                    1e300,
                                    1e-160,
                                    1e154,
                                    5e-324,
                                    1.7976931348623157e308,
                                    kInf,
                                    -kInf,
                                    NAN};
  switch (in->ConsumeIntegralInRange<int>(0, 3)) {
    case 0:
      return kSpecial[in->ConsumeIntegralInRange<std::size_t>(0, std::size(kSpecial) - 1)];
    case 1:
      return 0.5 * in->ConsumeIntegralInRange<int>(-8, 8);
    case 2:
      return in->ConsumeFloatingPointInRange<double>(-10, 10);
    default:
      return in->ConsumeFloatingPoint<double>();
  }
}

double finiteNumber(FuzzedDataProvider* in) {
  const double x = number(in);
  return std::isfinite(x) ? x : 0.0;
}

Vector3d vector(FuzzedDataProvider* in) { return Vector3d(number(in), number(in), number(in)); }
Vector3d finiteVector(FuzzedDataProvider* in) {
  return Vector3d(finiteNumber(in), finiteNumber(in), finiteNumber(in));
}

Ray ray(FuzzedDataProvider* in) {
  Ray r;
  r.origin = vector(in);
  r.dir = vector(in);
  r.tmin = in->ConsumeBool() ? 0.0 : number(in);
  r.tmax = in->ConsumeBool() ? kInf : number(in);
  return r;
}

template <typename T>
void checkHit(const std::optional<TriangleHitT<T>>& hit, const RayT<T>& r, const char* method) {
  if (!hit) return;
  if (!(std::isfinite(hit->t) && std::isfinite(hit->u) && std::isfinite(hit->v))) {
    std::fprintf(stderr, "%s %s: t %.17g u %.17g v %.17g\n", method,
                 sizeof(T) == 4 ? "float" : "double", double(hit->t), double(hit->u),
                 double(hit->v));
    fail("a triangle hit is not finite", hit->t, hit->u);
  }
  if (!(hit->t >= r.tmin && hit->t <= r.tmax)) fail("a triangle hit outside [tmin, tmax]", hit->t);
}

// Every method, both precisions, with and without culling, on one triangle; and the primitives.
void checkSingleTests(FuzzedDataProvider* in) {
  const Vector3d a = vector(in), b = vector(in), c = vector(in);
  const Ray r = ray(in);
  const bool cull = in->ConsumeBool();
  if (std::getenv("FUZZ_CORE_VERBOSE")) {
    std::fprintf(stderr,
                 "triangle (%.17g %.17g %.17g) (%.17g %.17g %.17g) (%.17g %.17g %.17g), ray (%.17g "
                 "%.17g %.17g) + t (%.17g %.17g %.17g), t in [%.17g, %.17g]%s\n",
                 a.x(), a.y(), a.z(), b.x(), b.y(), b.z(), c.x(), c.y(), c.z(), r.origin.x(),
                 r.origin.y(), r.origin.z(), r.dir.x(), r.dir.y(), r.dir.z(), r.tmin, r.tmax,
                 cull ? " cull" : "");
  }
  for (const TriangleMethod method : kAllTriangleMethods) {
    checkHit(intersectTriangle(method, r, a, b, c, cull), r, toString(method));
    const RayF rf = toFloat(r);
    checkHit(intersectTriangle(method, rf, Vec3<float>(a.cast<float>()),
                               Vec3<float>(b.cast<float>()), Vec3<float>(c.cast<float>()), cull),
             rf, toString(method));
  }
  const Vector3d size = a.cwiseAbs();
  const auto checkPrimitive = [&](const std::optional<PrimitiveHit>& hit) {
    if (hit && !(std::isfinite(hit->t) && hit->t >= r.tmin && hit->t <= r.tmax &&
                 hit->normal.allFinite())) {
      fail("a primitive hit is not finite or outside [tmin, tmax]", hit->t);
    }
  };
  if ((size.array() > 0).all() && size.allFinite()) checkPrimitive(intersect(r, Box{size}));
  if (size.x() > 0 && size.y() > 0 && size.allFinite()) {
    checkPrimitive(intersect(r, Cylinder{size.x(), size.y()}));
    checkPrimitive(intersect(r, Sphere{size.x()}));
  }
}

// Triangles whose vertices come from few values, so that edges are shared and faces axis-aligned.
Soup soup(FuzzedDataProvider* in) {
  Soup s;
  const int n = in->ConsumeIntegralInRange<int>(1, 24);
  std::vector<Vector3d> pool;
  for (int i = 0; i < 3 * n; ++i) {
    if (!pool.empty() && in->ConsumeBool()) {
      s.vertices.push_back(pool[in->ConsumeIntegralInRange<std::size_t>(0, pool.size() - 1)]);
    } else {
      pool.push_back(finiteVector(in));
      s.vertices.push_back(pool.back());
    }
  }
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::uint32_t>(3 * i);
    s.triangles.push_back({k, k + 1, k + 2});
  }
  return s;
}

template <typename T, TriangleMethod M>
void compareBvh(const BvhT<T>& bvh, const Soup& s, const RayT<T>& r, bool cull) {
  const auto hit = bvh.template closestHit<M>(r, cull);
  const auto brute = bruteForceClosestHit(M, s.vertices, s.triangles, r, cull);
  if (hit) {
    checkHit(std::optional<TriangleHitT<T>>(TriangleHitT<T>{hit->t, hit->u, hit->v}), r,
             toString(M));
  }
  if (bvh.template anyHit<M>(r, cull) != hit.has_value()) fail("anyHit differs from closestHit");
  const bool exempt =
      M != TriangleMethod::kWatertight && brute && (!hit || hit->t > brute->t) &&
      laser_raycast_test::hitOutsideExactTriangleBox(s, brute->triangle, r, brute->t);
  if (exempt) return;
  if (hit.has_value() != brute.has_value() || (hit && hit->t != brute->t)) {
    std::fprintf(stderr,
                 "%s %s: ray (%.17g %.17g %.17g) + t (%.17g %.17g %.17g), t in [%.17g, %.17g]%s\n",
                 toString(M), sizeof(T) == 4 ? "float" : "double", double(r.origin.x()),
                 double(r.origin.y()), double(r.origin.z()), double(r.dir.x()), double(r.dir.y()),
                 double(r.dir.z()), double(r.tmin), double(r.tmax), cull ? " cull" : "");
    for (const auto& found : {hit, brute}) {
      if (!found) continue;
      const auto& tri = s.triangles[found->triangle];
      std::fprintf(
          stderr,
          "  triangle %u at t %.17g: (%.17g %.17g %.17g) (%.17g %.17g %.17g) (%.17g %.17g %.17g)\n",
          found->triangle, double(found->t), s.vertices[tri[0]].x(), s.vertices[tri[0]].y(),
          s.vertices[tri[0]].z(), s.vertices[tri[1]].x(), s.vertices[tri[1]].y(),
          s.vertices[tri[1]].z(), s.vertices[tri[2]].x(), s.vertices[tri[2]].y(),
          s.vertices[tri[2]].z());
    }
  }
  if (hit.has_value() != brute.has_value()) {
    fail(hit ? "the BVH hits where brute force misses" : "the BVH misses what brute force hits",
         hit ? hit->t : brute->t, static_cast<double>(M));
  }
  if (hit && hit->t != brute->t) fail("the BVH's t differs from brute force", hit->t, brute->t);
}

void checkBvh(FuzzedDataProvider* in) {
  const Soup s = soup(in);
  const Ray r = ray(in);
  const bool cull = in->ConsumeBool();
  const Bvh bvh = Bvh::build(s.vertices, s.triangles);
  const BvhF bvhf = BvhF::build(s.vertices, s.triangles);
  for (const TriangleMethod method : kAllTriangleMethods) {
    dispatchTriangleMethod(method, [&](auto m) {
      compareBvh<double, decltype(m)::value>(bvh, s, r, cull);
      compareBvh<float, decltype(m)::value>(bvhf, s, toFloat(r), cull);
    });
  }
}

// An octahedron with semi-axes in [1, 4], turned and moved, scaled by 2^[-40, 40]: closed, and
// its centre is inside with a margin (its inradius) far above the rounding of its coordinates.
struct ClosedMesh {
  std::vector<Vector3d> vertices;
  std::vector<TriangleIndices> triangles;
  Vector3d center;
  double inradius;
};

ClosedMesh closedMesh(FuzzedDataProvider* in) {
  const double scale = std::ldexp(1.0, in->ConsumeIntegralInRange<int>(-40, 40));
  const Vector3d axes(in->ConsumeFloatingPointInRange<double>(1, 4),
                      in->ConsumeFloatingPointInRange<double>(1, 4),
                      in->ConsumeFloatingPointInRange<double>(1, 4));
  Eigen::Quaterniond q(number(in), number(in), number(in), number(in));
  if (!(q.coeffs().allFinite() && q.norm() > 1e-3 && q.norm() < 1e3)) q.setIdentity();
  const Eigen::Matrix3d rotation = q.normalized().toRotationMatrix();
  ClosedMesh m;
  m.center = scale * Vector3d(in->ConsumeFloatingPointInRange<double>(-1e3, 1e3),
                              in->ConsumeFloatingPointInRange<double>(-1e3, 1e3),
                              in->ConsumeFloatingPointInRange<double>(-1e3, 1e3));
  for (int k = 0; k < 3; ++k) {
    for (const double sign : {1.0, -1.0}) {
      m.vertices.push_back(m.center + rotation.col(k) * (sign * scale * axes[k]));
    }
  }
  // Vertices 0/1: +-x, 2/3: +-y, 4/5: +-z; each face (x, y, z) counter-clockwise seen from outside.
  for (const std::uint32_t x : {0u, 1u}) {
    for (const std::uint32_t y : {2u, 3u}) {
      for (const std::uint32_t z : {4u, 5u}) {
        const bool outward = (x == 0) == (y == 2) ? z == 4 : z == 5;
        m.triangles.push_back(outward ? TriangleIndices{x, y, z} : TriangleIndices{x, z, y});
      }
    }
  }
  m.inradius = scale / std::sqrt(1 / (axes.x() * axes.x()) + 1 / (axes.y() * axes.y()) +
                                 1 / (axes.z() * axes.z()));
  return m;
}

// A point strictly inside: the centre moved by under a quarter of the inradius.
Vector3d insidePoint(const ClosedMesh& m, FuzzedDataProvider* in) {
  Vector3d offset(in->ConsumeFloatingPointInRange<double>(-1, 1),
                  in->ConsumeFloatingPointInRange<double>(-1, 1),
                  in->ConsumeFloatingPointInRange<double>(-1, 1));
  return m.center + offset * (0.25 * m.inradius / std::sqrt(3.0));
}

// Rays from inside the closed mesh, and from outside through a point inside it, must hit it.
void checkWatertight(FuzzedDataProvider* in) {
  const ClosedMesh m = closedMesh(in);
  const Bvh bvh = Bvh::build(m.vertices, m.triangles);
  Ray r;
  const Vector3d target = insidePoint(m, in);
  if (in->ConsumeBool()) {
    r.origin = target;
    r.dir = finiteVector(in);
  } else {
    r.origin = target + finiteVector(in) * (m.inradius * in->ConsumeFloatingPointInRange(1.0, 1e6));
    r.dir = target - r.origin;
  }
  if (!isValidRay(r) || !(r.dir.norm() > 1e-100 * r.origin.norm())) return;
  if (!bvh.closestHit<TriangleMethod::kWatertight>(r)) fail("a ray left a closed mesh (BVH)");
  const auto brute = bruteForceClosestHit(TriangleMethod::kWatertight, m.vertices, m.triangles, r);
  if (!brute) fail("a ray left a closed mesh (every triangle)");
}

// A scene of the closed mesh and up to three fuzzed primitives, each in a frame of its own.
Scene casterScene(const ClosedMesh& m, FuzzedDataProvider* in) {
  Scene scene;
  const int frame = scene.addFrame("f");
  Body mesh_body;
  mesh_body.shape = std::make_shared<const Mesh>(m.vertices, m.triangles);
  mesh_body.frame = frame;
  mesh_body.label = scene.addLabel("mesh");
  scene.addBody(mesh_body);
  const int primitives = in->ConsumeIntegralInRange<int>(0, 3);
  for (int i = 0; i < primitives; ++i) {
    Body body;
    const Vector3d size = finiteVector(in).cwiseAbs();
    const int kind = in->ConsumeIntegralInRange<int>(0, 2);
    body.shape = kind == 0   ? Shape(Box{size})
                 : kind == 1 ? Shape(Cylinder{size.x(), size.y()})
                             : Shape(Sphere{size.z()});
    body.frame = scene.addFrame("p" + std::to_string(i));
    body.frame_from_body.translation() = finiteVector(in);
    try {
      scene.addBody(body);
    } catch (const std::invalid_argument&) {
      // a size that is not positive: refused, as it should be
    }
  }
  return scene;
}

// The caster's ranges: NaN exactly when the sensor pose is not finite; +Inf with no body, and
// never from inside the closed mesh with watertight and both faces; else within [tmin, tmax] with
// a body.
void checkRanges(const ScanResult& result, const Scene& scene, const ScanPattern& pattern,
                 const CastConfig& config, bool inside, bool sensor_ok) {
  if (static_cast<int>(result.range.size()) != pattern.size()) fail("a result of the wrong size");
  for (int i = 0; i < pattern.size(); ++i) {
    const double range = result.range[i];
    if (std::isnan(range) != !sensor_ok) fail("NaN range iff the sensor pose is not finite", range);
    if (std::isnan(range)) continue;
    if (range == kInf) {
      if (result.body[i] != -1) fail("a body on a beam without a hit");
      if (inside && config.method == TriangleMethod::kWatertight && !config.cull_backfaces &&
          sensor_ok) {
        fail("a beam left a closed mesh (caster)", i);
      }
      continue;
    }
    if (!(range >= config.tmin && range <= config.tmax))
      fail("a range outside [tmin, tmax]", range);
    if (result.body[i] < 0 || result.body[i] >= static_cast<int>(scene.bodies().size())) {
      fail("a hit without a valid body", range);
    }
  }
}

// The caster on a scene of the closed mesh and fuzzed primitives.
void checkCaster(FuzzedDataProvider* in) {
  const ClosedMesh m = closedMesh(in);
  const Scene scene = casterScene(m, in);
  FramePoses poses = FramePoses::identity(scene);
  for (std::size_t f = 1; f < poses.pose.size(); ++f) {
    poses.pose[f].translation() = vector(in);
    poses.valid[f] = std::isfinite(poses.pose[f].translation().sum());
  }
  // The sensor inside the closed mesh (all its beams must hit it unless a primitive is nearer),
  // or anywhere, possibly not finite.
  const bool inside = in->ConsumeBool();
  Eigen::Isometry3d sensor = Eigen::Isometry3d::Identity();
  Eigen::Quaterniond q(number(in), number(in), number(in), number(in));
  if (q.coeffs().allFinite() && q.norm() > 1e-3 && q.norm() < 1e3) {
    sensor.linear() = q.normalized().toRotationMatrix();
  }
  sensor.translation() = inside ? insidePoint(m, in) : vector(in);

  FanSpec fan;
  fan.angle_min = in->ConsumeFloatingPointInRange<double>(-M_PI, M_PI);
  fan.angle_max = fan.angle_min + in->ConsumeFloatingPointInRange<double>(1e-9, 2 * M_PI);
  if (in->ConsumeBool()) {
    fan.samples = in->ConsumeIntegralInRange<int>(2, 720);
  } else {
    fan.angle_increment = (fan.angle_max - fan.angle_min) / in->ConsumeIntegralInRange<int>(1, 719);
  }
  CastConfig config;
  config.method = kAllTriangleMethods[in->ConsumeIntegralInRange<std::size_t>(0, 4)];
  config.cull_backfaces = in->ConsumeBool();
  config.planar_fast_path = in->ConsumeBool();
  config.tmin = inside ? 0.0 : in->ConsumeFloatingPointInRange<double>(0, 10);
  config.tmax =
      inside ? 1e6 * m.inradius : config.tmin + in->ConsumeFloatingPointInRange(1e-3, 1e3);
  const bool rings = in->ConsumeBool();
  try {
    fan.validate();
    config.validate();
  } catch (const std::invalid_argument&) {
    return;
  }
  const double elevation = in->ConsumeFloatingPointInRange<double>(-M_PI / 2, M_PI / 2);
  const ScanPattern pattern = rings ? ScanPattern(fan, {elevation, 0.0, 0.5}) : ScanPattern(fan);
  Caster caster;
  const ScanResult& result = caster.cast(scene, poses, sensor, pattern, config);
  checkRanges(result, scene, pattern, config, inside, isValidPose(sensor));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzedDataProvider in(data, size);
  switch (in.ConsumeIntegralInRange<int>(0, 3)) {
    case 0:
      checkSingleTests(&in);
      break;
    case 1:
      checkBvh(&in);
      break;
    case 2:
      checkWatertight(&in);
      break;
    default:
      checkCaster(&in);
      break;
  }
  return 0;
}
