// The 2D views and box tests of a kept slice's tree (slice_views.h), each against its exact
// counterpart: every beam whose exact ray enters a child's box lies among the child's columns, no
// point of the box is nearer than its near distance, and PlaneRay enters every such child.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>
#include <vector>

#include "fan_specs.h"
#include "beams/beam_set.h"
#include "slice/kept_slice.h"
#include "slice/slice_views.h"
#include "random.h"

namespace laser_raycast_test {
namespace {

namespace core = laser_raycast::core;
using L = long double;

// Where the exact ray (plane coordinates: from origin along dir) enters the 2D box [lo, hi] within
// [0, tmax], or nothing.
std::optional<L> entry(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi,
                       const Eigen::Matrix<L, 2, 1>& o, const Eigen::Matrix<L, 2, 1>& d, L tmax) {
  L t0 = 0, t1 = tmax;
  for (int k = 0; k < 2; ++k) {
    if (d[k] == 0) {
      if (o[k] < lo[k] || o[k] > hi[k]) return std::nullopt;
      continue;
    }
    L a = (lo[k] - o[k]) / d[k], b = (hi[k] - o[k]) / d[k];
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
  }
  if (t0 > t1) return std::nullopt;
  return t0;
}

// A plane frame for a level sensor at (x, y), turned by yaw, over a frame at the identity.
core::ScanPlane planeAt(double x, double y, double yaw) {
  Eigen::Isometry3d world_from_sensor = Eigen::Isometry3d::Identity();
  world_from_sensor.translation() << x, y, 0.2;
  world_from_sensor.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return core::ScanPlane(world_from_sensor.inverse());
}

TEST(SliceViews, EveryBeamThatEntersAChildBoxIsAmongItsColumns) {
  Rng rng(67);
  long long inside = 0, windows = 0, entered_columns = 0, boxes_seen = 0;
  const core::ScanPattern fans[] = {core::ScanPattern(fanBySamples(-M_PI, M_PI, 360)),
                                    core::ScanPattern(fanBySamples(-2.35, 2.35, 271)),
                                    core::ScanPattern(fanBySamples(0.3, 2.9, 97))};
  for (const core::ScanPattern& fan : fans) {
    core::ScanResult result;
    result.range.assign(fan.size(), std::numeric_limits<double>::infinity());
    result.body.assign(fan.size(), -1);
    result.triangle.assign(fan.size(), -1);
    core::BeamSet beams;
    beams.reset(fan, core::CastConfig{}, &result);
    for (int scene = 0; scene < 6; ++scene) {
      // A slice of random segments (plane coordinates), built as KeptSlice builds its tree.
      std::vector<core::Aabb> boxes;
      for (int i = 0; i < 300; ++i) {
        const Eigen::Vector2d p(uniform(rng, -12, 12), uniform(rng, -12, 12));
        const Eigen::Vector2d q = p + Eigen::Vector2d(uniform(rng, -1, 1), uniform(rng, -1, 1));
        core::Aabb box;
        box.grow(Eigen::Vector3d(p.x(), p.y(), -30));
        box.grow(Eigen::Vector3d(q.x(), q.y(), 30));
        boxes.push_back(box);
      }
      const core::Bvh tree = core::Bvh::buildOverBoxes(boxes);
      const core::WideBvh wide(tree, {});
      const core::ScanPlane plane =
          planeAt(uniform(rng, -6, 6), uniform(rng, -6, 6), uniform(rng, -M_PI, M_PI));
      const double tmax = 25;
      const core::SliceViewBasis frame(plane, tmax, fan);
      // The map's exact inverse: the sensor and the beams in plane coordinates.
      Eigen::Matrix<L, 2, 2> m;
      m << plane.a, plane.b, plane.c, plane.d;
      const Eigen::Matrix<L, 2, 2> inv = m.inverse();
      const Eigen::Matrix<L, 2, 1> origin = -(inv * Eigen::Matrix<L, 2, 1>(plane.tx, plane.ty));
      const core::PlaneRay::Origin ray_origin(origin.cast<double>(), tree.bounds(), 0.0);
      for (const core::WideBvh::Node& node : wide.nodes()) {
        core::SliceViews views;
        views.compute(node, frame);
        for (int k = 0; k < core::WideBvh::kWidth; ++k) {
          if (node.index[k] == core::WideBvh::kEmpty) continue;
          const Eigen::Vector2d lo(node.lo[0][k], node.lo[1][k]), hi(node.hi[0][k], node.hi[1][k]);
          std::vector<char> reached(fan.size(), 0);
          if (views.mask & (1 << k)) {
            auto mark = [&](int first, int last) {
              for (int c = std::max(first, 0); c <= std::min(last, fan.size() - 1); ++c) {
                reached[c] = 1;
              }
            };
            if (views.columns_known & (1 << k)) {
              mark(views.col_lo[k], views.col_hi[k]);
            } else if (!(views.az_half[k] >= 0)) {
              mark(0, fan.size() - 1);
            } else {
              beams.grid().forEachColumnRange(views.az_center[k], views.az_half[k], mark);
            }
          }
          long long entering = 0;
          for (int c = 0; c < fan.size(); ++c) {
            const Eigen::Matrix<L, 2, 1> d =
                inv * Eigen::Matrix<L, 2, 1>(fan.directions()[c].x(), fan.directions()[c].y());
            const auto t = entry(lo, hi, origin, d, tmax);
            if (!t) continue;
            ++inside;
            ++entering;
            ASSERT_TRUE(reached[c])
                << "column " << c << " enters child " << k << " at " << double(*t);
            EXPECT_LE(views.near[k], double(*t) * (1 + 1e-12));
            const core::PlaneRay ray(ray_origin, d.cast<double>());
            alignas(16) float t_entry[4];
            const int entered = ray.enter(node, ray.cullLimit(tmax), t_entry);
            ASSERT_TRUE(entered & (1 << k)) << "column " << c << " child " << k;
          }
          // Tightness, for the boxes clear of the sensor that some beam enters: the columns of
          // the window against those that enter.
          if (entering > 0 && views.near[k] > 1) {
            windows += std::count(reached.begin(), reached.end(), 1);
            entered_columns += entering;
            ++boxes_seen;
          }
        }
      }
    }
  }
  EXPECT_GT(inside, 20000);
  // The corners bound a box's bearings tightly: here the windows hold 1.08 times the columns that
  // enter their boxes; the circle around each box gave 1.65 (and many times a long box seen end
  // on).
  EXPECT_LT(static_cast<double>(windows), 1.2 * static_cast<double>(entered_columns))
      << windows << " window columns, " << entered_columns << " entering, " << boxes_seen
      << " boxes";
}

}  // namespace
}  // namespace laser_raycast_test
