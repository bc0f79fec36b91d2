// Forward kinematics (kinematics.h): link poses for revolute, continuous, prismatic and fixed
// joints, and frame poses for a scene, against poses worked out by hand in the comments.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>

#include "laser_raycast/loader/kinematics.h"
#include "laser_raycast/loader/scene_loader.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast;
using Eigen::Matrix3d;
using Eigen::Vector3d;

const std::string kData = std::string(LASER_RAYCAST_SOURCE_DIR) + "/test/data/";

Eigen::Isometry3d pose(const Matrix3d& rotation, const Vector3d& translation) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.linear() = rotation;
  p.translation() = translation;
  return p;
}

// Every entry within 1e-12 of the hand-computed one (the entries are of order 1).
void expectPose(const std::map<std::string, Eigen::Isometry3d>& poses, const std::string& link,
                const Eigen::Isometry3d& expected) {
  const auto it = poses.find(link);
  ASSERT_NE(it, poses.end()) << "no pose for " << link;
  const Eigen::Matrix4d difference = it->second.matrix() - expected.matrix();
  EXPECT_LE(difference.cwiseAbs().maxCoeff(), 1e-12) << link << ": actual\n"
                                                     << it->second.matrix() << "\nexpected\n"
                                                     << expected.matrix();
}

Matrix3d rows(const Vector3d& r0, const Vector3d& r1, const Vector3d& r2) {
  Matrix3d m;
  m.row(0) = r0;
  m.row(1) = r1;
  m.row(2) = r2;
  return m;
}

LoadedModel load(const std::string& path, const std::string& prefix = "") {
  SceneLoader loader(nullptr);
  core::Scene scene;
  LoaderOptions options;
  options.tf_prefix = prefix;
  return loader.addUrdfFile(path, options, &scene);
}

// cli_joints.urdf: "swing" revolute about z at base's origin, "slide" prismatic along -y from
// (0, -1, 0), "plate_fix" fixed at (-1.5, 0, 0).
TEST(ForwardKinematics, RevolutePrismaticAndFixedJoints) {
  const LoadedModel model = load(kData + "cli_joints.urdf");
  const Eigen::Isometry3d world_from_root = pose(Matrix3d::Identity(), Vector3d(1, 2, 3));
  const auto poses =
      forwardKinematics(model, world_from_root, {{"swing", M_PI / 2}, {"slide", 0.5}});
  EXPECT_EQ(poses.size(), 4u);
  expectPose(poses, "base", world_from_root);
  // Rz(pi/2) at the base's origin.
  expectPose(poses, "arm", pose(rows({0, -1, 0}, {1, 0, 0}, {0, 0, 1}), Vector3d(1, 2, 3)));
  // (0, -1, 0) + 0.5 (0, -1, 0) from the base.
  expectPose(poses, "slider", pose(Matrix3d::Identity(), Vector3d(1, 0.5, 3)));
  expectPose(poses, "plate", pose(Matrix3d::Identity(), Vector3d(-0.5, 2, 3)));

  // Joints without a value are at 0; values of unknown joints are ignored.
  const auto rest = forwardKinematics(model, Eigen::Isometry3d::Identity(), {{"elbow", 1.0}});
  expectPose(rest, "arm", Eigen::Isometry3d::Identity());
  expectPose(rest, "slider", pose(Matrix3d::Identity(), Vector3d(0, -1, 0)));
}

