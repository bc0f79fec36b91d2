// The node's scene as parts (scene_source.h, without roscore), as ~spawn_model and ~delete_model
// change it: adding a model loads that model alone (its mesh read and its BVH built, counted by the
// loader) and composes a scene whose other bodies share the meshes already loaded, the same
// objects with the same BVHs, rather than building them again; removing it composes the scene
// from before, body for body.
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "scene_source.h"
#include "temp_files.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast;
using MeshPtr = std::shared_ptr<const core::Mesh>;

// A robot of one link holding the STL at path and a box, beside it.
std::string meshUrdf(const std::string& name, const std::string& path) {
  return "<robot name='" + name + "'><link name='" + name + "_link'><visual><geometry><mesh " +
         "filename='" + path + "'/></geometry></visual><visual><origin xyz='0 0 1'/><geometry>" +
         "<box size='1 1 1'/></geometry></visual></link></robot>";
}

ScenePart loadPart(const NodeParams& params, const std::string& name, std::uint32_t triangles) {
  const std::string stl = writeBinaryStlGrid(name + ".stl", triangles);
  ScenePart part;
  const std::string error =
      loadUrdfPart(params, meshUrdf(name, stl), "", "", "test " + name, &part);
  EXPECT_EQ(error, "");
  return part;
}

// The mesh of body i, or null for a primitive.
MeshPtr meshOf(const core::Scene& scene, std::size_t i) {
  const auto* mesh = std::get_if<MeshPtr>(&scene.bodies().at(i).shape);
  return mesh ? *mesh : nullptr;
}

// a and b hold the same bodies: the same shapes (a mesh the same object), frames, labels, poses.
void expectSameBodies(const core::Scene& a, const core::Scene& b, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    const core::Body &x = a.bodies().at(i), &y = b.bodies().at(i);
    EXPECT_EQ(meshOf(a, i), meshOf(b, i)) << "body " << i;
    EXPECT_EQ(a.frames().at(x.frame), b.frames().at(y.frame)) << "body " << i;
    EXPECT_EQ(a.labels().at(x.label), b.labels().at(y.label)) << "body " << i;
    EXPECT_TRUE(x.frame_from_body.matrix() == y.frame_from_body.matrix()) << "body " << i;
  }
}

TEST(SceneParts, AddingAModelBuildsItsMeshAloneAndSharesTheOthers) {
  NodeParams params;
  params.fixed_frame = "world";
  // The scene so far: a model placed in the fixed frame and one whose link comes from TF.
  std::vector<ScenePart> parts;
  parts.push_back(loadPart(params, "first", 20000));
  parts.back().placed = true;
  parts.back().root_pose = Eigen::Translation3d(1, 2, 0) * Eigen::Isometry3d::Identity();
  parts.push_back(loadPart(params, "second", 30000));
  EXPECT_EQ(parts[0].model.mesh_triangles_built, 20000u);
  EXPECT_EQ(parts[1].model.mesh_triangles_built, 30000u);
  core::Scene before;
  composeScene(parts, params.fixed_frame, &before);
  ASSERT_EQ(before.bodies().size(), 4u);  // a mesh and a box each
  std::vector<MeshPtr> meshes;
  std::vector<const core::Bvh*> bvhs;
  for (std::size_t i = 0; i < before.bodies().size(); ++i) {
    meshes.push_back(meshOf(before, i));
    bvhs.push_back(meshes.back() ? &meshes.back()->bvh() : nullptr);
  }
  ASSERT_TRUE(meshes[0] && meshes[2]);
  const long first_uses = meshes[0].use_count();

  // A model of 10,000 triangles added: the loader builds that mesh and no other.
  parts.push_back(loadPart(params, "added", 10000));
  EXPECT_EQ(parts.back().model.mesh_triangles_built, 10000u);
  core::Scene after;
  composeScene(parts, params.fixed_frame, &after);
  ASSERT_EQ(after.bodies().size(), 6u);
  // The bodies from before come first, on the same meshes: the same objects, BVHs and all, one
  // more holder each (the new scene), not copies.
  expectSameBodies(before, after, before.bodies().size());
  for (std::size_t i = 0; i < before.bodies().size(); ++i) {
    if (!meshes[i]) continue;
    EXPECT_EQ(&meshOf(after, i)->bvh(), bvhs[i]) << "body " << i;
  }
  EXPECT_EQ(meshes[0].use_count(), first_uses + 1);
  // The added model's mesh is the one its load built.
  EXPECT_EQ(meshOf(after, 4), meshOf(parts.back().scene, 0));
  EXPECT_EQ(after.triangleCount(), 60000u);
  EXPECT_NE(after.version(), before.version());  // the caster's per-scene state is made anew

  // Removed again: the scene composed then holds the bodies from before, body for body.
  parts.pop_back();
  core::Scene again;
  composeScene(parts, params.fixed_frame, &again);
  ASSERT_EQ(again.bodies().size(), before.bodies().size());
  expectSameBodies(before, again, before.bodies().size());
  EXPECT_EQ(again.frames(), before.frames());
  EXPECT_EQ(again.labels(), before.labels());
}

// A model spawned twice from one mesh file reads and builds that mesh once: the second load finds
// it in the process's cache, and both scenes share it.
TEST(SceneParts, ASecondModelOfOneMeshBuildsNothing) {
  NodeParams params;
  const std::string stl = writeBinaryStlGrid("shared.stl", 5000);
  ScenePart one, two;
  ASSERT_EQ(loadUrdfPart(params, meshUrdf("one", stl), "", "", "test one", &one), "");
  ASSERT_EQ(loadUrdfPart(params, meshUrdf("two", stl), "", "", "test two", &two), "");
  EXPECT_EQ(one.model.mesh_triangles_built, 5000u);
  EXPECT_EQ(two.model.mesh_triangles_built, 0u);
  EXPECT_EQ(meshOf(one.scene, 0), meshOf(two.scene, 0));
}

}  // namespace
}  // namespace laser_raycast_test
