#include "laser_raycast/loader/scene_loader.h"

#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <mutex>
#include <regex>
#include <set>
#include <sstream>

#include "laser_raycast/core/pose.h"
#include "mesh_file.h"

namespace laser_raycast {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

std::string inQuotes(const std::string& s) { return "'" + s + "'"; }

std::string vectorString(const Eigen::Vector3d& v) {
  std::ostringstream out;
  out << v.x() << " " << v.y() << " " << v.z();
  return out.str();
}

// ---------------------------------------------------------------------------------------------------
// URDF parsing

// Collects what urdfdom reports through console_bridge while it parses: that is the only place
// it says why a parse failed, and it drops a <visual> or <collision> it cannot parse (a "nan" size,
// an empty <geometry>) without failing the parse. Errors are kept; the rest goes on to the
// previous handler.
class UrdfParseLog : public console_bridge::OutputHandler {
 public:
  UrdfParseLog()
      : lock_(mutex()),
        previous_(console_bridge::getOutputHandler()),
        previous_level_(console_bridge::getLogLevel()) {
    console_bridge::useOutputHandler(this);
    // Errors must reach us even if the application silenced console_bridge.
    if (previous_level_ > console_bridge::CONSOLE_BRIDGE_LOG_ERROR) {
      console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_ERROR);
    }
  }
  ~UrdfParseLog() override {
    console_bridge::setLogLevel(previous_level_);
    console_bridge::restorePreviousOutputHandler();
  }
  UrdfParseLog(const UrdfParseLog&) = delete;
  UrdfParseLog& operator=(const UrdfParseLog&) = delete;

  void log(const std::string& text, console_bridge::LogLevel level, const char* filename,
           int line) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) {
      errors_.push_back(text);
    } else if (previous_) {
      previous_->log(text, level, filename, line);
    }
  }
  void forward(const std::string& text) const {
    if (previous_ && previous_level_ <= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) {
      previous_->log(text, console_bridge::CONSOLE_BRIDGE_LOG_ERROR, __FILE__, __LINE__);
    }
  }
  const std::vector<std::string>& errors() const { return errors_; }

 private:
  // One capture at a time: console_bridge keeps a single previous handler.
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  std::lock_guard<std::mutex> lock_;
  console_bridge::OutputHandler* previous_;
  console_bridge::LogLevel previous_level_;
  std::vector<std::string> errors_;
};

// The <visual> or <collision> elements urdfdom dropped: (link, "visual"/"collision") -> reasons.
using DroppedElements = std::map<std::pair<std::string, std::string>, std::vector<std::string>>;

urdf::ModelInterfaceSharedPtr parseUrdf(const std::string& xml, const std::string& source,
                                        DroppedElements* dropped) {
  urdf::ModelInterfaceSharedPtr model;
  std::vector<std::string> errors;
  UrdfParseLog log;
  try {
    model = urdf::parseURDF(xml);
  } catch (const std::exception& e) {
    model.reset();
    errors.push_back(e.what());
  }
  // urdfdom logs the reasons first, then "Could not parse visual element for Link [name]".
  static const std::regex kDropped(
      "Could not parse (visual|collision) element for Link \\[(.*)\\]");
  std::vector<std::string> reasons;
  for (const std::string& text : log.errors()) {
    std::smatch match;
    if (model && std::regex_search(text, match, kDropped)) {
      std::string why;
      for (const std::string& reason : reasons) why += (why.empty() ? "" : "; ") + reason;
      (*dropped)[{match[2].str(), match[1].str()}].push_back(why.empty() ? text : why);
      reasons.clear();
    } else {
      reasons.push_back(text);
    }
  }
  if (!model) {
    errors.insert(errors.begin(), reasons.begin(), reasons.end());
    std::string msg = source + ": malformed URDF (urdfdom cannot parse it)";
    for (const std::string& e : errors) msg += "; " + e;
    throw SceneLoadError(msg);
  }
  for (const std::string& text : reasons) log.forward(text);  // not ours to judge
  return model;
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

}  // namespace

SceneLoader::SceneLoader(PackageResolver resolver) : resolver_(std::move(resolver)) {}

