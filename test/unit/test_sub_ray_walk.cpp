// The parts a bundle's sub-rays are walked with (walk/sub_ray_walk.h), against the tests they stand
// for: two watertight tests side by side (intersectPairFromOrigin) against the scalar test, bit for
// bit, on random triangles and on rays through vertices, along edges and beyond a double's range;
// and the bundle's box test (WideBundleRay) against each of its rays' own (WideBoxRay): every
// child a ray enters, the bundle enters no later. (The whole walk against each sub-ray's own cast
// is test_caster_bundle's.)
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <vector>

#include "accel/wide_bundle_ray.h"
#include "accel/wide_bvh.h"
#include "random.h"
#include "walk/sub_ray_pair.h"

namespace laser_raycast_test {
namespace {

namespace core = laser_raycast::core;
using core::WatertightRay;

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// A direction within `angle` of d (not normalised back: a sub-ray's may not be exactly unit).
Eigen::Vector3d near(Rng& rng, const Eigen::Vector3d& d, double angle) {
  return (d + angle * uniform(rng, 0, 1) * randomUnitVector(rng)).normalized();
}

// One case of the pair test: both rays' results against the scalar test's.
void expectPairIsScalar(const Eigen::Vector3d& d0, const Eigen::Vector3d& d1,
                        const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                        const Eigen::Vector3d& c, double tmin, bool cull, const double tmax[2],
                        long long* hits) {
  const WatertightRay::Shear s0 = WatertightRay::shearOf(d0), s1 = WatertightRay::shearOf(d1);
  if (s0.kx != s1.kx || s0.ky != s1.ky || s0.kz != s1.kz) return;  // not a pair
  double t[2];
  const int mask = core::intersectPairFromOrigin(s0, s1, a, b, c, tmin, cull, tmax, t);
  for (int k = 0; k < 2; ++k) {
    const auto hit = core::intersectFromOrigin(k == 0 ? s0 : s1, a, b, c, tmin, cull, tmax[k]);
    ASSERT_EQ(bool(mask & (1 << k)), hit.has_value()) << "lane " << k;
    if (hit) {
      ++*hits;
      ASSERT_TRUE(sameBits(t[k], hit->t)) << "lane " << k << ": " << t[k] << " vs " << hit->t;
    }
  }
}

TEST(SubRayPair, EachLaneIsTheScalarTestBitForBit) {
  Rng rng(2718);
  long long pairs = 0, hits = 0;
  for (int trial = 0; trial < 200000; ++trial) {
    // A triangle somewhere in front, and two rays aimed near a point of it (inside or beyond an
    // edge), from a fraction of a milliradian to a few degrees apart.
    const double scale = logUniform(rng, -3, 3);
    const Eigen::Vector3d centre = scale * randomUnitVector(rng);
    const Eigen::Vector3d a = centre + 0.3 * scale * randomUnitVector(rng);
    const Eigen::Vector3d b = centre + 0.3 * scale * randomUnitVector(rng);
    const Eigen::Vector3d c = centre + 0.3 * scale * randomUnitVector(rng);
    const double u = uniform(rng, -0.2, 1.2), v = uniform(rng, -0.2, 1.2 - u);
    const Eigen::Vector3d aim = (a + u * (b - a) + v * (c - a)).normalized();
    const double spread = logUniform(rng, -5, -1);
    const double tmin = trial % 3 == 0 ? 0.0 : 0.01 * scale;
    const double tmax[2] = {trial % 4 == 0 ? 1.2 * scale : std::numeric_limits<double>::infinity(),
                            trial % 5 == 0 ? 0.9 * scale : 2 * scale};
    expectPairIsScalar(near(rng, aim, spread), near(rng, aim, spread), a, b, c, tmin, trial % 2,
                       tmax, &hits);
    ++pairs;
  }
  EXPECT_GT(hits, pairs / 4);
}

// Rays exactly through a vertex or along a shared edge of a grid of triangles (where the scalar
// test takes the exact sign and the ownership rule), and triangles too far or too small for the
// products to stay in a double's range (where it rescales): each lane the scalar test's answer.
TEST(SubRayPair, BoundaryAndRangeCasesFollowTheScalarTest) {
  Rng rng(31415);
  long long hits = 0;
  const double inf = std::numeric_limits<double>::infinity();
  const double tmax[2] = {inf, inf};
  for (int trial = 0; trial < 20000; ++trial) {
    // A unit square split along its diagonal, at x = depth, its corners on integer y, z: a ray
    // aimed at a corner or along the diagonal meets the boundary exactly.
    const double depth = trial % 7 + 1;
    const Eigen::Vector3d p00(depth, 0, 0), p10(depth, 1, 0), p01(depth, 0, 1), p11(depth, 1, 1);
    const Eigen::Vector3d corner = trial % 2 ? p00 : p11;
    const Eigen::Vector3d on_diagonal = p10 + uniform(rng, 0, 1) * (p01 - p10);
    const Eigen::Vector3d d0 = corner.normalized(), d1 = on_diagonal.normalized();
    for (const bool cull : {false, true}) {
      expectPairIsScalar(d0, d1, p00, p10, p11, 0, cull, tmax, &hits);
      expectPairIsScalar(d0, d1, p00, p11, p01, 0, cull, tmax, &hits);
      expectPairIsScalar(d1, d0, p10, p01, p11, 0, cull, tmax, &hits);
    }
    // Far beyond and far within a double's range.
    const double huge = std::ldexp(1.0, 500 + trial % 400), tiny = std::ldexp(1.0, -900);
    for (const double s : {huge, tiny}) {
      const Eigen::Vector3d aim = randomUnitVector(rng);
      Eigen::Vector3d e1 = aim.unitOrthogonal(), e2 = aim.cross(e1);
      expectPairIsScalar(near(rng, aim, 1e-4), near(rng, aim, 1e-4), s * (aim - 0.1 * e1),
                         s * (aim + 0.1 * e1 - 0.1 * e2), s * (aim + 0.1 * e2), 0, false, tmax,
                         &hits);
    }
  }
  EXPECT_GT(hits, 1000);
}

// A node of four children: random boxes around the ray's way, some empty.
core::WideBvh::Node randomNode(Rng& rng, const Eigen::Vector3d& origin, const Eigen::Vector3d& d) {
  core::WideBvh::Node node{};
  for (int k = 0; k < core::WideBvh::kWidth; ++k) {
    const bool empty = uniform(rng, 0, 1) < 0.1;
    node.index[k] = empty ? core::WideBvh::kEmpty : static_cast<std::uint32_t>(k);
    node.count[k] = empty ? 0 : 1;
    const Eigen::Vector3d centre =
        origin + uniform(rng, -2, 30) * d + logUniform(rng, -3, 0.5) * randomUnitVector(rng);
    for (int a = 0; a < 3; ++a) {
      const double half = logUniform(rng, -3, 0.5);
      node.lo[a][k] =
          empty ? std::numeric_limits<float>::infinity() : core::floatBelow(centre[a] - half);
      node.hi[a][k] =
          empty ? -std::numeric_limits<float>::infinity() : core::floatAbove(centre[a] + half);
    }
  }
  return node;
}

TEST(WideBundleRay, EntersEveryChildASubRayEntersNoLater) {
  Rng rng(1618);
  long long entered = 0, checked = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const Eigen::Vector3d origin = uniformInCube(rng, 20);
    Eigen::Vector3d axis = randomUnitVector(rng);
    // Axes with a component near 0 or exactly 0 (level beams, beams along an axis).
    if (trial % 4 == 1) axis.z() = uniform(rng, -1e-3, 1e-3);
    if (trial % 4 == 2) axis.y() = 0;
    axis.normalize();
    const double spread = logUniform(rng, -4.5, -2);
    std::vector<Eigen::Vector3d> dirs;
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d hi = -lo;
    for (int s = 0; s < 7; ++s) {
      dirs.push_back(s == 0 ? axis : near(rng, axis, spread));
      lo = lo.cwiseMin(dirs.back());
      hi = hi.cwiseMax(dirs.back());
    }
    core::Aabb bounds;
    bounds.lo = origin - Eigen::Vector3d::Constant(60);
    bounds.hi = origin + Eigen::Vector3d::Constant(60);
    const core::WideBoxRay::Origin from(origin, bounds, 0.0);
    const core::WideBundleRay bundle(from, lo, hi);
    const core::WideBvh::Node node = randomNode(rng, origin, axis);
    const double tmax = uniform(rng, 1, 40);
    float bundle_t[4];
    const int bundle_mask = bundle.enter(node, bundle.cullLimit(tmax), bundle_t);
    for (const Eigen::Vector3d& d : dirs) {
      const core::WideBoxRay ray(from, d);
      float t[4];
      const int mask = ray.enter(node, ray.cullLimit(tmax), t);
      for (int k = 0; k < 4; ++k) {
        if (!(mask & (1 << k))) continue;
        ++entered;
        ASSERT_TRUE(bundle_mask & (1 << k)) << "trial " << trial << " child " << k;
        ASSERT_LE(bundle_t[k], t[k]) << "trial " << trial << " child " << k;
      }
      ++checked;
    }
  }
  EXPECT_GT(entered, checked / 10);
}

}  // namespace
}  // namespace laser_raycast_test
