// The candidate filters of the caster's walk, each against the exact triangle test: the edge
// filter and the column raster (from one pose, and for a sweep block whose columns leave from
// poses of their own) let through every beam whose exact hit could be kept, and a rect of the
// grid gets exactly the whole grid's candidates inside it; the pre-test of a bundle's sub-rays,
// in float four at a time, lets through every sub-ray that hits and every one its double form
// lets through.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <vector>

#include "beam_set_cases.h"
#include "beams/beam_set.h"
#include "beams/column_motion.h"
#include "beams/column_raster.h"
#include "beams/edge_filter.h"
#include "fan_specs.h"
#include "laser_raycast/core/triangle.h"
#include "random.h"
#include "walk/sub_ray_filter.h"

namespace laser_raycast_test {
namespace {

namespace core = laser_raycast::core;

// Random triangles near the sensor and far, large and tiny, some through the sensor's axis; each
// beam given a random current range (a third of them none): the beams whose exact hit could be
// kept, t <= range and t <= tmax.
struct FilterCase {
  Eigen::Vector3d a, b, c;
};

FilterCase randomTriangle(Rng& rng) {
  const double scale = std::pow(10.0, uniform(rng, -1, 1.5));
  const Eigen::Vector3d c = scale * randomUnitVector(rng);
  const double size = scale * uniform(rng, 0.001, 1.5);
  return FilterCase{c + size * randomUnitVector(rng), c + size * randomUnitVector(rng),
                    c + size * randomUnitVector(rng)};
}

// Casts nothing: sets the beams' ranges through keepNearestHit(), as the walks do.
void setRandomRanges(Rng& rng, core::BeamSet* beams) {
  for (int row = 0; row < beams->grid().rows(); ++row) {
    for (int col = 0; col < beams->grid().cols(); ++col) {
      if (rng() % 3 == 0) continue;
      beams->keepNearestHit(row, col, uniform(rng, 0.05, 40), 0, 0,
                            [] { return Eigen::Vector3d(); });
    }
  }
}

// The candidates a filter gave, and the beams that must be among them.
template <class Candidates>
void expectEveryKeptHitACandidate(Rng& rng, const core::ScanPattern& pattern, Candidates&& run,
                                  long long* hits, const core::ColumnMotion* motion = nullptr) {
  core::CastConfig config;
  config.tmax = 25;
  FreshBeams fresh(pattern, config);
  core::BeamSet& beams = fresh.beams;
  setRandomRanges(rng, &beams);
  long long passed = 0, tested = 0;
  for (int i = 0; i < 3000; ++i) {
    const FilterCase t = randomTriangle(rng);
    std::vector<char> candidate(pattern.size(), 0);
    run(beams, t, [&](int row, int col) { candidate[beams.grid().beam(row, col)] = 1; });
    for (int row = 0; row < beams.grid().rows(); ++row) {
      for (int col = 0; col < beams.grid().cols(); ++col) {
        ++tested;
        passed += candidate[beams.grid().beam(row, col)];
        core::Ray ray;
        ray.dir = beams.grid().direction(row, col);
        if (motion) ray = motion->ray(col, ray.dir, 0.0);  // a sweep's beam from its column
        ray.tmax = std::min(config.tmax, beams.range(row, col));
        if (!core::intersectTriangle<core::TriangleMethod::kWatertight>(ray, t.a, t.b, t.c)) {
          continue;
        }
        ++*hits;
        EXPECT_TRUE(candidate[beams.grid().beam(row, col)])
            << "triangle " << i << " row " << row << " col " << col;
      }
    }
    if (::testing::Test::HasFailure()) return;
  }
  // And it does filter (less for a sweep's block: triangles within a few shifts of the sensor let
  // every beam through).
  EXPECT_LT(passed, motion ? tested / 2 : tested / 4);
}

TEST(EdgeFilter, LetsThroughEveryBeamWhoseExactHitCouldBeKept) {
  Rng rng(29);
  const core::ScanPattern pattern(fanBySamples(-M_PI, M_PI, 360),
                                  std::vector<double>{-0.5, -0.2, 0.0, 0.1, 0.4});
  long long hits = 0;
  expectEveryKeptHitACandidate(
      rng, pattern,
      [](const core::BeamSet& beams, const FilterCase& t, auto&& mark) {
        const core::EdgeFilter filter(t.a, t.b, t.c);
        for (int row = 0; row < beams.grid().rows(); ++row) {
          filter.forEachCandidate(beams, row, 0, beams.grid().cols() - 1,
                                  [&](int col) { mark(row, col); });
        }
      },
      &hits);
  EXPECT_GT(hits, 1000);
}

// The same for the column raster, on a lidar's rings and on rings up to its steepest elevation.
// For a sweep block (ColumnMotion): every beam from its column's pose whose exact hit could be
// kept is a candidate, the raster widened by the block's spread with the triangle's plane distance
// as the near distance, and the raster that follows each column's origin (its planes nearer than
// twice the shift widened instead: shifts up to 5 cm and triangles from 10 cm away have both).
TEST(ColumnRaster, WithASpreadLetsThroughEveryColumnsBeamWhoseExactHitCouldBeKept) {
  Rng rng(47);
  std::vector<double> lidar;
  for (int r = 0; r < 16; ++r) lidar.push_back(-0.27 + 0.54 * r / 15);
  for (const auto& rings : {lidar, std::vector<double>{0.0}}) {
    const core::ScanPattern pattern(fanBySamples(-M_PI, M_PI, 512), rings);
    long long hits = 0;
    for (int trial = 0; trial < 4; ++trial) {
      const core::ColumnMotion motion =
          randomColumns(rng, pattern.azimuthCount(), uniform(rng, 0, 0.05), uniform(rng, 0, 0.03),
                        core::steepestElevation(pattern));
      const core::Spread& spread = motion.spread();
      expectEveryKeptHitACandidate(
          rng, pattern,
          [&](const core::BeamSet& beams, const FilterCase& t, auto&& mark) {
            const Eigen::Vector3d n = (t.b - t.a).cross(t.c - t.a);
            const double near = std::abs(n.dot(t.a)) / n.norm();
            const double widen =
                near > 2 * spread.shift
                    ? std::sin(std::min(M_PI / 2, spread.turn + std::asin(spread.shift / near)))
                    : 1.0;
            core::ColumnRaster(beams, t.a, t.b, t.c, widen, spread.shift, spread.turn)
                .forEachCandidate(beams, beams.grid().all(),
                                  [&](int row, int col) { mark(row, col); });
          },
          &hits, &motion);
      if (HasFailure()) return;
      if (pattern.planar()) continue;  // the walks raster a planar fan by its windows
      expectEveryKeptHitACandidate(
          rng, pattern,
          [&](const core::BeamSet& beams, const FilterCase& t, auto&& mark) {
            core::ColumnRaster(beams, t.a, t.b, t.c, motion, 0.0)
                .forEachCandidate(beams, beams.grid().all(),
                                  [&](int row, int col) { mark(row, col); });
          },
          &hits, &motion);
      if (HasFailure()) return;
    }
    EXPECT_GT(hits, 1000);
  }
}

TEST(ColumnRaster, LetsThroughEveryBeamWhoseExactHitCouldBeKept) {
  Rng rng(43);
  std::vector<double> lidar, steep;
  for (int r = 0; r < 32; ++r) lidar.push_back(-0.27 + 0.54 * r / 31);
  for (int r = 0; r < 9; ++r) {
    steep.push_back(-core::BeamGrid::kMaxColumnRasterElevation * (1 - r / 4.0));
  }
  for (const auto& rings : {lidar, steep}) {
    const core::ScanPattern pattern(fanBySamples(-M_PI, M_PI, 512), rings);
    long long hits = 0;
    expectEveryKeptHitACandidate(
        rng, pattern,
        [](const core::BeamSet& beams, const FilterCase& t, auto&& mark) {
          ASSERT_TRUE(beams.grid().columnRaster());
          core::ColumnRaster(beams, t.a, t.b, t.c)
              .forEachCandidate(beams, beams.grid().all(),
                                [&](int row, int col) { mark(row, col); });
        },
        &hits);
    EXPECT_GT(hits, 1000);
  }
}

// A rect of the grid gets the candidates the whole grid gets inside it, no more and no fewer: the
// raster skips the columns whose bounds miss the rect's rows before it looks rows up, and that
// must change nothing. The whole grid (64 rows) is scanned column by column and the rects (at most
// 13 rows) row by row, so this also holds the two scans to the same candidates.
TEST(ColumnRaster, ARectGetsTheWholeGridsCandidatesInsideIt) {
  Rng rng(53);
  std::vector<double> rings;
  for (int r = 0; r < 64; ++r) rings.push_back(-0.26 + 0.52 * r / 63);
  const core::ScanPattern pattern(fanBySamples(-M_PI, M_PI, 256), rings);
  core::CastConfig config;
  config.tmax = 25;
  FreshBeams fresh(pattern, config);
  core::BeamSet& beams = fresh.beams;
  setRandomRanges(rng, &beams);
  long long inside = 0;
  for (int i = 0; i < 3000; ++i) {
    const FilterCase t = randomTriangle(rng);
    const core::ColumnRaster raster(beams, t.a, t.b, t.c);
    std::set<int> whole, part;
    core::BeamRect rect;
    rect.row_lo = static_cast<int>(uniform(rng, 0, beams.grid().rows()));
    rect.row_hi =
        std::min(beams.grid().rows() - 1, rect.row_lo + static_cast<int>(uniform(rng, 0, 12)));
    rect.col_lo = static_cast<int>(uniform(rng, 0, beams.grid().cols()));
    rect.col_hi =
        std::min(beams.grid().cols() - 1, rect.col_lo + static_cast<int>(uniform(rng, 0, 40)));
    raster.forEachCandidate(beams, beams.grid().all(), [&](int row, int col) {
      if (row >= rect.row_lo && row <= rect.row_hi && col >= rect.col_lo && col <= rect.col_hi) {
        whole.insert(beams.grid().beam(row, col));
      }
    });
    raster.forEachCandidate(beams, rect, [&](int row, int col) {
      EXPECT_TRUE(row >= rect.row_lo && row <= rect.row_hi && col >= rect.col_lo &&
                  col <= rect.col_hi);
      part.insert(beams.grid().beam(row, col));
    });
    ASSERT_EQ(whole, part) << "triangle " << i;
    inside += static_cast<long long>(part.size());
  }
  EXPECT_GT(inside, 1000);
}

// SubRayFilter over a bundle's sub-rays (one a beam, from the sensor's origin): random triangles,
// the sub-rays aimed at random points in and around each (barycentrics from -0.05 to 1.05) or
// anywhere, taken in runs of 1 to 9 so that every lane count of the four-wide float test is met.
// With the directions kept in float (Bundle::from_origin) it lets through every sub-ray the exact
// test hits and every one the double test lets through, and turns away nearly all the double test
// turns away; without them it is the double test.
TEST(SubRayFilter, InFloatLetsThroughEveryHitAndEverySubRayTheDoubleTestDoes) {
  Rng rng(61);
  const core::ScanPattern pattern(fanBySamples(-M_PI, M_PI, 200),
                                  std::vector<double>{-0.3, -0.1, 0.0, 0.2});
  const std::size_t n = pattern.size();
  std::vector<Eigen::Vector3d> directions(n);
  core::ScanResult own;
  own.range.assign(n, std::numeric_limits<double>::infinity());
  own.body.assign(n, -1);
  own.triangle.assign(n, -1);
  core::CastConfig config;
  for (const bool from_origin : {true, false}) {
    core::BeamSet::Bundle bundle;
    bundle.directions = &directions;
    bundle.result = &own;
    bundle.from_origin = from_origin;
    long long hits = 0, double_misses = 0, float_misses = 0;
    for (int i = 0; i < 400; ++i) {
      const FilterCase t = randomTriangle(rng);
      for (Eigen::Vector3d& d : directions) {
        if (rng() % 4 == 0) {
          d = randomUnitVector(rng);
          continue;
        }
        const double u = uniform(rng, -0.05, 1.05), v = uniform(rng, -0.05, 1.05 - u);
        d = ((1 - u - v) * t.a + u * t.b + v * t.c).normalized();
      }
      FreshBeams fresh(pattern, config);
      fresh.beams.reset(pattern, config, &fresh.result, &bundle);
      ASSERT_EQ(fresh.beams.subDirectionsFloat() != nullptr, from_origin);
      const core::SubRayFilter filter(t.a, t.b, t.c);
      std::vector<char> passed(n, 0);
      for (int begin = 0; begin < static_cast<int>(n);) {
        const int end = std::min(static_cast<int>(n), begin + 1 + static_cast<int>(rng() % 9));
        int last = begin - 1;
        filter.forEachPassing(fresh.beams, begin, end, [&](int s) {
          EXPECT_TRUE(s > last && s < end) << "sub-ray " << s << " of " << begin << " to " << end;
          last = s;
          passed[s] = 1;
        });
        begin = end;
      }
      for (std::size_t s = 0; s < n; ++s) {
        core::Ray ray;
        ray.dir = directions[s];
        const bool hit =
            core::intersectTriangle<core::TriangleMethod::kWatertight>(ray, t.a, t.b, t.c)
                .has_value();
        const bool double_miss = filter.misses(directions[s]);
        hits += hit;
        double_misses += double_miss;
        float_misses += !passed[s];
        EXPECT_TRUE(passed[s] || !hit) << "triangle " << i << " sub-ray " << s;
        EXPECT_TRUE(passed[s] || double_miss) << "triangle " << i << " sub-ray " << s;
        if (!from_origin) EXPECT_EQ(!passed[s], double_miss);
      }
      if (::testing::Test::HasFailure()) return;
    }
    EXPECT_GT(hits, 10000);
    EXPECT_GT(double_misses, 10000);
    EXPECT_GE(float_misses, double_misses * 99 / 100) << "from_origin " << from_origin;
  }
}

}  // namespace
}  // namespace laser_raycast_test