std::shared_ptr<const core::Mesh> SceneLoader::loadMesh(const std::string& uri,
                                                        const std::string& base_dir,
                                                        const Eigen::Vector3d& scale,
                                                        const core::BvhConfig& bvh) {
  last_bvh_seconds_ = 0;
  std::string where = "mesh " + inQuotes(uri);
  try {
    requirePositive("the mesh scale", scale);
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
    if (cached != cache_.end()) return cached->second;

    if (!std::ifstream(path, std::ios::binary).good()) {
      throw SceneLoadError("file cannot be opened for reading");
    }
    if (fs::file_size(path, ec) == 0 && !ec) throw SceneLoadError("file is empty (0 bytes)");

    mesh_file::MeshData data = mesh_file::readMeshFile(path, scale);
    const Clock::time_point start = Clock::now();
    std::shared_ptr<const core::Mesh> mesh;
    try {
      mesh = std::make_shared<const core::Mesh>(std::move(data.vertices), std::move(data.triangles),
                                                bvh);
    } catch (const std::invalid_argument& e) {
      throw SceneLoadError(e.what());
    }
    last_bvh_seconds_ = secondsSince(start);
    cache_.emplace(key, mesh);
    return mesh;
  } catch (const SceneLoadError& e) {
    throw SceneLoadError(where + ": " + e.what());
  }
}

