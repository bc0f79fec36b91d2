// A sweep block's reach (ColumnMotion::Reach): what it gathers from poses made by quaternion, as a
// block's class poses are, bounds what the same poses' rotation matrices give. And the columns'
// poses (ColumnPoses) against PoseSamples' own interpolation.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <limits>
#include <vector>

#include "beams/column_motion.h"
#include "cast_reference.h"
#include "caster/column_poses.h"
#include "laser_raycast/core/pose_samples.h"
#include "random.h"
#include "scene/scene_index.h"

namespace laser_raycast_test {
namespace {

namespace core = laser_raycast::core;

// A pose's reach taken from its quaternion (a sweep's poses, ColumnPoses::Relative) bounds the
// turn of the matrix it gives at least as far as the matrix's own reach does, for turns from 1e-12
// rad to a half turn and quaternions off unit length by their rounding, and says "translations
// only" or "in the plane" only where the matrix is so.
TEST(ColumnMotion, AQuaternionsReachCoversItsRotationMatrix) {
  Rng rng(57);
  // Also over many poses at once: the maxima a block keeps bound each pose's own.
  core::ColumnMotion::Reach all_q, all_m;
  bool all_translations = true, all_in_plane = true;
  for (int i = 0; i < 20000; ++i) {
    const double angle = i % 7 == 0 ? 0.0 : logUniform(rng, -12, 0.5);
    const Eigen::Vector3d axis = i % 3 == 0 ? Eigen::Vector3d::UnitZ() : randomUnitVector(rng);
    Eigen::Quaterniond q(Eigen::AngleAxisd(angle, axis));
    // Off unit length by a few ulp, as a slerp's weighted sum is.
    q.coeffs() *= 1 + uniform(rng, -4, 4) * std::numeric_limits<double>::epsilon();
    const Eigen::Matrix3d r = q.toRotationMatrix();
    const Eigen::Vector3d t =
        i % 5 == 0 ? Eigen::Vector3d(uniform(rng, -1, 1), 0.2, 0) : uniformInCube(rng, 0.01);
    Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
    m.linear() = r;
    m.translation() = t;
    core::ColumnMotion::Reach from_q, from_m;
    from_q.add(q, r, t);
    from_m.add(m);
    EXPECT_GE(from_q.turnFrobenius2(), from_m.turnFrobenius2()) << "angle " << angle;
    EXPECT_LE(from_q.turnFrobenius2(), from_m.turnFrobenius2() * (1 + 1e-8) + 1e-20)
        << "angle " << angle;
    EXPECT_EQ(from_q.shift2, from_m.shift2);
    EXPECT_NEAR(from_q.z_move2, from_m.z_move2, 1e-15 * from_m.z_move2);
    EXPECT_TRUE(!from_q.translationsOnly() || from_m.translationsOnly());
    EXPECT_TRUE(!from_q.inPlane() || from_m.inPlane());
    EXPECT_TRUE(angle != 0 || from_q.translationsOnly());
    EXPECT_TRUE(!(axis == Eigen::Vector3d::UnitZ() && t.z() == 0) || from_q.inPlane());
    // Each run of 50 poses as a block would gather them.
    all_q.add(q, r, t);
    all_m.add(m);
    all_translations = all_translations && angle == 0;
    all_in_plane = all_in_plane && axis == Eigen::Vector3d::UnitZ() && t.z() == 0;
    if (i % 50 == 49) {
      EXPECT_GE(all_q.turnFrobenius2(), all_m.turnFrobenius2()) << "poses to " << i;
      EXPECT_EQ(all_q.shift2, all_m.shift2);
      EXPECT_TRUE(!all_q.translationsOnly() || all_m.translationsOnly());
      EXPECT_TRUE(!all_q.inPlane() || all_m.inPlane());
      EXPECT_TRUE(!all_translations || all_q.translationsOnly());
      EXPECT_TRUE(!all_in_plane || all_q.inPlane());
      all_q = all_m = core::ColumnMotion::Reach();
      all_translations = all_in_plane = true;
    }
  }
}

// Six samples 10 ms apart from a random pose, each turned from the last by `arc` about a random
// axis (the rotations' own angle: half the quaternions' arc is the slerp's) and moved by up to 2 cm.
core::PoseSamples turningSamples(const core::Scene& scene, double arc, Rng& rng) {
  core::PoseSamples samples;
  Eigen::Quaterniond q = randomRotation(rng);
  Eigen::Vector3d t = uniformInCube(rng, 10);
  for (int k = 0; k < 6; ++k) {
    samples.times.push_back(0.01 * k);
    samples.world_from_sensor.push_back(pose(t, q.toRotationMatrix()));
    samples.frames.push_back(core::FramePoses::identity(scene));
    q = q * Eigen::Quaterniond(Eigen::AngleAxisd(arc, randomUnitVector(rng)));
    t += uniformInCube(rng, 0.02);
  }
  return samples;
}

// A sweep's column poses are PoseSamples::sensorAt's at the columns' times to a few ulp, between
// samples that turn by anything from 1e-9 rad to a third of a turn: the slerp's sines are taken
// from series of as few terms as each arc allows (ColumnPoses::Rotations), and a series cut for a
// longer arc than it serves would be off by far more (x^7 / 5040 at 0.1 rad: 2e-11).
TEST(ColumnPoses, ColumnPosesAreTheSamplesInterpolatedOnArcsOfEveryLength) {
  core::Scene scene = sceneWithFrame();
  addBody(&scene, core::Box{Eigen::Vector3d(1, 1, 1)}, 0, pose({5, 0, 0}));
  const core::SceneIndex index(scene);
  Rng rng(58);
  for (const double arc : {1e-9, 1e-5, 1e-3, 0.0019, 0.003, 0.0150, 0.02, 0.1, 0.24, 0.3, 2.0}) {
    const core::PoseSamples samples = turningSamples(scene, arc, rng);
    std::vector<double> times;
    for (int c = 0; c < 200; ++c) times.push_back(uniform(rng, -0.005, 0.055));
    core::ColumnPoses::Storage storage;
    const core::ColumnPoses poses(scene, index, samples, times, &storage);
    double rotation = 0, translation = 0;
    for (int c = 0; c < poses.columns(); ++c) {
      const Eigen::Isometry3d expected = samples.sensorAt(times[c]), got = poses.sensor(c);
      rotation = std::max(rotation, (got.linear() - expected.linear()).cwiseAbs().maxCoeff());
      translation =
          std::max(translation, (got.translation() - expected.translation()).cwiseAbs().maxCoeff());
    }
    // A few ulp of the rotation's entries (at most 1: 1.3e-15 seen) and of the translation's (at
    // most 11 m; the same expression: 0 seen).
    EXPECT_LT(rotation, 3e-15) << "arc " << arc;
    EXPECT_LT(translation, 1e-14) << "arc " << arc;
  }
}

// A row class's delta from its column's pose (ColumnPoses::Relative::classDelta, shared by every
// column between the same two samples) composed with the column's pose is the class's own pose,
// the samples interpolated at its time relative to the reference (PoseSamples::sensorAt), to a
// few ulp, between samples that turn by 1e-9 rad to a third of a turn; a turn taken the wrong way
// round would be off by the arc's share of the class's time (1e-6 of the arc at least here).
TEST(ColumnPoses, AClassDeltaAfterItsColumnsPoseIsTheClasssPose) {
  core::Scene scene = sceneWithFrame();
  addBody(&scene, core::Box{Eigen::Vector3d(1, 1, 1)}, 0, pose({5, 0, 0}));
  const core::SceneIndex index(scene);
  Rng rng(59);
  for (const double arc : {1e-9, 1e-5, 1e-3, 0.003, 0.02, 0.1, 0.3, 2.0}) {
    const core::PoseSamples samples = turningSamples(scene, arc, rng);
    // Columns 0..99 and their classes, each a time of up to 4 ms after its column, at 100..199.
    std::vector<double> times;
    for (int c = 0; c < 100; ++c) times.push_back(uniform(rng, 0.0, 0.05));
    for (int c = 0; c < 100; ++c) times.push_back(times[c] + uniform(rng, 1e-6, 0.004));
    core::ColumnPoses::Storage storage;
    const core::ColumnPoses poses(scene, index, samples, times, &storage);
    core::ColumnPoses::Relative relative(poses, 50, nullptr);
    const Eigen::Isometry3d world_from_ref = samples.sensorAt(times[50]);
    double rotation = 0, translation = 0;
    int tested = 0;
    for (int c = 0; c < 100; ++c) {
      const core::ColumnPoses::Bracket &b = poses.bracket(c), &bk = poses.bracket(100 + c);
      if (!(b.j != b.i && bk.i == b.i && bk.j != bk.i)) continue;  // not between one pair
      ++tested;
      core::ColumnMotion::Pose column;
      core::ColumnMotion::Reach reach;
      relative.at(c, nullptr, &column, &reach);
      const core::ColumnMotion::ClassDelta delta = relative.classDelta(b, bk.s - b.s);
      const Eigen::Matrix3d got_rotation = column.linear() * delta.rot;
      const Eigen::Vector3d got_translation = column.translation() + delta.offset;
      const Eigen::Isometry3d expected =
          world_from_ref.inverse() * samples.sensorAt(times[100 + c]);
      rotation = std::max(rotation, (got_rotation - expected.linear()).cwiseAbs().maxCoeff());
      translation =
          std::max(translation, (got_translation - expected.translation()).cwiseAbs().maxCoeff());
    }
    EXPECT_GT(tested, 50) << "arc " << arc;
    EXPECT_LT(rotation, 1e-14) << "arc " << arc;
    EXPECT_LT(translation, 1e-14) << "arc " << arc;
  }
}

// A block's motion with row classes given pose by pose keeps each class as its column's delta:
// every beam's ray is its class's pose's to the rounding, deviation() bounds how far its origin
// lies from its column's, and the spread bounds how far each class's pose lies and turns from the
// reference.
TEST(ColumnMotion, RowClassesGivenPoseByPoseAreTheirPosesRays) {
  Rng rng(60);
  const int columns = 40, classes = 5;
  std::vector<Eigen::Isometry3d> column_poses;
  std::vector<std::vector<Eigen::Isometry3d>> class_poses(classes - 1);
  auto small_pose = [&](double turn, double move) {
    return pose(uniformInCube(rng, move),
                Eigen::AngleAxisd(uniform(rng, 0, turn), randomUnitVector(rng)).toRotationMatrix());
  };
  for (int c = 0; c < columns; ++c) {
    column_poses.push_back(small_pose(0.01, 0.01));
    for (auto& poses_of_class : class_poses) {
      poses_of_class.push_back(column_poses.back() * small_pose(1e-4, 1e-4));
    }
  }
  const std::vector<int> class_of_row = {0, 3, 1, 4, 2, 2, 0};
  const core::ColumnMotion motion(7, column_poses, 0.3, 0.0, class_of_row, class_poses);
  double deviation = 0, shift = 0, turn = 0;
  for (int c = 0; c < columns; ++c) {
    for (int row = 0; row < static_cast<int>(class_of_row.size()); ++row) {
      const int k = class_of_row[row];
      const Eigen::Isometry3d& m = k == 0 ? column_poses[c] : class_poses[k - 1][c];
      const Eigen::Vector3d d = randomUnitVector(rng);
      const core::Ray ray = motion.ray(row, 7 + c, d, 0.1);
      EXPECT_LT((ray.origin - m.translation()).cwiseAbs().maxCoeff(), 1e-17);
      EXPECT_LT((ray.dir - m.linear() * d).cwiseAbs().maxCoeff(), 1e-15);
      EXPECT_EQ(ray.tmin, 0.1);
      EXPECT_LT((motion.direction(row, 7 + c, d) - ray.dir).norm(), 1e-300);
      const Eigen::Vector3d n = randomUnitVector(rng);
      EXPECT_LT((motion.toBeam(row, 7 + c, n) - m.linear().transpose() * n).norm(), 1e-15);
      deviation = std::max(deviation, (m.translation() - column_poses[c].translation()).norm());
      shift = std::max(shift, m.translation().norm());
      turn = std::max(turn, Eigen::AngleAxisd(m.linear()).angle());
    }
  }
  EXPECT_GE(motion.deviation(), deviation);
  EXPECT_LE(motion.deviation(), deviation * (1 + 1e-6));
  EXPECT_GE(motion.spread().shift, shift);
  EXPECT_GE(motion.spread().turn, turn);
  EXPECT_FALSE(motion.translationsOnly());
  EXPECT_FALSE(motion.inPlane());
}

}  // namespace
}  // namespace laser_raycast_test