// A chain whose origins are turned, so that each axis is in its joint's frame, not the parent's:
//   a --j1 continuous: origin (1 0 0) yaw pi/2, axis z, value pi/2--> b
//     b = T(1,0,0) Rz(pi/2) Rz(pi/2) = T(1,0,0) Rz(pi)
//   b --j2 prismatic: origin (0 2 0), axis x, value 0.5--> c
//     c = b T(0.5,2,0): position (1,0,0) + Rz(pi) (0.5,2,0) = (0.5,-2,0), rotation Rz(pi)
//   c --j3 fixed: origin (0 0 1) roll pi/2--> d
//     d: position (0.5,-2,0) + Rz(pi) (0,0,1) = (0.5,-2,1), rotation Rz(pi) Rx(pi/2)
//        = [-1 0 0; 0 0 1; 0 1 0]
//   d --j4 revolute: origin yaw pi/2, axis (0 1 1)/sqrt(2), value pi--> e
//     a half turn about the unit axis u is 2 u u^T - I = [-1 0 0; 0 0 1; 0 1 0];
//     e: position (0.5,-2,1), rotation d Rz(pi/2) [-1 0 0; 0 0 1; 0 1 0]
//        = [-1 0 0; 0 0 1; 0 1 0] [0 0 -1; -1 0 0; 0 1 0] = [0 0 1; 0 1 0; -1 0 0] = Ry(pi/2)
//   e --j5 fixed: origin (1 0 0)--> f
//     f: position (0.5,-2,1) + Ry(pi/2) (1,0,0) = (0.5,-2,0), rotation Ry(pi/2)
//   a --j6 floating: origin (0 0 5)--> g (a floating joint does not move: g at (0,0,5))
const char* const kChain = R"(<?xml version="1.0"?>
<robot name="chain">
  <link name="a"/><link name="b"/><link name="c"/><link name="d"/><link name="e"/><link name="f"/>
  <link name="g"/>
  <joint name="j1" type="continuous"><parent link="a"/><child link="b"/>
    <origin xyz="1 0 0" rpy="0 0 1.5707963267948966"/><axis xyz="0 0 1"/></joint>
  <joint name="j2" type="prismatic"><parent link="b"/><child link="c"/>
    <origin xyz="0 2 0"/><axis xyz="1 0 0"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="j3" type="fixed"><parent link="c"/><child link="d"/>
    <origin xyz="0 0 1" rpy="1.5707963267948966 0 0"/></joint>
  <joint name="j4" type="revolute"><parent link="d"/><child link="e"/>
    <origin rpy="0 0 1.5707963267948966"/><axis xyz="0 1 1"/>
    <limit lower="-4" upper="4" effort="1" velocity="1"/></joint>
  <joint name="j5" type="fixed"><parent link="e"/><child link="f"/><origin xyz="1 0 0"/></joint>
  <joint name="j6" type="floating"><parent link="a"/><child link="g"/><origin xyz="0 0 5"/></joint>
</robot>)";

TEST(ForwardKinematics, ContinuousJointAndAxesInTheJointFrame) {
  SceneLoader loader(nullptr);
  core::Scene scene;
  const LoadedModel model = loader.addUrdfString(kChain, "", {}, &scene);
  const auto poses = forwardKinematics(model, Eigen::Isometry3d::Identity(),
                                       {{"j1", M_PI / 2}, {"j2", 0.5}, {"j4", M_PI}});
  EXPECT_EQ(poses.size(), 7u);
  const Matrix3d rz_pi = rows({-1, 0, 0}, {0, -1, 0}, {0, 0, 1});
  const Matrix3d ry_half_pi = rows({0, 0, 1}, {0, 1, 0}, {-1, 0, 0});
  expectPose(poses, "a", Eigen::Isometry3d::Identity());
  expectPose(poses, "b", pose(rz_pi, Vector3d(1, 0, 0)));
  expectPose(poses, "c", pose(rz_pi, Vector3d(0.5, -2, 0)));
  expectPose(poses, "d", pose(rows({-1, 0, 0}, {0, 0, 1}, {0, 1, 0}), Vector3d(0.5, -2, 1)));
  expectPose(poses, "e", pose(ry_half_pi, Vector3d(0.5, -2, 1)));
  expectPose(poses, "f", pose(ry_half_pi, Vector3d(0.5, -2, 0)));
  expectPose(poses, "g", pose(Matrix3d::Identity(), Vector3d(0, 0, 5)));
}

