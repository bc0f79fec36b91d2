// The scene: bodies (a shared mesh or an analytic primitive) attached to named frames. Built once;
// the per-scan state (where each frame is) lives in FramePoses, so a Scene is immutable while
// casting.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "laser_raycast/core/mesh.h"
#include "laser_raycast/core/primitives.h"

namespace laser_raycast {
namespace core {

using Shape = std::variant<Box, Cylinder, Sphere, std::shared_ptr<const Mesh>>;

struct Body {
  Shape shape;
  int frame = 0;  // index into Scene::frames(): the frame whose pose moves this body
  int label =
      0;  // index into Scene::labels(): what a hit on this body reports (e.g. its URDF link)
  Eigen::Isometry3d frame_from_body =
      Eigen::Isometry3d::Identity();  // the body's pose in its frame
  // Its colour (e.g. the URDF <material>'s), RGB in [0, 1], for the reflectance of hits on it
  // where its mesh gives none (surface_reflectance.h).
  bool has_color = false;
  Eigen::Vector3d color = Eigen::Vector3d::Zero();
};

class Scene {
 public:
  Scene();

  // Frames and labels are looked up by name; adding an existing name returns its index.
  int addFrame(const std::string& name);
  int addLabel(const std::string& name);
  // Throws std::invalid_argument if the frame or label index is out of range, the pose is not a
  // finite rigid transform, a primitive size is not positive, or the mesh is null. Returns the
  // body's index.
  int addBody(Body body);

  const std::vector<std::string>& frames() const { return frames_; }
  const std::vector<std::string>& labels() const { return labels_; }
  const std::vector<Body>& bodies() const { return bodies_; }
  // A sphere containing the body, in the body's frame.
  const Eigen::Vector3d& sphereCenter(int body) const { return sphere_centers_[body]; }
  double sphereRadius(int body) const { return sphere_radii_[body]; }
  // A box containing the body, in the body's frame: centre and half extents (a mesh's bounds, a
  // primitive's own box).
  const Eigen::Vector3d& boxCenter(int body) const { return box_centers_[body]; }
  const Eigen::Vector3d& boxHalf(int body) const { return box_halves_[body]; }
  std::size_t triangleCount() const;
  // Changes on every modification and is unique across scenes, so a cached result can tell whether
  // it was computed from this scene as it is now.
  std::uint64_t version() const { return version_; }

 private:
  std::uint64_t version_;
  std::vector<std::string> frames_;
  std::vector<std::string> labels_;
  std::vector<Body> bodies_;
  std::vector<Eigen::Vector3d> sphere_centers_;
  std::vector<double> sphere_radii_;
  std::vector<Eigen::Vector3d> box_centers_, box_halves_;
};

// Where each frame of a scene is this scan, in one common (fixed) frame.
struct FramePoses {
  std::vector<Eigen::Isometry3d> pose;
  std::vector<char> valid;  // 0: unknown this scan; the frame's bodies are skipped

  // Every frame at the identity, valid.
  static FramePoses identity(const Scene& scene);
};

// Fills pose with the frame's pose in the common frame and returns true, or returns false if it is
// unknown (the ROS node asks TF; tests pass a lambda).
using PoseLookup = std::function<bool(const std::string& frame, Eigen::Isometry3d& pose)>;

// Asks lookup for every frame. A frame is invalid if lookup returns false or gives a pose that is
// not a finite rigid transform. Returns the number of invalid frames.
int resolveFramePoses(const Scene& scene, const PoseLookup& lookup, FramePoses* poses);

}  // namespace core
}  // namespace laser_raycast
