// A sweep block's reach (ColumnMotion::Reach): what it gathers from poses made by quaternion, as a
// block's class poses are, bounds what the same poses' rotation matrices give.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <limits>

#include "beams/column_motion.h"
#include "random.h"

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

}  // namespace
}  // namespace laser_raycast_test
