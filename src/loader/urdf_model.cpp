#include "urdf_model.h"

#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "laser_raycast/core/pose.h"

namespace laser_raycast {
namespace urdf_model {
namespace {

std::string vectorString(const Eigen::Vector3d& v) {
  std::ostringstream out;
  out << v.x() << " " << v.y() << " " << v.z();
  return out.str();
}

Eigen::Isometry3d toIsometry(const urdf::Pose& pose) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() << pose.position.x, pose.position.y, pose.position.z;
  // A zero quaternion normalises to NaN, which isValidPose rejects.
  t.linear() =
      Eigen::Quaterniond(pose.rotation.w, pose.rotation.x, pose.rotation.y, pose.rotation.z)
          .normalized()
          .toRotationMatrix();
  return t;
}

ModelJoint::Type jointType(int type) {
  switch (type) {
    case urdf::Joint::FIXED:
      return ModelJoint::Type::kFixed;
    case urdf::Joint::REVOLUTE:
      return ModelJoint::Type::kRevolute;
    case urdf::Joint::CONTINUOUS:
      return ModelJoint::Type::kContinuous;
    case urdf::Joint::PRISMATIC:
      return ModelJoint::Type::kPrismatic;
    default:
      return ModelJoint::Type::kOther;
  }
}

// One <visual> or <collision> of a link.
struct Element {
  const char* kind;   // "visual" or "collision"
  std::size_t index;  // 1-based among the link's elements of that kind
  std::string name;
  urdf::Pose origin;
  urdf::GeometrySharedPtr geometry;
  urdf::MaterialSharedPtr material = nullptr;  // a visual's <material>, if any
};

std::string describe(const std::string& source, const std::string& link, const Element& e) {
  std::ostringstream out;
  out << source << ": link " << inQuotes(link) << ", " << e.kind << " #" << e.index;
  if (!e.name.empty()) out << " (" << e.name << ")";
  return out.str();
}
// The elements of one link that become bodies, and a problem for each one urdfdom dropped.
struct LinkElements {
  std::vector<Element> elements;
  std::vector<std::string> dropped;
};

// Elements: a link's visuals (or, if it has none, its collisions) for kVisual, its collisions for
// kCollision.
LinkElements linkElements(const urdf::Link& link, GeometrySource geometry,
                          const DroppedElements& dropped, const std::string& source) {
  LinkElements out;
  const bool use_visual = geometry == GeometrySource::kVisual &&
                          (!link.visual_array.empty() || dropped.count({link.name, "visual"}));
  if (use_visual) {
    for (const urdf::VisualSharedPtr& v : link.visual_array) {
      out.elements.push_back(
          {"visual", out.elements.size() + 1, v->name, v->origin, v->geometry, v->material});
    }
  } else {
    for (const urdf::CollisionSharedPtr& c : link.collision_array) {
      out.elements.push_back(
          {"collision", out.elements.size() + 1, c->name, c->origin, c->geometry});
    }
  }
  // urdfdom stops reading a link at the first element it cannot parse: a bad <visual> takes the
  // link's later visuals and all its collisions with it, a bad <collision> its later collisions.
  const auto addDropped = [&](const char* dropped_kind, const char* also_lost) {
    const auto drop = dropped.find({link.name, dropped_kind});
    if (drop == dropped.end()) return;
    for (const std::string& reason : drop->second) {
      out.dropped.push_back(source + ": link " + inQuotes(link.name) +
                            ": urdfdom could not parse a <" + dropped_kind + "> (" + reason +
                            ") and dropped it with " + also_lost);
    }
  };
  addDropped("visual", "the link's later <visual> and all its <collision> elements");
  if (!use_visual) addDropped("collision", "the link's later <collision> elements");
  return out;
}
// Shapes: a URDF geometry as a core shape, primitives validated. Throws SceneLoadError with the
// problem.
core::Shape shapeOf(const urdf::Geometry& geometry, const MeshLoader& load_mesh) {
  try {
    switch (geometry.type) {
      case urdf::Geometry::BOX: {
        const auto& box = static_cast<const urdf::Box&>(geometry);
        const core::Box b{Eigen::Vector3d(box.dim.x, box.dim.y, box.dim.z)};
        core::validate(b);
        return b;
      }
      case urdf::Geometry::CYLINDER: {
        const auto& cylinder = static_cast<const urdf::Cylinder&>(geometry);
        const core::Cylinder c{cylinder.radius, cylinder.length};
        core::validate(c);
        return c;
      }
      case urdf::Geometry::SPHERE: {
        const core::Sphere s{static_cast<const urdf::Sphere&>(geometry).radius};
        core::validate(s);
        return s;
      }
      case urdf::Geometry::MESH:
        return load_mesh(static_cast<const urdf::Mesh&>(geometry));
      default:
        throw SceneLoadError("unknown geometry type " +
                             std::to_string(static_cast<int>(geometry.type)));
    }
  } catch (const std::invalid_argument& e) {
    throw SceneLoadError(e.what());
  }
}
// The colour of a visual's <material>: its <color>'s RGB. A material with only a <texture> has
// none (urdfdom reports an absent <color> as opaque black; the texture is not read).
bool materialColor(const urdf::Material* material, Eigen::Vector3d* color) {
  if (!material) return false;
  const urdf::Color& c = material->color;
  const bool black = c.r == 0 && c.g == 0 && c.b == 0;
  if (black && !material->texture_filename.empty()) return false;
  *color = Eigen::Vector3d(c.r, c.g, c.b);
  if (!color->allFinite()) return false;
  *color = color->cwiseMax(0.0).cwiseMin(1.0);
  return true;
}

// One element of a link as a body on the link's merged frame. Throws SceneLoadError with the
// problem.
PendingBody elementBody(const Element& element, const std::string& link,
                        const std::pair<std::string, Eigen::Isometry3d>& placement,
                        const MeshLoader& load_mesh) {
  if (!element.geometry) throw SceneLoadError("no geometry");
  const Eigen::Isometry3d link_from_body = toIsometry(element.origin);
  if (!core::isValidPose(link_from_body)) {
    throw SceneLoadError("its origin is not a finite rigid transform");
  }
  PendingBody body{shapeOf(*element.geometry, load_mesh), placement.first, link,
                   placement.second * link_from_body};
  body.has_color = materialColor(element.material.get(), &body.color);
  return body;
}
}  // namespace

std::string inQuotes(const std::string& s) { return "'" + s + "'"; }

void requirePositive(const char* what, const Eigen::Vector3d& v) {
  // Written so that NaN fails.
  if (!(v.allFinite() && (v.array() > 0).all())) {
    throw SceneLoadError(std::string(what) + " must be finite and > 0, got (" + vectorString(v) +
                         ")");
  }
}

std::vector<ModelJoint> modelJoints(const urdf::ModelInterface& model, const std::string& prefix,
                                    const std::string& source) {
  std::vector<ModelJoint> joints;
  for (const auto& [name, joint] : model.joints_) {
    ModelJoint j;
    j.name = name;
    j.type = jointType(joint->type);
    j.parent_link = prefix + joint->parent_link_name;
    j.child_link = prefix + joint->child_link_name;
    j.parent_from_joint = toIsometry(joint->parent_to_joint_origin_transform);
    if (!core::isValidPose(j.parent_from_joint)) {
      throw SceneLoadError(source + ": malformed URDF: joint " + inQuotes(name) +
                           " has an origin that is not a finite rigid transform");
    }
    const Eigen::Vector3d axis(joint->axis.x, joint->axis.y, joint->axis.z);
    const bool needs_axis =
        j.type == ModelJoint::Type::kRevolute || j.type == ModelJoint::Type::kContinuous ||
        j.type == ModelJoint::Type::kPrismatic || joint->type == urdf::Joint::PLANAR;
    if (needs_axis) {
      // Written so that NaN fails.
      if (!(axis.allFinite() && axis.norm() > 0)) {
        throw SceneLoadError(source + ": malformed URDF: joint " + inQuotes(name) + " has axis (" +
                             vectorString(axis) + "), which cannot be normalised");
      }
      j.axis = axis.normalized();
    }
    joints.push_back(j);
  }
  return joints;
}

LinkFrames mergeFixedJoints(const urdf::ModelInterface& model,
                            const urdf::LinkConstSharedPtr& root) {
  LinkFrames out;
  out.frame_of[root->name] = {root->name, Eigen::Isometry3d::Identity()};
  out.order.push_back(root);
  for (std::size_t i = 0; i < out.order.size(); ++i) {
    const urdf::LinkConstSharedPtr link = out.order[i];
    const auto [frame, frame_from_link] = out.frame_of.at(link->name);
    for (const urdf::JointSharedPtr& joint : link->child_joints) {
      const urdf::LinkConstSharedPtr child = model.getLink(joint->child_link_name);
      if (!child || out.frame_of.count(child->name)) continue;
      if (joint->type == urdf::Joint::FIXED) {
        out.frame_of[child->name] = {
            frame, frame_from_link * toIsometry(joint->parent_to_joint_origin_transform)};
      } else {
        out.frame_of[child->name] = {child->name, Eigen::Isometry3d::Identity()};
      }
      out.order.push_back(child);
    }
  }
  return out;
}

std::vector<PendingBody> linkBodies(const LinkFrames& frames, const DroppedElements& dropped,
                                    const LoaderOptions& options, const std::string& source,
                                    const MeshLoader& load_mesh,
                                    std::vector<std::string>* warnings) {
  const auto report = [&](const std::string& problem) {
    if (!options.skip_bad_geometry) throw SceneLoadError(problem);
    warnings->push_back(problem);
  };
  const std::set<std::string> ignored(options.ignore_links.begin(), options.ignore_links.end());
  std::vector<PendingBody> pending;
  for (const urdf::LinkConstSharedPtr& link : frames.order) {
    if (ignored.count(link->name)) continue;
    const LinkElements selected = linkElements(*link, options.geometry, dropped, source);
    for (const std::string& problem : selected.dropped) report(problem);
    for (const Element& element : selected.elements) {
      try {
        pending.push_back(
            elementBody(element, link->name, frames.frame_of.at(link->name), load_mesh));
      } catch (const SceneLoadError& e) {
        const std::string where = describe(source, link->name, element);
        if (!options.skip_bad_geometry) rethrowWithContext(e, where);
        warnings->push_back(where + ": " + e.what());
      }
    }
  }
  return pending;
}

void commitBodies(std::vector<PendingBody> pending, const std::string& prefix,
                  const std::string& source, core::Scene* scene, LoadedModel* out) {
  for (PendingBody& body : pending) {
    core::Body b;
    b.shape = std::move(body.shape);
    b.frame = scene->addFrame(prefix + body.frame);
    b.label = scene->addLabel(prefix + body.label);
    b.frame_from_body = body.frame_from_body;
    b.has_color = body.has_color;
    b.color = body.color;
    try {
      scene->addBody(std::move(b));
    } catch (const std::invalid_argument& e) {
      // Everything addBody checks was checked above; this would be a loader bug.
      throw SceneLoadError(source + ": link " + inQuotes(body.label) + ": " + e.what());
    }
    ++out->bodies;
    if (const auto* mesh =
            std::get_if<std::shared_ptr<const core::Mesh>>(&scene->bodies().back().shape)) {
      out->triangles += (*mesh)->triangles().size();
    }
  }
}
}  // namespace urdf_model
}  // namespace laser_raycast