TEST(ForwardKinematics, ModelWithoutMovableJoints) {
  // Regression: KDL's tree solver indexes an empty joint array here.
  SceneLoader loader(nullptr);
  core::Scene scene;
  const LoadedModel model = loader.addUrdfString(R"(<robot name="still">
    <link name="a"/><link name="b"/><link name="c"/>
    <joint name="ab" type="fixed"><parent link="a"/><child link="b"/><origin xyz="0 1 0"/></joint>
    <joint name="ac" type="floating"><parent link="a"/><child link="c"/><origin xyz="0 0 1"/>
    </joint></robot>)",
                                                 "", {}, &scene);
  const auto poses = forwardKinematics(model, Eigen::Isometry3d::Identity(), {{"ac", 1.0}});
  EXPECT_EQ(poses.size(), 3u);
  expectPose(poses, "b", pose(Matrix3d::Identity(), Vector3d(0, 1, 0)));
  expectPose(poses, "c", pose(Matrix3d::Identity(), Vector3d(0, 0, 1)));
}

TEST(ForwardKinematics, LinkNamesCarryTheModelsPrefix) {
  const LoadedModel model = load(kData + "cli_joints.urdf", "m1/");
  const auto poses = forwardKinematics(model, Eigen::Isometry3d::Identity(), {{"slide", 1.0}});
  EXPECT_EQ(poses.size(), 4u);
  expectPose(poses, "m1/slider", pose(Matrix3d::Identity(), Vector3d(0, -2, 0)));
}

TEST(FramePosesFromLinks, SceneFramesTakeTheirLinksPoses) {
  // cli_joints.urdf: the plate is merged into the base's frame; arm and slider have their own.
  SceneLoader loader(nullptr);
  core::Scene scene;
  const LoadedModel model = loader.addUrdfFile(kData + "cli_joints.urdf", {}, &scene);
  const Eigen::Isometry3d world_from_root = pose(Matrix3d::Identity(), Vector3d(0, 0, 2));
  auto link_poses = forwardKinematics(model, world_from_root, {{"swing", M_PI}});
  const core::FramePoses frames = framePosesFromLinks(scene, link_poses);
  ASSERT_EQ(frames.pose.size(), scene.frames().size());
  for (std::size_t f = 0; f < scene.frames().size(); ++f) {
    SCOPED_TRACE(scene.frames()[f]);
    ASSERT_TRUE(frames.valid[f]);
    expectPose(link_poses, scene.frames()[f], frames.pose[f]);
  }
  // A frame whose link has no pose is invalid.
  link_poses.erase("arm");
  const core::FramePoses without_arm = framePosesFromLinks(scene, link_poses);
  for (std::size_t f = 0; f < scene.frames().size(); ++f) {
    EXPECT_EQ(static_cast<bool>(without_arm.valid[f]), scene.frames()[f] != "arm")
        << scene.frames()[f];
  }
}

TEST(PoseFromXyzRpy, FixedAxesRollPitchYaw) {
  // Roll, then yaw, about the fixed axes: Rz(pi/2) Rx(pi/2).
  const Eigen::Isometry3d p = poseFromXyzRpy(1, 2, 3, M_PI / 2, 0, M_PI / 2);
  const Eigen::Isometry3d expected = pose(rows({0, 0, 1}, {1, 0, 0}, {0, 1, 0}), Vector3d(1, 2, 3));
  EXPECT_LE((p.matrix() - expected.matrix()).cwiseAbs().maxCoeff(), 1e-15) << p.matrix();
  // Pitch alone: Ry(pi/2).
  const Eigen::Isometry3d pitch = poseFromXyzRpy(0, 0, 0, 0, M_PI / 2, 0);
  EXPECT_LE((pitch.linear() - rows({0, 0, 1}, {0, 1, 0}, {-1, 0, 0})).cwiseAbs().maxCoeff(), 1e-15);
}

}  // namespace
}  // namespace laser_raycast_test
