#include "laser_raycast/loader/scene_loader.h"

#include <malloc.h>
#include <urdf_model/model.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>

#include "import_process.h"
#include "laser_raycast/core/pose.h"
#include "mesh_file.h"
#include "stl_reader.h"
#include "urdf_parse.h"

namespace laser_raycast {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// The bytes the process has allocated and not freed: glibc's count over every arena, plus the
// blocks it maps on their own (every large vector).
std::size_t heapBytes() {
  const struct mallinfo2 info = mallinfo2();
  return info.uordblks + info.hblkhd;
}

std::string inQuotes(const std::string& s) { return "'" + s + "'"; }

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

void requirePositive(const char* what, const Eigen::Vector3d& v) {
  // Written so that NaN fails.
  if (!(v.allFinite() && (v.array() > 0).all())) {
    throw SceneLoadError(std::string(what) + " must be finite and > 0, got (" + vectorString(v) +
                         ")");
  }
}

// ---------------------------------------------------------------------------------------------------
// The stages of SceneLoader::addUrdf, in order: joints, fixed-joint merging, elements, shapes,
// commit. Only the last one touches the scene.

// Joints: every joint of the model, for forward kinematics. Throws SceneLoadError for an origin
// or axis that is not usable.
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

// Where each link sits: the scene frame it moves with and its pose there (names without prefix).
struct LinkFrames {
  std::vector<urdf::LinkConstSharedPtr> order;  // breadth first from the root
  std::map<std::string, std::pair<std::string, Eigen::Isometry3d>> frame_of;
};

// Fixed-joint merging: each link moves with the topmost link of its fixed chain. Breadth first
// from the root, so a parent is placed before its children.
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

// Reads (or finds in the cache) the mesh of a <mesh> element.
using MeshLoader = std::function<std::shared_ptr<const core::Mesh>(const urdf::Mesh&)>;

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

// A body waiting for the commit stage; frame and label without the prefix.
struct PendingBody {
  core::Shape shape;
  std::string frame, label;
  Eigen::Isometry3d frame_from_body;
  bool has_color = false;
  Eigen::Vector3d color = Eigen::Vector3d::Zero();
};

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

// The bodies of every link that is not ignored. A problem is an error, or under skip_bad_geometry
// a warning in *warnings and the element is left out.
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

// Commit: the bodies into the scene. Called only once every element has succeeded, so a failure
// leaves the scene untouched.
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

}  // namespace

MeshImportBounds MeshImportBounds::forFile(std::uintmax_t bytes, MeshReader reader) const {
  const double mb = static_cast<double>(bytes) / (1024 * 1024);
  const auto stepUp = [](double value, double step) { return std::ceil(value / step) * step; };
  MeshImportBounds out = *this;
  if (out.max_memory_mb == 0) {
    const double per_byte = reader == MeshReader::kStl ? kStlMemoryPerFileByte : kMemoryPerFileByte;
    out.max_memory_mb = std::max(kBaseMemoryMb, stepUp(per_byte * mb, kMemoryStepMb));
  }
  if (out.max_seconds == 0) {
    out.max_seconds = std::max(kBaseSeconds, stepUp(kSecondsPerFileMb * mb, kSecondsStep));
  }
  return out;
}

void MeshImportBounds::validate(const std::string& memory_name,
                                const std::string& time_name) const {
  std::ostringstream msg;
  // Written so that NaN fails.
  if (!(std::isfinite(max_memory_mb) && (max_memory_mb == 0 || max_memory_mb >= kMinMemoryMb))) {
    msg << memory_name << " must be 0 (from the file's size) or finite and >= " << kMinMemoryMb
        << " MB, got " << max_memory_mb;
  } else if (!(std::isfinite(max_seconds) && max_seconds >= 0)) {
    msg << time_name << " must be 0 (from the file's size) or finite and > 0 s, got "
        << max_seconds;
  } else {
    return;
  }
  throw std::invalid_argument(msg.str());
}

SceneLoader::SceneLoader(PackageResolver resolver) : resolver_(std::move(resolver)) {}
SceneLoader::~SceneLoader() = default;
SceneLoader::SceneLoader(SceneLoader&&) noexcept = default;
SceneLoader& SceneLoader::operator=(SceneLoader&&) noexcept = default;

