// A random scene for the caster's walk tests: a mesh of many prisms (one connected component
// each), a sphere mesh, a soup of separate triangles, boxes, cylinders and spheres, on a fixed
// frame and a moving one.
#pragma once

#include <cmath>
#include <memory>
#include <vector>

#include "cast_reference.h"
#include "mesh_builder.h"
#include "random.h"
#include "test_geometry.h"

namespace laser_raycast_test {

// Many prisms in one mesh: one connected component each.
inline std::shared_ptr<const core::Mesh> prismField(Rng& rng, int count, double spread) {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<core::TriangleIndices> triangles;
  for (int k = 0; k < count; ++k) {
    const int sides = 3 + static_cast<int>(uniform(rng, 0, 12));
    const TriMesh p =
        makePrism(circle(sides, uniform(rng, 0.05, 0.6), uniform(rng, 0, 1)),
                  {uniform(rng, -2, -0.2), uniform(rng, -0.1, 0.1), uniform(rng, 0.2, 2)});
    const Eigen::Vector3d at(uniform(rng, -spread, spread), uniform(rng, -spread, spread), 0);
    const auto base = static_cast<std::uint32_t>(vertices.size());
    for (const auto& v : p.vertices) vertices.push_back(v + at);
    for (const auto& t : p.triangles) triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  }
  return std::make_shared<const core::Mesh>(vertices, triangles);
}

struct RandomScene {
  core::Scene scene;
  core::FramePoses poses;
};

inline RandomScene randomScene(Rng& rng) {
  RandomScene out;
  core::Scene& scene = out.scene;
  const int world = scene.addFrame("world");
  const int cart = scene.addFrame("cart");
  for (const char* label : {"field", "ball", "soup", "box", "can", "bead"}) scene.addLabel(label);
  addBody(&scene, prismField(rng, 60, 12), world, Eigen::Isometry3d::Identity(), 0);
  addBody(&scene, uvSphere(uniform(rng, 0.5, 2), 12, 24), cart,
          pose(Eigen::Vector3d(uniform(rng, -6, 6), uniform(rng, -6, 6), 0)), 1);
  addBody(&scene, randomSoup(rng, 300, 8, 0.4), world, Eigen::Isometry3d::Identity(), 2);
  for (int i = 0; i < 8; ++i) {
    const Eigen::Isometry3d at =
        pose(uniformInBox(rng, Eigen::Vector3d(-10, -10, -1), Eigen::Vector3d(10, 10, 1)),
             randomRotation(rng).toRotationMatrix());
    switch (i % 3) {
      case 0:
        addBody(&scene,
                core::Box{Eigen::Vector3d(uniform(rng, 0.1, 3), uniform(rng, 0.1, 3),
                                          uniform(rng, 0.1, 3))},
                i % 2 ? cart : world, at, 3);
        break;
      case 1:
        addBody(&scene, core::Cylinder{uniform(rng, 0.1, 1), uniform(rng, 0.2, 3)},
                i % 2 ? cart : world, at, 4);
        break;
      default:
        addBody(&scene, core::Sphere{uniform(rng, 0.1, 1)}, i % 2 ? cart : world, at, 5);
    }
  }
  out.poses = core::FramePoses::identity(scene);
  out.poses.pose[cart] =
      pose(uniformInBox(rng, Eigen::Vector3d(-2, -2, -0.3), Eigen::Vector3d(2, 2, 0.3)),
           yaw(uniform(rng, -M_PI, M_PI)));
  return out;
}

}  // namespace laser_raycast_test
