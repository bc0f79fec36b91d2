// Stress case 3: grazing rays, meeting a triangle's plane at theta = 10^-k rad (k = 1..7).
//
// The analytic bound. Let S be the largest distance from the ray origin to a vertex, L the longest
// edge, A the area, u the unit roundoff. The watertight test works relative to the origin in a
// sheared frame where the ray is the +z axis: x' = p_x - (d_x / d_z) p_z with p = v - o, so each
// sheared coordinate carries an error of at most ~8 u S (the subtraction v - o, the shear factor,
// the product and the difference; |d_x / d_z| <= 1). The ray passes through the triangle, so the
// sheared vertices lie within ~2.5 L of the axis (the oblique projection stretches by at most
// 1 + sqrt 2), and each edge function e_i = x'_j y'_k - y'_j x'_k (twice a projected sub-area) is
// off by at most 4 * 8uS * 2.5L + 2u * 2 * (2.5L)^2 <= 130 u S L. Their sum, det, is twice the
// projected area, 2 A sin(theta) / |d_z| >= 2 A sin(theta): grazing shrinks it, not the errors. So
// the barycentric weights e_i / det are off by sum |d lambda_i| <= 390 u S L / (A sin theta), and
// t = sum lambda_i z_i with |z_i - z_j| <= sqrt(3) L (z = p_z / d_z, |d_z| >= 1/sqrt 3) by
//
//   |dt| <= 700 u S (L^2 / A) / sin(theta) + 10 u S
//
// (the last term: rounding of the weighted sum and of its z_i). In words: c u S / sin(theta), with
// c ~ 700 times the triangle's shape factor L^2 / A (2.3 for an equilateral triangle). Geometric
// reading: a relative error u in the data moves the plane by ~u S; a plane moved by h along its
// normal moves the hit by h / sin(theta) along the ray. The measured error is reported in units of
// u S / sin(theta); it is a few units, far inside the bound. The same bound (with their own u) is
// applied to the float variants' figures, which exceed it.
//
// The reference is long double arithmetic on the rounded inputs (the exact answer for the data as
// given), so it measures the method's error, not the input rounding. At theta = 1e-7, long double
// adds ~2^-64 S / theta, four orders below the double bound.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "laser_raycast/core/bvh.h"
#include "random.h"
#include "stress_report.h"

