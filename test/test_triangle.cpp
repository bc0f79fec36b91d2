#include <gtest/gtest.h>

#include "laser_raycast/core/triangle.h"

using namespace laser_raycast::core;

TEST(Triangle, Smoke) {
  Ray ray;
  ray.origin = Eigen::Vector3d(0.2, 0.2, -1);
  ray.dir = Eigen::Vector3d(0, 0, 1);
  for (auto m : kAllTriangleMethods) {
    auto hit = intersectTriangle(m, ray, Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0),
                                 Eigen::Vector3d(0, 1, 0));
    ASSERT_TRUE(hit) << toString(m);
    EXPECT_DOUBLE_EQ(hit->t, 1.0) << toString(m);
    EXPECT_DOUBLE_EQ(hit->u, 0.2) << toString(m);
    EXPECT_DOUBLE_EQ(hit->v, 0.2) << toString(m);
  }
}
