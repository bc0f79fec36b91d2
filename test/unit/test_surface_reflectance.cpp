// Reflectance and incidence from the surface hit (surface_reflectance.h): meshes read through the
// importer (test/data/surfaces, written by make_surfaces.py) and cast, against values computed
// here from the files' definitions: the checkerboard's texel under each hit, the vertex colours
// interpolated at hand-computed barycentric coordinates, the vertex normals' incidence.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "laser_raycast/core/beam_list.h"
#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/measurement_model.h"
#include "laser_raycast/core/surface.h"
#include "laser_raycast/core/surface_reflectance.h"
#include "laser_raycast/loader/scene_loader.h"

namespace laser_raycast {
namespace {

using Eigen::Vector3d;

const std::string kDir = std::string(LASER_RAYCAST_SOURCE_DIR) + "/test/data/surfaces/";

std::shared_ptr<const core::Mesh> load(const std::string& file) {
  SceneLoader loader(nullptr);
  return loader.loadMesh(kDir + file, "", Vector3d::Ones(), {});
}

// A scene of one mesh at the origin, on label 0.
core::Scene sceneOf(std::shared_ptr<const core::Mesh> mesh) {
  core::Scene scene;
  core::Body body;
  body.shape = std::move(mesh);
  body.frame = scene.addFrame("world");
  body.label = scene.addLabel("wall");
  scene.addBody(body);
  return scene;
}

// Casts pattern from the origin and samples the surfaces.
struct Sampled {
  core::ScanResult result;
  core::SurfaceSamples surface;
};
Sampled castAndSample(const core::Scene& scene, const core::ScanPattern& pattern,
                      std::vector<char> fixed = {}) {
  core::Caster caster;
  core::CastConfig config;
  config.compute_incidence = true;
  Sampled out;
  const core::FramePoses poses = core::FramePoses::identity(scene);
  out.result = caster.cast(scene, poses, Eigen::Isometry3d::Identity(), pattern, config);
  core::sampleSurfaces(scene, poses, Eigen::Isometry3d::Identity(), pattern, out.result, 1.0, fixed,
                       &out.surface);
  return out;
}

// A URDF (its meshes relative to kDir) cast with two beams, along +x and +y.
Sampled castAlongXAndY(const std::string& urdf) {
  core::Scene scene;
  SceneLoader loader(nullptr);
  loader.addUrdfString(urdf, kDir, {}, &scene);
  core::FanSpec fan;
  fan.angle_min = 0;
  fan.angle_max = M_PI / 2;
  fan.samples = 2;
  return castAndSample(scene, core::ScanPattern(fan));
}

// A grid of beams towards the plane x = distance, over y and z in (-extent, extent).
core::ScanPattern gridTowards(double distance, double extent, int azimuths, int rings) {
  core::FanSpec fan;
  const double a = std::atan(extent / distance);
  fan.angle_min = -a;
  fan.angle_max = a;
  fan.samples = azimuths;
  std::vector<double> elevations;
  for (int r = 0; r < rings; ++r) elevations.push_back(-a * 0.9 + 1.8 * a * r / (rings - 1));
  return core::ScanPattern(fan, elevations);
}

TEST(SurfaceReflectance, ACheckerboardTextureGivesTheCheckerboardInTheIntensities) {
  const auto mesh = load("checker_wall.obj");
  ASSERT_NE(mesh->surface(), nullptr);
  ASSERT_EQ(mesh->surface()->uvs.size(), mesh->vertices().size());
  const core::Scene scene = sceneOf(mesh);
  const core::ScanPattern pattern = gridTowards(2.0, 0.98, 301, 61);
  const Sampled s = castAndSample(scene, pattern);
  int checked = 0, white = 0;
  for (int i = 0; i < pattern.size(); ++i) {
    ASSERT_TRUE(std::isfinite(s.result.range[i])) << i;
    const Vector3d hit = s.result.range[i] * pattern.directions()[i];
    // The texel under the hit, from the OBJ's texture coordinates and the PNG's layout.
    const double u = (hit.y() + 1) / 2, v = (hit.z() + 1) / 2;
    const double column = u * 8, row = (1 - v) * 8;
    // Beams within rounding of a cell edge could fall on either side.
    if (std::abs(column - std::round(column)) < 1e-9 || std::abs(row - std::round(row)) < 1e-9) {
      continue;
    }
    const bool is_white = (static_cast<int>(column) + static_cast<int>(row)) % 2 == 0;
    EXPECT_EQ(s.surface.reflectance[i], is_white ? 1.0 : 0.0)
        << "beam " << i << " at y " << hit.y() << " z " << hit.z();
    ++checked;
    white += is_white;
  }
  EXPECT_GT(checked, pattern.size() * 9 / 10);
  EXPECT_GT(white, checked / 3);
  EXPECT_LT(white, 2 * checked / 3);
}

TEST(SurfaceReflectance, BeamsOffTheGridAreSampledFromTheirOwnOrigins) {
  // Parallel beams along +x from origins spread over y and z (a calibrated head's beams, each
  // from its own origin): each hits the wall x = 2 straight ahead of its origin, on the texel
  // under (y, z), which the beam from the sensor's origin along the same direction would not.
  const core::Scene scene = sceneOf(load("checker_wall.obj"));
  core::BeamList beams;
  for (int k = 0; k < 40; ++k) {
    beams.directions.push_back(Vector3d::UnitX());
    beams.origins.push_back(Vector3d(0.3, -0.93 + 0.047 * k, 0.81 - 0.041 * k));
  }
  core::Caster caster;
  core::CastConfig config;
  config.compute_incidence = true;
  const core::FramePoses poses = core::FramePoses::identity(scene);
  const core::ScanResult result =
      caster.castBeams(scene, poses, Eigen::Isometry3d::Identity(), beams, config);
  core::SurfaceSamples surface;
  core::sampleSurfaces(scene, poses, Eigen::Isometry3d::Identity(), beams, result, 1.0, {},
                       &surface);
  int white = 0;
  for (int i = 0; i < beams.size(); ++i) {
    ASSERT_NEAR(result.range[i], 1.7, 1e-12) << i;
    const double u = (beams.origins[i].y() + 1) / 2, v = (beams.origins[i].z() + 1) / 2;
    const bool is_white = (static_cast<int>(u * 8) + static_cast<int>((1 - v) * 8)) % 2 == 0;
    EXPECT_EQ(surface.reflectance[i], is_white ? 1.0 : 0.0) << "beam " << i;
    EXPECT_NEAR(surface.cos_incidence[i], 1.0, 1e-12) << i;
    white += is_white;
  }
  EXPECT_GT(white, 5);
  EXPECT_LT(white, 35);
}

TEST(SurfaceReflectance, TheIntensityChangesAtTheTexturesCellEdges) {
  // A fan at z = 0.1 (row 3 from the top: v = 0.55) across the wall: the intensity flips exactly
  // where u crosses a multiple of 1/8, i.e. at y = -1 + k / 4.
  const core::Scene scene = sceneOf(load("checker_wall.obj"));
  core::FanSpec fan;
  fan.angle_min = -0.4;
  fan.angle_max = 0.4;
  fan.samples = 2001;
  const core::ScanPattern pattern(fan, {std::atan2(0.1, 2.0)});
  const Sampled s = castAndSample(scene, pattern);
  core::MeasurementConfig config;
  config.intensity = true;
  core::MeasurementModel model(config);
  core::MeasuredScan measured;
  model.measure(scene, s.result, {0.5}, &measured, &s.surface);
  for (int i = 1; i < pattern.size(); ++i) {
    const double y0 = (s.result.range[i - 1] * pattern.directions()[i - 1]).y();
    const double y1 = (s.result.range[i] * pattern.directions()[i]).y();
    const bool edge_between = std::floor((y0 + 1) * 4) != std::floor((y1 + 1) * 4);
    const bool flips = (measured.intensities[i - 1] > 0) != (measured.intensities[i] > 0);
    EXPECT_EQ(flips, edge_between) << "between y " << y0 << " and " << y1;
  }
  // Intensity is reflectance x cos(incidence): the white cells give the cosine itself.
  for (int i = 0; i < pattern.size(); ++i) {
    if (measured.intensities[i] > 0) {
      EXPECT_FLOAT_EQ(measured.intensities[i], s.result.cos_incidence[i]);
    }
  }
}

TEST(SurfaceReflectance, VertexColoursAreInterpolatedAtTheHit) {
  const auto mesh = load("rgb_triangle.ply");
  ASSERT_NE(mesh->surface(), nullptr);
  ASSERT_EQ(mesh->surface()->colors.size(), 3u);
  const core::Scene scene = sceneOf(mesh);
  // Beams to (3, y, z); the barycentric coordinates of (y, z) on red (-1, -1), green (1, -1),
  // blue (0, 1), worked by hand: (0, 0) = 1/4 red + 1/4 green + 1/2 blue; (0.5, -0.5) = 1/8 red
  // + 5/8 green + 1/4 blue; (-0.25, 0.5) = 1/4 red + 0 green + 3/4 blue... checked: (-1, -1) / 4
  // + (0, 1) * 3 / 4 = (-0.25, 0.5).
  struct Case {
    double y, z;
    Vector3d rgb;
  };
  const std::vector<Case> cases = {{0.0, 0.0, {0.25, 0.25, 0.5}},
                                   {0.5, -0.5, {0.125, 0.625, 0.25}},
                                   {-0.25, 0.5, {0.25, 0.0, 0.75}}};
  for (const Case& c : cases) {
    core::FanSpec fan;
    const double azimuth = std::atan2(c.y, 3.0);
    fan.angle_min = azimuth;
    fan.angle_max = azimuth + 1e-3;
    fan.samples = 2;
    const core::ScanPattern pattern(fan, {std::atan2(c.z, std::hypot(3.0, c.y))});
    const Sampled s = castAndSample(scene, pattern);
    const double expected = 0.2126 * c.rgb.x() + 0.7152 * c.rgb.y() + 0.0722 * c.rgb.z();
    EXPECT_NEAR(s.surface.reflectance[0], expected, 1e-6) << "at y " << c.y << " z " << c.z;
    // A link whose reflectivity is set keeps it: the surface gives none.
    const Sampled fixed = castAndSample(scene, pattern, {1});
    EXPECT_TRUE(std::isnan(fixed.surface.reflectance[0]));
  }
}

TEST(SurfaceReflectance, VertexNormalsGiveTheIncidence) {
  const core::Scene scene = sceneOf(load("tilted_normals.obj"));
  const core::ScanPattern pattern = gridTowards(2.0, 0.9, 21, 5);
  const Sampled s = castAndSample(scene, pattern);
  const Vector3d normal = Vector3d(-1, 1, 0).normalized();
  for (int i = 0; i < pattern.size(); ++i) {
    ASSERT_TRUE(std::isfinite(s.result.range[i]));
    EXPECT_NEAR(s.surface.cos_incidence[i], std::abs(pattern.directions()[i].dot(normal)), 1e-6);
    // No colour: the link's reflectivity applies.
    EXPECT_TRUE(std::isnan(s.surface.reflectance[i]));
  }
}

TEST(SurfaceReflectance, TheUrdfMaterialColourAppliesWhereTheMeshGivesNone) {
  // A grey box (no mesh) straight ahead, and the vertex-coloured triangle given a red <material>
  // to the left: the box gets the material's luminance, the triangle keeps its vertex colours.
  const std::string urdf = R"(<robot name="r">
    <material name="grey"><color rgba="0.5 0.5 0.5 1"/></material>
    <link name="base">
      <visual><origin xyz="3 0 0"/><geometry><box size="0.2 1 1"/></geometry>
        <material name="grey"/></visual>
      <visual><origin xyz="0 0 0" rpy="0 0 1.5707963267948966"/>
        <geometry><mesh filename="rgb_triangle.ply"/></geometry>
        <material name="red"><color rgba="1 0 0 1"/></material></visual>
    </link></robot>)";
  const Sampled s = castAlongXAndY(urdf);
  ASSERT_TRUE(std::isfinite(s.result.range[0]));
  ASSERT_TRUE(std::isfinite(s.result.range[1]));
  EXPECT_NEAR(s.surface.reflectance[0], 0.5, 1e-12);
  // The triangle turned to face +y: the beam along +y meets its (y, z) = (0, 0) point.
  EXPECT_NEAR(s.surface.reflectance[1], 0.2126 * 0.25 + 0.7152 * 0.25 + 0.0722 * 0.5, 1e-6);
}

TEST(SurfaceReflectance, APlyWithoutMaterialsTakesTheUrdfColour) {
  // A PLY names no material unless its header has a material element; assimp still gives it a
  // white one of its own. Neither the file read by assimp (an ASCII cuboid, x from 3 to 4 ahead)
  // nor one read by the loader's reader of plain binary PLY (a wall at y = 3, both windings) may
  // stand for the surface's colour: their links' URDF materials give the reflectance.
  std::string wall =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nelement face 2\n"
      "property list uchar int vertex_indices\nend_header\n";
  const float corners[9] = {-1, 3, -1, 1, 3, -1, 0, 3, 1};
  wall.append(reinterpret_cast<const char*>(corners), sizeof corners);
  for (const std::int32_t order : {0x00020100, 0x00010200}) {  // (0, 1, 2) and (0, 2, 1)
    wall.push_back(3);
    for (int k = 0; k < 3; ++k) {
      const std::int32_t index = (order >> (8 * k)) & 0xff;
      wall.append(reinterpret_cast<const char*>(&index), 4);
    }
  }
  const std::string wall_path = testing::TempDir() + "plain_wall.ply";
  std::ofstream(wall_path, std::ios::binary) << wall;
  const std::string urdf = R"(<robot name="r">
    <link name="base">
      <visual><origin xyz="3 -1 -1.5"/>
        <geometry><mesh filename="../meshes/cuboid.ply"/></geometry>
        <material name="grey"><color rgba="0.5 0.5 0.5 1"/></material></visual>
      <visual><geometry><mesh filename="file://)" +
                           wall_path + R"("/></geometry>
        <material name="red"><color rgba="1 0 0 1"/></material></visual>
    </link></robot>)";
  const Sampled s = castAlongXAndY(urdf);
  ASSERT_NEAR(s.result.range[0], 3, 1e-12);
  ASSERT_NEAR(s.result.range[1], 3, 1e-12);
  EXPECT_NEAR(s.surface.reflectance[0], 0.5, 1e-12);
  EXPECT_NEAR(s.surface.reflectance[1], 0.2126, 1e-12);
}

TEST(SurfaceReflectance, BarycentricCoordinatesByCramersRule) {
  Vector3d w;
  ASSERT_TRUE(core::barycentricAt(Vector3d::Zero(), Vector3d::UnitX(), Vector3d(1, -1, -1),
                                  Vector3d(1, 1, -1), Vector3d(1, 0, 1), &w));
  EXPECT_NEAR(w[0], 0.25, 1e-15);
  EXPECT_NEAR(w[1], 0.25, 1e-15);
  EXPECT_NEAR(w[2], 0.5, 1e-15);
  // Parallel to the plane: none.
  EXPECT_FALSE(core::barycentricAt(Vector3d::Zero(), Vector3d::UnitY(), Vector3d(1, -1, -1),
                                   Vector3d(1, 1, -1), Vector3d(1, 0, 1), &w));
}

TEST(SurfaceReflectance, BadAttributesAreRefusedNamingTheArray) {
  core::SurfaceAttributes s;
  s.colors.resize(2);
  try {
    s.validate(3, 1);
    ADD_FAILURE() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("colors has 2 entries"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace laser_raycast