LoadedModel SceneLoader::addUrdfFile(const std::string& path, const LoaderOptions& options,
                                     core::Scene* scene) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw SceneLoadError(path + ": a directory, not a URDF file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneLoadError(path + ": cannot open the URDF file for reading");
  std::ostringstream xml;
  xml << in.rdbuf();
  if (!in && !in.eof()) throw SceneLoadError(path + ": error reading the URDF file");
  std::string dir = fs::path(path).parent_path().string();
  if (dir.empty()) dir = ".";  // a bare file name: relative meshes are next to it
  return addUrdf(xml.str(), dir, path, options, scene);
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

  for (const auto& [name, joint] : model->joints_) {
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
    out.joints.push_back(j);
  }

  // Fixed-joint merging: each link moves with the topmost link of its fixed chain. Breadth first
  // from the root, so a parent is placed before its children.
  std::map<std::string, std::pair<std::string, Eigen::Isometry3d>> frame_of;  // without prefix
  frame_of[root->name] = {root->name, Eigen::Isometry3d::Identity()};
  std::vector<urdf::LinkConstSharedPtr> order{root};
  for (std::size_t i = 0; i < order.size(); ++i) {
    const urdf::LinkConstSharedPtr& link = order[i];
    const auto& [frame, frame_from_link] = frame_of.at(link->name);
    for (const urdf::JointSharedPtr& joint : link->child_joints) {
      const urdf::LinkConstSharedPtr child = model->getLink(joint->child_link_name);
      if (!child || frame_of.count(child->name)) continue;
      if (joint->type == urdf::Joint::FIXED) {
        frame_of[child->name] = {
            frame, frame_from_link * toIsometry(joint->parent_to_joint_origin_transform)};
      } else {
        frame_of[child->name] = {child->name, Eigen::Isometry3d::Identity()};
      }
      order.push_back(child);
    }
  }
  for (const auto& [link, placement] : frame_of) {
    out.link_frames[prefix + link] = {prefix + placement.first, placement.second};
  }

  // Bodies are collected first and added at the end, so a failure leaves the scene untouched.
  struct PendingBody {
    core::Shape shape;
    std::string frame, label;
    Eigen::Isometry3d frame_from_body;
  };
  std::vector<PendingBody> pending;
  const std::set<std::string> ignored(options.ignore_links.begin(), options.ignore_links.end());
  double bvh_seconds = 0;

  for (const urdf::LinkConstSharedPtr& link : order) {
    if (ignored.count(link->name)) continue;
    // The elements to load, and those urdfdom dropped among them.
    std::vector<Element> elements;
    const bool use_visual = options.geometry == GeometrySource::kVisual &&
                            (!link->visual_array.empty() || dropped.count({link->name, "visual"}));
    if (use_visual) {
      for (const urdf::VisualSharedPtr& v : link->visual_array) {
        elements.push_back({"visual", elements.size() + 1, v->name, v->origin, v->geometry});
      }
    } else {
      for (const urdf::CollisionSharedPtr& c : link->collision_array) {
        elements.push_back({"collision", elements.size() + 1, c->name, c->origin, c->geometry});
      }
    }
    const auto report = [&](const std::string& problem) {
      if (!options.skip_bad_geometry) throw SceneLoadError(problem);
      out.warnings.push_back(problem);
    };
    // urdfdom stops reading a link at the first element it cannot parse: a bad <visual> takes the
    // link's later visuals and all its collisions with it, a bad <collision> its later collisions.
    const auto reportDropped = [&](const char* dropped_kind, const char* also_lost) {
      const auto drop = dropped.find({link->name, dropped_kind});
      if (drop == dropped.end()) return;
      for (const std::string& reason : drop->second) {
        report(source + ": link " + inQuotes(link->name) + ": urdfdom could not parse a <" +
               dropped_kind + "> (" + reason + ") and dropped it with " + also_lost);
      }
    };
    reportDropped("visual", "the link's later <visual> and all its <collision> elements");
    if (!use_visual) reportDropped("collision", "the link's later <collision> elements");

    const auto& [frame, frame_from_link] = frame_of.at(link->name);
    for (const Element& element : elements) {
      try {
        if (!element.geometry) throw SceneLoadError("no geometry");
        const Eigen::Isometry3d link_from_body = toIsometry(element.origin);
        if (!core::isValidPose(link_from_body)) {
          throw SceneLoadError("its origin is not a finite rigid transform");
        }
        core::Shape shape;
        try {
          switch (element.geometry->type) {
            case urdf::Geometry::BOX: {
              const auto& box = static_cast<const urdf::Box&>(*element.geometry);
              const core::Box b{Eigen::Vector3d(box.dim.x, box.dim.y, box.dim.z)};
              core::validate(b);
              shape = b;
              break;
            }
            case urdf::Geometry::CYLINDER: {
              const auto& cylinder = static_cast<const urdf::Cylinder&>(*element.geometry);
              const core::Cylinder c{cylinder.radius, cylinder.length};
              core::validate(c);
              shape = c;
              break;
            }
            case urdf::Geometry::SPHERE: {
              const core::Sphere s{static_cast<const urdf::Sphere&>(*element.geometry).radius};
              core::validate(s);
              shape = s;
              break;
            }
            case urdf::Geometry::MESH: {
              const auto& mesh = static_cast<const urdf::Mesh&>(*element.geometry);
              shape =
                  loadMesh(mesh.filename, base_dir,
                           Eigen::Vector3d(mesh.scale.x, mesh.scale.y, mesh.scale.z), options.bvh);
              bvh_seconds += last_bvh_seconds_;
              break;
            }
            default:
              throw SceneLoadError("unknown geometry type " +
                                   std::to_string(static_cast<int>(element.geometry->type)));
          }
        } catch (const std::invalid_argument& e) {
          throw SceneLoadError(e.what());
        }
        pending.push_back({shape, frame, link->name, frame_from_link * link_from_body});
      } catch (const SceneLoadError& e) {
        report(describe(source, link->name, element) + ": " + e.what());
      }
    }
  }

  for (PendingBody& body : pending) {
    core::Body b;
    b.shape = std::move(body.shape);
    b.frame = scene->addFrame(prefix + body.frame);
    b.label = scene->addLabel(prefix + body.label);
    b.frame_from_body = body.frame_from_body;
    try {
      scene->addBody(std::move(b));
    } catch (const std::invalid_argument& e) {
      // Everything addBody checks was checked above; this would be a loader bug.
      throw SceneLoadError(source + ": link " + inQuotes(body.label) + ": " + e.what());
    }
    ++out.bodies;
    if (const auto* mesh =
            std::get_if<std::shared_ptr<const core::Mesh>>(&scene->bodies().back().shape)) {
      out.triangles += (*mesh)->triangles().size();
    }
  }
  out.bvh_build_seconds = bvh_seconds;
  out.load_seconds = std::max(0.0, secondsSince(start) - bvh_seconds);
  return out;
}

}  // namespace laser_raycast
