// The conservative pieces of the caster's walk, each against its exact counterpart: a box's view
// (float, four children at once, and double) holds every beam whose exact ray enters the box, and
// no point of the box is nearer than its near distance; the occlusion tiles never call a window
// closed that has an open beam. (The triangles' candidate filters: test_candidate_filters.)
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <set>
#include <vector>

#include "beam_set_cases.h"
#include "fan_specs.h"
#include "laser_raycast/core/aabb.h"
#include "beams/beam_set.h"
#include "beams/column_motion.h"
#include "laser_raycast/core/mesh.h"
#include "beams/node_views.h"
#include "laser_raycast/core/scan_spec.h"
#include "random.h"
#include "triangle_soup.h"

namespace laser_raycast_test {
namespace {

namespace core = laser_raycast::core;
constexpr double kInf = std::numeric_limits<double>::infinity();

// Where the exact ray (sensor frame, from the origin along d) enters the box (body frame, posed by
// sensor_from_body) within [0, tmax], or nothing: the slab test in long double on the box's
// corners moved into the sensor frame... simpler and exact enough: in the body frame, with the
// origin and direction moved there in long double.
std::optional<long double> entry(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                                 const Eigen::Isometry3d& sensor_from_body,
                                 const Eigen::Vector3d& d, double tmax) {
  using L = long double;
  const Eigen::Matrix<L, 3, 3> r = sensor_from_body.linear().cast<L>().transpose();
  const Eigen::Matrix<L, 3, 1> o = -(r * sensor_from_body.translation().cast<L>());
  const Eigen::Matrix<L, 3, 1> dir = r * d.cast<L>();
  L t0 = 0, t1 = tmax;
  for (int k = 0; k < 3; ++k) {
    if (dir[k] == 0) {
      if (o[k] < lo[k] || o[k] > hi[k]) return std::nullopt;
      continue;
    }
    L a = (lo[k] - o[k]) / dir[k], b = (hi[k] - o[k]) / dir[k];
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
  }
  if (t0 > t1) return std::nullopt;
  return t0;
}

// The same for a ray from `origin` (sensor frame) along d.
std::optional<long double> entryFrom(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                                     const Eigen::Isometry3d& sensor_from_body,
                                     const Eigen::Vector3d& origin, const Eigen::Vector3d& d,
                                     double tmax) {
  Eigen::Isometry3d shifted = sensor_from_body;
  shifted.translation() -= origin;  // the box as seen from the ray's origin
  return entry(lo, hi, shifted, d, tmax);
}


// A few beam patterns: fans and rings.
std::vector<core::ScanPattern> patterns() {
  std::vector<core::ScanPattern> out;
  out.emplace_back(fanBySamples(-M_PI, M_PI, 181));
  out.emplace_back(fanBySamples(-2.3, 2.3, 271));
  out.emplace_back(fanBySamples(-M_PI, M_PI, 90), std::vector<double>{-0.4, -0.1, 0.0, 0.2, 0.5});
  return out;
}


// The beam set rebuilds a beam's direction from its row's and column's factors, the pattern's own
// expression: the same bits as the pattern's directions.
TEST(BeamSet, RebuiltDirectionsAreThePatternsBitForBit) {
  for (const core::ScanPattern& pattern : patterns()) {
    FreshBeams fresh(pattern, core::CastConfig{});
    for (int row = 0; row < fresh.beams.grid().rows(); ++row) {
      for (int col = 0; col < fresh.beams.grid().cols(); ++col) {
        ASSERT_EQ(fresh.beams.grid().rebuiltDirection(row, col), fresh.beams.grid().direction(row, col))
            << "row " << row << " col " << col;
      }
    }
  }
}

TEST(NodeViews, EveryBeamThatEntersAChildBoxIsInItsWindow) {
  Rng rng(21);
  long long checked = 0, inside = 0, window_columns = 0, entered_columns = 0;
  for (const core::ScanPattern& pattern : patterns()) {
    FreshBeams fresh(pattern, core::CastConfig{});
    core::BeamSet& beams = fresh.beams;
    for (int scene = 0; scene < 8; ++scene) {
      const Soup s = scene % 2 ? clusteredSoup(rng, 400) : spreadSoup(rng, 400);
      const core::Mesh mesh(s.vertices, s.triangles);
      const core::WideBvh& w = mesh.wideBvh();
      const Eigen::Isometry3d pose = randomPose(rng, 6);
      const core::ViewBasis frame(pose, pattern.planar(), 30.0);
      for (const core::WideBvh::Node& node : w.nodes()) {
        core::NodeViews views;
        views.compute(node, frame);
        for (int k = 0; k < core::WideBvh::kWidth; ++k) {
          if (node.index[k] == core::WideBvh::kEmpty) continue;
          const Eigen::Vector3d lo(node.lo[0][k], node.lo[1][k], node.lo[2][k]);
          const Eigen::Vector3d hi(node.hi[0][k], node.hi[1][k], node.hi[2][k]);
          std::set<int> reached, reached_columns, entering_columns;
          if (views.mask & (1 << k)) {
            beams.grid().forEachChildRect(views, k, beams.grid().all(), [&](const core::BeamRect& r) {
              for (int row = r.row_lo; row <= r.row_hi; ++row) {
                for (int col = r.col_lo; col <= r.col_hi; ++col) {
                  reached.insert(beams.grid().beam(row, col));
                  reached_columns.insert(col);
                }
              }
            });
          }
          for (int row = 0; row < beams.grid().rows(); ++row) {
            for (int col = 0; col < beams.grid().cols(); ++col) {
              const auto t = entry(lo, hi, pose, beams.grid().direction(row, col), 30.0);
              ++checked;
              if (!t) continue;
              ++inside;
              entering_columns.insert(col);
              EXPECT_TRUE(reached.count(beams.grid().beam(row, col)))
                  << "row " << row << " col " << col << " enters child " << k << " at "
                  << double(*t);
              EXPECT_LE(views.near[k], double(*t) * (1 + 1e-12));
            }
          }
          if (HasFailure()) return;
          // Tightness in azimuth, for the boxes clear of the sensor that some beam enters.
          if (!entering_columns.empty() && views.near[k] > 1) {
            window_columns += static_cast<long long>(reached_columns.size());
            entered_columns += static_cast<long long>(entering_columns.size());
          }
        }
      }
    }
  }
  EXPECT_GT(inside, 5000);
  EXPECT_GT(checked, 1000000);
  // The corners bound a box's azimuths: here the windows hold 1.8 times the columns that enter
  // their boxes (small boxes, a column or two each, and a partial column each side); the circle
  // around each box gave 3.0.
  EXPECT_LT(static_cast<double>(window_columns), 2.2 * static_cast<double>(entered_columns))
      << window_columns << " window columns, " << entered_columns << " entered";
}

// Every beam that enters a random box is in its view's window, no nearer than its near distance;
// with `spread`, each column's beams leave from a random pose near the sensor (a sweep block's
// ColumnMotion) and the view is widened by the block's spread.
void expectBoxViewsHoldEveryBeam(Rng& rng, bool spread, int boxes, long long min_inside) {
  long long inside = 0;
  for (const core::ScanPattern& pattern : patterns()) {
    FreshBeams fresh(pattern, core::CastConfig{});
    const core::BeamGrid& grid = fresh.beams.grid();
    for (int i = 0; i < boxes; ++i) {
      const Eigen::Vector3d center = uniformInCube(rng, 8);
      const Eigen::Vector3d half(uniform(rng, 0.01, 3), uniform(rng, 0.01, 3),
                                 uniform(rng, 0.01, 3));
      const Eigen::Isometry3d pose = randomPose(rng, 5);
      const core::ColumnMotion motion =
          spread ? randomColumns(rng, grid.cols(), uniform(rng, 0, 0.3), uniform(rng, 0, 0.1),
                                 core::steepestElevation(pattern))
                 : randomColumns(rng, grid.cols(), 0, 0, 0);
      const Eigen::Matrix3d& r = pose.linear();
      const core::View view =
          core::boxView(center, half, r, r.cwiseAbs(), pose.translation(), pattern.angleMin(),
                        !pattern.planar(), spread ? motion.spread() : core::Spread());
      std::set<int> reached;
      if (!pattern.planar() || view.crosses) {
        grid.forEachRect(view, grid.all(), [&](const core::BeamRect& rect) {
          for (int row = rect.row_lo; row <= rect.row_hi; ++row) {
            for (int col = rect.col_lo; col <= rect.col_hi; ++col) reached.insert(grid.beam(row, col));
          }
        });
      }
      for (int row = 0; row < grid.rows(); ++row) {
        for (int col = 0; col < grid.cols(); ++col) {
          const core::Ray ray = motion.ray(col, grid.direction(row, col), 0.0);
          const auto t = entryFrom(center - half, center + half, pose, ray.origin, ray.dir, kInf);
          if (!t) continue;
          ++inside;
          EXPECT_TRUE(reached.count(grid.beam(row, col))) << "box " << i;
          EXPECT_LE(view.near, double(*t) * (1 + 1e-12));
        }
      }
      if (::testing::Test::HasFailure()) return;
    }
  }
  EXPECT_GT(inside, min_inside);
}

TEST(BoxView, EveryBeamThatEntersTheBoxIsInItsWindow) {
  Rng rng(23);
  expectBoxViewsHoldEveryBeam(rng, false, 400, 10000);
}

TEST(BoxView, WithASpreadEveryColumnsBeamThatEntersTheBoxIsInItsWindow) {
  Rng rng(37);
  expectBoxViewsHoldEveryBeam(rng, true, 400, 8000);
}

// With a sweep block's spread (ColumnMotion): every beam of every column, from the column's own
// pose, that enters a box is in the box's widened window, and no nearer than its near distance;
// the float views of four children and the double view of one box alike.
TEST(NodeViews, WithASpreadEveryColumnsBeamThatEntersAChildBoxIsInItsWindow) {
  Rng rng(31);
  long long inside = 0;
  for (const core::ScanPattern& pattern : patterns()) {
    FreshBeams fresh(pattern, core::CastConfig{});
    const core::BeamGrid& grid = fresh.beams.grid();
    for (int scene = 0; scene < 8; ++scene) {
      const Soup s = scene % 4 < 2 ? clusteredSoup(rng, 200) : spreadSoup(rng, 200);
      const core::Mesh mesh(s.vertices, s.triangles);
      const Eigen::Isometry3d pose = randomPose(rng, 6);
      // Large spreads, and small ones without a turn (where the corners still narrow windows).
      const bool small = scene % 2 == 0;
      const double shift = small ? uniform(rng, 0.02, 0.05) : uniform(rng, 0, 0.3);
      const core::ColumnMotion motion =
          randomColumns(rng, grid.cols(), shift, small ? 0.0 : uniform(rng, 0, 0.1),
                        core::steepestElevation(pattern));
      const core::ViewBasis frame(pose, pattern.planar(), 30.0, motion.spread());
      for (const core::WideBvh::Node& node : mesh.wideBvh().nodes()) {
        core::NodeViews views;
        views.compute(node, frame);
        for (int k = 0; k < core::WideBvh::kWidth; ++k) {
          if (node.index[k] == core::WideBvh::kEmpty) continue;
          const Eigen::Vector3d lo(node.lo[0][k], node.lo[1][k], node.lo[2][k]);
          const Eigen::Vector3d hi(node.hi[0][k], node.hi[1][k], node.hi[2][k]);
          std::set<int> reached;
          if (views.mask & (1 << k)) {
            grid.forEachChildRect(views, k, grid.all(), [&](const core::BeamRect& r) {
              for (int row = r.row_lo; row <= r.row_hi; ++row) {
                for (int col = r.col_lo; col <= r.col_hi; ++col) reached.insert(grid.beam(row, col));
              }
            });
          }
          for (int row = 0; row < grid.rows(); ++row) {
            for (int col = 0; col < grid.cols(); ++col) {
              const core::Ray ray = motion.ray(col, grid.direction(row, col), 0.0);
              const auto t = entryFrom(lo, hi, pose, ray.origin, ray.dir, 30.0);
              if (!t) continue;
              ++inside;
              EXPECT_TRUE(reached.count(grid.beam(row, col)))
                  << "row " << row << " col " << col << " enters child " << k;
              EXPECT_LE(views.near[k], double(*t) * (1 + 1e-12));
            }
          }
          if (HasFailure()) return;
        }
      }
    }
  }
  EXPECT_GT(inside, 5000);
}


TEST(OcclusionTiles, AWindowWithAnOpenBeamIsNeverClosed) {
  Rng rng(31);
  for (const int rows : {1, 5, 17}) {
    const int cols = 300;
    std::vector<float> range(rows * cols, 10.0f);
    core::OcclusionTiles tiles;
    tiles.reset(rows, cols, 10.0f);
    long long closed = 0, narrow = 0;
    for (int step = 0; step < 20000; ++step) {
      // Ranges only decrease, as in a cast.
      const int row = static_cast<int>(uniform(rng, 0, rows)),
                col = static_cast<int>(uniform(rng, 0, cols));
      float& x = range[static_cast<std::size_t>(row) * cols + col];
      x = std::min(x, static_cast<float>(uniform(rng, 0, 10)));
      tiles.lower(row, col, x);
      core::BeamRect rect;
      rect.row_lo = static_cast<int>(uniform(rng, 0, rows));
      rect.row_hi = std::min(rows - 1, rect.row_lo + static_cast<int>(uniform(rng, 0, rows)));
      rect.col_lo = static_cast<int>(uniform(rng, 0, cols));
      rect.col_hi = std::min(cols - 1, rect.col_lo + static_cast<int>(logUniform(rng, 0, 2.5)));
      const float near = static_cast<float>(uniform(rng, 0, 10));
      bool open = false;
      for (int r = rect.row_lo; r <= rect.row_hi; ++r) {
        for (int c = rect.col_lo; c <= rect.col_hi; ++c) {
          open |= !(range[static_cast<std::size_t>(r) * cols + c] < near);
        }
      }
      const bool said = tiles.anyOpen(rect, near);
      if (open) {
        ASSERT_TRUE(said) << "step " << step;
      }
      // A narrow window of one row is read beam by beam: the answer is exact.
      if (rect.row_lo == rect.row_hi && rect.col_hi - rect.col_lo < 16) {
        ASSERT_EQ(said, open) << "step " << step;
        ++narrow;
      }
      closed += !said;
    }
    EXPECT_GT(closed, 100);
    EXPECT_GT(narrow, 1000);
  }
}

// The same for the beam set's own test, which reads small windows beam by beam (four at a time, in
// float) and larger ones through its tiles; and it does close windows.
TEST(BeamSet, AWindowWithAnOpenBeamIsNeverClosed) {
  Rng rng(47);
  const core::ScanPattern pattern(fanBySamples(-M_PI, M_PI, 301),
                                  std::vector<double>{0.3, -0.2, 0.1, -0.4, 0.0, 0.2, -0.1});
  FreshBeams fresh(pattern, core::CastConfig{});
  core::BeamSet& beams = fresh.beams;
  long long closed = 0;
  for (int step = 0; step < 20000; ++step) {
    const int row = static_cast<int>(uniform(rng, 0, beams.grid().rows())),
              col = static_cast<int>(uniform(rng, 0, beams.grid().cols()));
    beams.keepNearestHit(row, col, std::min(beams.range(row, col), uniform(rng, 0, 10)), 0, 0,
                [] { return Eigen::Vector3d(); });
    core::BeamRect rect;
    rect.row_lo = static_cast<int>(uniform(rng, 0, beams.grid().rows()));
    rect.row_hi = std::min(beams.grid().rows() - 1, rect.row_lo + static_cast<int>(uniform(rng, 0, 3)));
    rect.col_lo = static_cast<int>(uniform(rng, 0, beams.grid().cols()));
    rect.col_hi =
        std::min(beams.grid().cols() - 1, rect.col_lo + static_cast<int>(logUniform(rng, 0, 2.5)));
    const double near = uniform(rng, 0, 10);
    bool open = false;
    for (int r = rect.row_lo; r <= rect.row_hi; ++r) {
      for (int c = rect.col_lo; c <= rect.col_hi; ++c) open |= !(beams.range(r, c) < near);
    }
    const bool said = beams.anyOpen(rect, near);
    if (open) {
      ASSERT_TRUE(said) << "step " << step;
    }
    closed += !said;
  }
  EXPECT_GT(closed, 1000);
}

}  // namespace
}  // namespace laser_raycast_test
