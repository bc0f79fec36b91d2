// The scene loader tests' URDF snippets, their fixture (a loader whose package:// resolver knows
// only test_pkg, test/data) and checks on what it loaded. The including target defines
// LASER_RAYCAST_SOURCE_DIR.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "laser_raycast/loader/scene_loader.h"

namespace laser_raycast_test {

namespace core = laser_raycast::core;

using MeshPtr = std::shared_ptr<const core::Mesh>;

inline const std::string kSourceDir = LASER_RAYCAST_SOURCE_DIR;
inline const std::string kMeshes = kSourceDir + "/test/data/meshes";

inline std::string robot(const std::string& body) {
  return "<?xml version=\"1.0\"?><robot name=\"test\">" + body + "</robot>";
}

inline std::string meshLink(const std::string& link, const std::string& filename,
                            const std::string& scale = "1 1 1") {
  return "<link name=\"" + link + "\"><visual><geometry><mesh filename=\"" + filename +
         "\" scale=\"" + scale + "\"/></geometry></visual></link>";
}

inline std::string boxLink(const std::string& link, const std::string& size = "1 1 1") {
  return "<link name=\"" + link + "\"><visual><geometry><box size=\"" + size +
         "\"/></geometry></visual></link>";
}

inline std::string joint(const std::string& name, const std::string& type,
                         const std::string& parent, const std::string& child,
                         const std::string& origin = "", const std::string& extra = "") {
  return "<joint name=\"" + name + "\" type=\"" + type + "\"><parent link=\"" + parent +
         "\"/><child link=\"" + child + "\"/>" + origin + extra + "</joint>";
}

inline MeshPtr meshOf(const core::Scene& scene, int body) {
  const auto* mesh = std::get_if<MeshPtr>(&scene.bodies().at(body).shape);
  return mesh ? *mesh : nullptr;
}

inline const std::string& frameOf(const core::Scene& scene, int body) {
  return scene.frames().at(scene.bodies().at(body).frame);
}

inline const std::string& labelOf(const core::Scene& scene, int body) {
  return scene.labels().at(scene.bodies().at(body).label);
}

inline void expectBounds(const core::Mesh& mesh, const Eigen::Vector3d& lo,
                         const Eigen::Vector3d& hi, double tol) {
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(mesh.bounds().lo[k], lo[k], tol) << "axis " << k;
    EXPECT_NEAR(mesh.bounds().hi[k], hi[k], tol) << "axis " << k;
  }
}

// For a convex mesh: every triangle's normal points away from the centre.
inline void expectOutwardFaces(const core::Mesh& mesh) {
  const Eigen::Vector3d center = mesh.bounds().center();
  for (std::uint32_t t = 0; t < mesh.triangles().size(); ++t) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (std::uint32_t v : mesh.triangles()[t]) centroid += mesh.vertices()[v] / 3;
    EXPECT_GT(mesh.normal(t).dot(centroid - center), 0) << "triangle " << t;
  }
}

inline void expectPose(const Eigen::Isometry3d& actual, const Eigen::Isometry3d& expected,
                       double tol = 1e-12) {
  EXPECT_TRUE(actual.isApprox(expected, tol)) << "actual\n"
                                              << actual.matrix() << "\nexpected\n"
                                              << expected.matrix();
}

inline Eigen::Isometry3d pose(const Eigen::Vector3d& xyz,
                              const Eigen::Vector3d& rpy = Eigen::Vector3d::Zero()) {
  // URDF: fixed axes roll about x, then pitch about y, then yaw about z.
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = xyz;
  t.linear() = (Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  return t;
}

class SceneLoaderTest : public ::testing::Test {
 protected:
  SceneLoaderTest()
      : loader_([this](const std::string& package) -> std::optional<std::string> {
          resolved_.push_back(package);
          if (package == "test_pkg") return kSourceDir + "/test/data";
          return std::nullopt;
        }) {}

  laser_raycast::LoadedModel load(const std::string& xml,
                                  const laser_raycast::LoaderOptions& options = {},
                                  const std::string& base_dir = "") {
    return loader_.addUrdfString(xml, base_dir, options, &scene_);
  }

  laser_raycast::SceneLoader loader_;
  std::vector<std::string> resolved_;
  core::Scene scene_;
};

}  // namespace laser_raycast_test