namespace laser_raycast_test {
namespace {

using L = long double;
using Vec3L = Eigen::Matrix<L, 3, 1>;
using Eigen::Vector3d;

constexpr int kMaxK = 7;
constexpr double kMargin = 0.05;  // barycentric margin of a "clearly" inside or outside target
constexpr double kTmax = 4.0;     // finite, so that "beyond tmax" is checkable (t0 <= 2)

// The analytic bound above, for the rounded inputs of one precision.
double grazingBound(double u, L s, L longest_edge, L area, L sin_theta) {
  return double(700 * u * s * (longest_edge * longest_edge / area) / sin_theta + 10 * u * s);
}

struct GrazingTally {
  long rays = 0, wrong = 0, impossible = 0, beyond_bound = 0;
  double worst = 0;  // max |t - t_ref| sin(theta) / (u S)
  double bound_min = std::numeric_limits<double>::infinity(), bound_max = 0;  // same units
};

// What long double says about a ray and a triangle given in precision T.
struct Truth {
  L t, u, v, sin_theta, s, longest_edge, area;
  L minBary() const { return std::min({1 - u - v, u, v}); }
};

template <typename T>
Truth truthOf(const core::RayT<T>& ray, const core::Vec3<T>& a_t, const core::Vec3<T>& b_t,
              const core::Vec3<T>& c_t) {
  const Vec3L a = a_t.template cast<L>(), b = b_t.template cast<L>(), c = c_t.template cast<L>();
  const Vec3L o = ray.origin.template cast<L>(), d = ray.dir.template cast<L>();
  const Vec3L n = (b - a).cross(c - a);
  Truth r;
  r.t = n.dot(a - o) / n.dot(d);
  const Vec3L p = o + r.t * d;
  const L n2 = n.squaredNorm();
  r.u = (p - a).cross(c - a).dot(n) / n2;
  r.v = (b - a).cross(p - a).dot(n) / n2;
  r.sin_theta = std::abs(n.dot(d)) / (std::sqrt(n2) * d.norm());
  r.s = std::max({(a - o).norm(), (b - o).norm(), (c - o).norm()});
  r.longest_edge = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
  r.area = std::sqrt(n2) / 2;
  return r;
}

// Scores one method result against the truth: the decision where it is clear, impossible values
// always, and the error against the bound for every hit on a ray the truth does not call clearly
// outside.
template <typename T>
void score(const std::optional<core::TriangleHitT<T>>& hit, const Truth& truth,
           GrazingTally* tally) {
  const double u = unitRoundoff<T>();
  const bool clearly_inside =
      truth.minBary() >= kMargin && truth.t >= 0.1 && truth.t <= kTmax / 1.1;
  const bool clearly_outside =
      truth.minBary() <= -kMargin || truth.t < -0.1 || truth.t > kTmax * 1.1;
  ++tally->rays;
  if (!hit) {
    tally->wrong += clearly_inside;
    return;
  }
  if (!(std::isfinite(hit->t) && std::isfinite(hit->u) && std::isfinite(hit->v) && hit->t >= 0 &&
        hit->t <= T(kTmax))) {
    ++tally->impossible;
    return;
  }
  if (clearly_outside) {
    ++tally->wrong;
    return;
  }
  const double error = double(std::abs(L(hit->t) - truth.t));
  const double unit = double(u * truth.s / truth.sin_theta);
  const double bound = grazingBound(u, truth.s, truth.longest_edge, truth.area, truth.sin_theta);
  tally->worst = std::max(tally->worst, error / unit);
  tally->bound_min = std::min(tally->bound_min, bound / unit);
  tally->bound_max = std::max(tally->bound_max, bound / unit);
  if (error > bound) {
    ++tally->beyond_bound;
  }
}

// A grazing ray in long double: a direction at angle theta to the triangle's plane (from above or
// below), aimed at a target point; the origin t0 in [0.5, 2] before it.
struct GrazingGeometry {
  Vec3L a, b, c, origin, dir;
};

// A well-shaped triangle (vertices on a circle of radius 0.6..1, 1.5..2.5 rad apart) in the plane
// z = 0 of a random frame, and a ray at theta to it aimed at barycentrics (u, v).
GrazingGeometry grazing(Rng& rng, const Eigen::Isometry3d& frame, double theta,
                        const Eigen::Vector2d& target_uv) {
  const Eigen::Matrix<L, 3, 3> r = frame.linear().cast<L>();
  const Vec3L shift = frame.translation().cast<L>();
  Vec3L local[3];
  L angle = uniform(rng, 0, 2 * M_PI);
  for (auto& p : local) {
    const L radius = uniform(rng, 0.6, 1.0);
    p = Vec3L(radius * std::cos(angle), radius * std::sin(angle), 0);
    angle += uniform(rng, 1.5, 2.5);
  }
  const Vec3L target = (1 - target_uv.x() - target_uv.y()) * local[0] + target_uv.x() * local[1] +
                       target_uv.y() * local[2];
  const L phi = uniform(rng, 0, 2 * M_PI);
  const L side = uniform(rng, 0, 1) < 0.5 ? -1 : 1;
  const Vec3L d(std::cos(L(theta)) * std::cos(phi), std::cos(L(theta)) * std::sin(phi),
                side * std::sin(L(theta)));
  const Vec3L o = target - L(uniform(rng, 0.5, 2.0)) * d;
  return {r * local[0] + shift, r * local[1] + shift, r * local[2] + shift, r * o + shift, r * d};
}

// Barycentrics clearly inside (every weight >= 0.1) or clearly outside (one weight in
// [-0.5, -0.1]).
Eigen::Vector2d targetBarycentrics(Rng& rng, bool inside) {
  if (inside) {
    for (;;) {
      const Eigen::Vector2d uv = randomBarycentrics(rng);
      if (std::min({1 - uv.x() - uv.y(), uv.x(), uv.y()}) >= 0.1) return uv;
    }
  }
  const double negative = uniform(rng, -0.5, -0.1), other = uniform(rng, 0.2, 0.8);
  switch (std::uniform_int_distribution<int>(0, 2)(rng)) {
    case 0:
      return Eigen::Vector2d(negative, other);
    case 1:
      return Eigen::Vector2d(other, negative);
    default:
      return Eigen::Vector2d(other, 1 - other - negative);  // the weight of a is negative
  }
}

template <typename T>
core::Vec3<T> round(const Vec3L& p) {
  return p.cast<T>();
}

std::string kHeader(int k) { return "10^-" + std::to_string(k) + " rad"; }

TEST(StressGrazing, SingleTrianglesDecideAndBoundT) {
  Rng rng(3001);
  std::vector<std::vector<GrazingTally>> tallies(variants().size(),
                                                 std::vector<GrazingTally>(kMaxK + 1));
  for (int k = 1; k <= kMaxK; ++k) {
    const double theta = std::pow(10.0, -k);
    for (int trial = 0; trial < 1000; ++trial) {
      const Eigen::Isometry3d frame = randomPose(rng, 2.0);
      const GrazingGeometry g = grazing(rng, frame, theta, targetBarycentrics(rng, trial % 2 == 0));
      for (std::size_t vi = 0; vi < variants().size(); ++vi) {
        dispatchVariant(variants()[vi], [&](auto m, auto x) {
          using T = decltype(x);
          const core::Vec3<T> a = round<T>(g.a), b = round<T>(g.b), c = round<T>(g.c);
          core::RayT<T> ray;
          ray.origin = round<T>(g.origin);
          ray.dir = round<T>(g.dir);
          ray.tmax = T(kTmax);
          score(core::intersectTriangle<decltype(m)::value>(ray, a, b, c), truthOf(ray, a, b, c),
                &tallies[vi][k]);
        });
      }
    }
  }
  std::vector<std::string> header = {"method"};
  for (int k = 1; k <= kMaxK; ++k) header.push_back(kHeader(k));
  Table decisions{"3a",
                  "3a. Grazing rays at 10^-k rad: wrong hit/miss decisions (impossible t)",
                  "1,000 random well-shaped triangles (random pose) per angle, half the rays "
                  "aimed at least 0.1 inside in barycentrics, half at least 0.1 outside; truth in "
                  "long double from the rounded inputs. A decision counts where the truth is "
                  "clear by 0.05 in barycentrics; an impossible t is negative, beyond tmax, or "
                  "non-finite (or u, v non-finite). Asserted on production: 0 wrong, 0 impossible.",
                  header,
                  {}};
  double bound_min = std::numeric_limits<double>::infinity(), bound_max = 0;
  for (int k = 1; k <= kMaxK; ++k) {
    bound_min = std::min(bound_min, tallies[0][k].bound_min);
    bound_max = std::max(bound_max, tallies[0][k].bound_max);
  }
  Table errors{"3b",
               "3b. Grazing rays at 10^-k rad: worst |dt| in units of u S / sin(theta)",
               "The same rays. S: farthest vertex from the origin, u: the precision's unit "
               "roundoff. The analytic bound (derivation in test/stress/test_stress_grazing.cpp) "
               "is 700 (L^2/A) u S / sin(theta) + 10 u S, " +
                   fixed(bound_min, 0) + " to " + fixed(bound_max, 0) +
                   " units for these triangles. Asserted on production: every hit within the "
                   "bound. In brackets: hits beyond it.",
               header,
               {}};
  for (std::size_t vi = 0; vi < variants().size(); ++vi) {
    std::vector<std::string> d_row = {variantName(variants()[vi])}, e_row = d_row;
    for (int k = 1; k <= kMaxK; ++k) {
      const GrazingTally& t = tallies[vi][k];
      d_row.push_back(count(t.wrong) + (t.impossible ? " (" + count(t.impossible) + ")" : ""));
      e_row.push_back(fixed(t.worst, 2) +
                      (t.beyond_bound ? " [" + count(t.beyond_bound) + "]" : ""));
    }
    decisions.addRow(d_row);
    errors.addRow(e_row);
  }
  record(decisions);
  record(errors);
  ASSERT_TRUE(isProduction(variants()[0]));
  for (int k = 1; k <= kMaxK; ++k) {
    const GrazingTally& p = tallies[0][k];
    EXPECT_EQ(p.rays, 1000) << k;
    EXPECT_EQ(p.wrong, 0) << "theta 1e-" << k;
    EXPECT_EQ(p.impossible, 0) << "theta 1e-" << k;
    EXPECT_EQ(p.beyond_bound, 0) << "theta 1e-" << k;
  }
}

// Through the BVH: a 16 x 16 grid floor (512 triangles, shape factor L^2/A = 4), axis-aligned (the
// BVH's boxes are flat, and the ray nearly lies in their faces) and in a random pose. The grazing
// ray is aimed at least 0.05 inside a triangle of the floor, so it must hit that triangle.
TEST(StressGrazing, BvhFloorHitsWithBoundedT) {
  Rng rng(3101);
  const int cells = 16;
  TriMesh floor;
  for (int i = 0; i <= cells; ++i) {
    for (int j = 0; j <= cells; ++j) {
      floor.vertices.emplace_back(-1 + 2.0 * i / cells, -1 + 2.0 * j / cells, 0);
    }
  }
  for (int i = 0; i < cells; ++i) {
    for (int j = 0; j < cells; ++j) {
      const auto at = [&](int di, int dj) {
        return static_cast<std::uint32_t>((i + di) * (cells + 1) + j + dj);
      };
      floor.triangles.push_back({at(0, 0), at(1, 0), at(1, 1)});
      floor.triangles.push_back({at(0, 0), at(1, 1), at(0, 1)});
    }
  }
  const std::vector<Eigen::Isometry3d> poses = {Eigen::Isometry3d::Identity(),
                                                randomPose(rng, 3.0)};
  std::vector<std::vector<GrazingTally>> tallies(variants().size(),
                                                 std::vector<GrazingTally>(kMaxK + 1));
  for (const Eigen::Isometry3d& pose : poses) {
    const TriMesh mesh = transformed(floor, 1.0, pose);
    const core::Bvh bvh = core::Bvh::build(mesh.vertices, mesh.triangles);
    const core::BvhF bvh_f = core::BvhF::build(mesh.vertices, mesh.triangles);
    for (int k = 1; k <= kMaxK; ++k) {
      const double theta = std::pow(10.0, -k);
      for (int trial = 0; trial < 300; ++trial) {
        // Exact local geometry: the target in a random triangle, the ray at theta to z = 0.
        const auto tri_index = std::uniform_int_distribution<std::uint32_t>(
            0, static_cast<std::uint32_t>(floor.triangles.size() - 1))(rng);
        const auto& tri = floor.triangles[tri_index];
        Eigen::Vector2d uv;
        do {
          uv = randomBarycentrics(rng);
        } while (std::min({1 - uv.x() - uv.y(), uv.x(), uv.y()}) < kMargin);
        const Vec3L target = (1 - uv.x() - uv.y()) * floor.vertices[tri[0]].cast<L>() +
                             uv.x() * floor.vertices[tri[1]].cast<L>() +
                             uv.y() * floor.vertices[tri[2]].cast<L>();
        const L phi = uniform(rng, 0, 2 * M_PI);
        const Vec3L d(std::cos(L(theta)) * std::cos(phi), std::cos(L(theta)) * std::sin(phi),
                      std::sin(L(theta)));  // from below: origin under the floor
        const Vec3L o = target - L(uniform(rng, 0.5, 2.0)) * d;
        const Eigen::Matrix<L, 3, 3> r = pose.linear().cast<L>();
        const Vec3L shift = pose.translation().cast<L>();
        for (std::size_t vi = 0; vi < variants().size(); ++vi) {
          dispatchVariant(variants()[vi], [&](auto m, auto x) {
            using T = decltype(x);
            core::RayT<T> ray;
            ray.origin = round<T>(r * o + shift);
            ray.dir = round<T>(r * d);
            ray.tmax = T(kTmax);
            const core::Vec3<T> a = mesh.vertices[tri[0]].cast<T>(),
                                b = mesh.vertices[tri[1]].cast<T>(),
                                c = mesh.vertices[tri[2]].cast<T>();
            const auto hit = pick(bvh, bvh_f, T{}).template closestHit<decltype(m)::value>(ray);
            // Another triangle than the target one is a wrong decision (a miss of the target).
            if (hit && hit->triangle != tri_index) {
              ++tallies[vi][k].rays;
              ++tallies[vi][k].wrong;
              return;
            }
            std::optional<core::TriangleHitT<T>> as_triangle;
            if (hit) as_triangle = core::TriangleHitT<T>{hit->t, hit->u, hit->v};
            score(as_triangle, truthOf(ray, a, b, c), &tallies[vi][k]);
          });
        }
      }
    }
  }
  std::vector<std::string> header = {"method"};
  for (int k = 1; k <= kMaxK; ++k) header.push_back(kHeader(k));
  Table t{"3c",
          "3c. Grazing rays through the BVH: wrong triangle or miss / worst |dt| in u S / "
          "sin(theta)",
          "A 16 x 16 grid floor, axis-aligned and in a random pose, 300 rays per pose and angle "
          "aimed at least 0.05 inside one triangle (float variants: a float BVH). Asserted on "
          "production: the target triangle hit every time, t within the bound of 3b.",
          header,
          {}};
  for (std::size_t vi = 0; vi < variants().size(); ++vi) {
    std::vector<std::string> row = {variantName(variants()[vi])};
    for (int k = 1; k <= kMaxK; ++k) {
      const GrazingTally& g = tallies[vi][k];
      row.push_back(count(g.wrong + g.impossible) + " / " + fixed(g.worst, 2) +
                    (g.beyond_bound ? " [" + count(g.beyond_bound) + "]" : ""));
    }
    t.addRow(row);
  }
  record(t);
  for (int k = 1; k <= kMaxK; ++k) {
    const GrazingTally& p = tallies[0][k];
    EXPECT_EQ(p.wrong, 0) << "theta 1e-" << k;
    EXPECT_EQ(p.impossible, 0) << "theta 1e-" << k;
    EXPECT_EQ(p.beyond_bound, 0) << "theta 1e-" << k;
  }
}

}  // namespace
}  // namespace laser_raycast_test