std::shared_ptr<const core::Mesh> SceneLoader::loadMesh(const std::string& uri,
                                                        const std::string& base_dir,
                                                        const Eigen::Vector3d& scale,
                                                        const core::BvhConfig& bvh,
                                                        const MeshImportBounds& bounds) {
  last_bvh_seconds_ = 0;
  last_mesh_bytes_ = 0;
  std::string where = "mesh " + inQuotes(uri);
  try {
    requirePositive("the mesh scale", scale);
    try {
      bounds.validate();
    } catch (const std::invalid_argument& e) {
      throw SceneLoadError(e.what());
    }
    const std::string path = mesh_file::resolveUri(uri, base_dir, resolver_);
    if (path != uri) where += " (" + path + ")";

    std::error_code ec;
    const fs::file_status status = fs::status(path, ec);
    if (!fs::exists(status)) throw SceneLoadError("file not found");
    if (!fs::is_regular_file(status)) throw SceneLoadError("not a regular file");
    // The cache key: the same file reached through different URIs is read once.
    fs::path canonical = fs::weakly_canonical(path, ec);
    if (ec) canonical = fs::absolute(path, ec);
    const auto key =
        std::make_pair(canonical.string(), std::array<double, 3>{scale.x(), scale.y(), scale.z()});
    const auto cached = cache_.find(key);
    if (cached != cache_.end()) {
      if (std::shared_ptr<const core::Mesh> mesh = cached->second.lock()) return mesh;
      cache_.erase(cached);  // every holder let it go: read the file anew
    }

    if (!std::ifstream(path, std::ios::binary).good()) {
      throw SceneLoadError("file cannot be opened for reading");
    }
    const std::uintmax_t size = fs::file_size(path, ec);
    if (size == 0 && !ec) throw SceneLoadError("file is empty (0 bytes)");

    if (!importer_) importer_ = std::make_unique<import_process::MeshImporter>();
    const MeshReader reader = mesh_file::isStlPath(path) ? MeshReader::kStl : MeshReader::kAssimp;
    mesh_file::MeshData data =
        importer_->import(path, scale, bounds.forFile(ec ? 0 : size, reader));
    // What the mesh holds: its input, and what the build allocated and kept.
    const std::size_t input_bytes = data.vertices.capacity() * sizeof(data.vertices[0]) +
                                    data.triangles.capacity() * sizeof(data.triangles[0]);
    const std::size_t heap_before = heapBytes();
    const Clock::time_point start = Clock::now();
    std::shared_ptr<const core::Mesh> mesh;
    try {
      auto built = std::make_shared<core::Mesh>(std::move(data.vertices), std::move(data.triangles),
                                                bvh, scale);
      built->setSurface(std::move(data.surface));
      mesh = std::move(built);
    } catch (const std::invalid_argument& e) {
      throw SceneLoadError(e.what());
    }
    last_bvh_seconds_ = secondsSince(start);
    last_mesh_bytes_ = input_bytes + std::max<std::size_t>(heapBytes(), heap_before) - heap_before;
    cache_.emplace(key, mesh);
    ++meshes_built_;
    return mesh;
  } catch (const SceneLoadError& e) {
    rethrowWithContext(e, where);
  }
}

LoadedModel SceneLoader::addUrdfFile(const std::string& uri, const LoaderOptions& options,
                                     core::Scene* scene) {
  // A package:// URI is named with the file it resolved to, as a mesh is.
  std::string path = uri, source = uri;
  if (isPackageUri(uri)) {
    try {
      path = resolvePackageUri(uri, resolver_);
    } catch (const SceneLoadError& e) {
      throw SceneLoadError(uri + ": " + e.what());
    }
    source = uri + " (" + path + ")";
  }
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw SceneLoadError(source + ": a directory, not a URDF file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneLoadError(source + ": cannot open the URDF file for reading");
  std::ostringstream xml;
  xml << in.rdbuf();
  if (!in && !in.eof()) throw SceneLoadError(source + ": error reading the URDF file");
  std::string dir = fs::path(path).parent_path().string();
  if (dir.empty()) dir = ".";  // a bare file name: relative meshes are next to it
  return addUrdf(xml.str(), dir, source, options, scene);
}

LoadedModel SceneLoader::addUrdfString(const std::string& urdf_xml, const std::string& base_dir,
                                       const LoaderOptions& options, core::Scene* scene,
                                       const std::string& source) {
  return addUrdf(urdf_xml, base_dir, source, options, scene);
}

LoadedModel SceneLoader::addUrdf(const std::string& urdf_xml, const std::string& base_dir,
                                 const std::string& source, const LoaderOptions& options,
                                 core::Scene* scene) {
  const Clock::time_point start = Clock::now();
  try {
    options.bvh.validate();
    options.mesh_import.validate();
  } catch (const std::invalid_argument& e) {
    throw SceneLoadError(source + ": " + e.what());
  }

  DroppedElements dropped;
  const urdf::ModelInterfaceSharedPtr model = parseUrdf(urdf_xml, source, &dropped);
  const urdf::LinkConstSharedPtr root = model->getRoot();
  if (!root) throw SceneLoadError(source + ": malformed URDF (no root link)");
  const std::string& prefix = options.tf_prefix;

  LoadedModel out;
  out.name = model->getName();
  out.root_link = prefix + root->name;
  out.links = model->links_.size();
  out.joints = modelJoints(*model, prefix, source);
  const LinkFrames frames = mergeFixedJoints(*model, root);
  // urdfdom accepts a joint whose parent is its own child; that link hangs from nothing (found by
  // test/fuzz/fuzz_urdf_loader).
  for (const auto& [name, link] : model->links_) {
    if (!frames.frame_of.count(name)) {
      // Such a link holds itself (child_links): break the cycle, or the model leaks.
      for (const auto& entry : model->links_) entry.second->child_links.clear();
      throw SceneLoadError(source + ": link '" + name + "' is not connected to the root link '" +
                           root->name + "' (a joint that makes it its own parent, or a cycle)");
    }
  }
  for (const auto& [link, placement] : frames.frame_of) {
    out.link_frames[prefix + link] = {prefix + placement.first, placement.second};
  }

  double bvh_seconds = 0;
  const MeshLoader load_mesh = [&](const urdf::Mesh& mesh) {
    const auto loaded =
        loadMesh(mesh.filename, base_dir, Eigen::Vector3d(mesh.scale.x, mesh.scale.y, mesh.scale.z),
                 options.bvh, options.mesh_import);
    bvh_seconds += last_bvh_seconds_;
    if (last_mesh_bytes_ > 0) {
      out.mesh_triangles_built += loaded->triangles().size();
      out.mesh_bytes_built += last_mesh_bytes_;
    }
    return loaded;
  };
  commitBodies(linkBodies(frames, dropped, options, source, load_mesh, &out.warnings), prefix,
               source, scene, &out);
  out.bvh_build_seconds = bvh_seconds;
  out.load_seconds = std::max(0.0, secondsSince(start) - bvh_seconds);
  return out;
}

}  // namespace laser_raycast
