#include "laser_raycast/loader/kinematics.h"

#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/frames.hpp>
#include <kdl/jntarray.hpp>
#include <kdl/tree.hpp>
#include <map>
#include <stdexcept>
#include <vector>

// Forward kinematics with orocos KDL. kdl_parser would build the KDL tree from the URDF itself,
// but it links the ROS urdf library and through it roscpp (ldd libkdl_parser.so.1d), which the
// offline tools must not need; the loader has already parsed the joints, so the tree is built here
// from the ModelJoint list with KDL alone. Each link is placed by KDL's chain solver along the
// tree's chain from the root: KDL 1.5's tree solver (TreeFkSolverPos_recursive) reads the joint
// array at index 0 for fixed segments too, past its end when the model has no movable joint (an
// Eigen assertion failure with test/data/node_scene.urdf).

namespace laser_raycast {
namespace {

KDL::Frame toKdl(const Eigen::Isometry3d& pose) {
  const Eigen::Matrix3d r = pose.linear();
  const Eigen::Vector3d t = pose.translation();
  return KDL::Frame(KDL::Rotation(r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0),
                                  r(2, 1), r(2, 2)),
                    KDL::Vector(t.x(), t.y(), t.z()));
}

Eigen::Isometry3d fromKdl(const KDL::Frame& frame) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) pose.linear()(r, c) = frame.M(r, c);
    pose.translation()(r) = frame.p(r);
  }
  return pose;
}

bool moves(ModelJoint::Type type) {
  return type == ModelJoint::Type::kRevolute || type == ModelJoint::Type::kContinuous ||
         type == ModelJoint::Type::kPrismatic;
}

// The child link of joint as a KDL segment. KDL places a joint's axis in the parent link's frame,
// through the joint's origin, and the segment's tip at the origin: the URDF convention, in which
// the child is at origin * motion(value) (axis in the joint frame).
KDL::Segment toSegment(const ModelJoint& joint) {
  const KDL::Frame origin = toKdl(joint.parent_from_joint);
  const KDL::Vector axis = origin.M * KDL::Vector(joint.axis.x(), joint.axis.y(), joint.axis.z());
  KDL::Joint kdl_joint(joint.name, KDL::Joint::Fixed);  // fixed, floating, planar: do not move
  if (joint.type == ModelJoint::Type::kPrismatic) {
    kdl_joint = KDL::Joint(joint.name, origin.p, axis, KDL::Joint::TransAxis);
  } else if (moves(joint.type)) {
    kdl_joint = KDL::Joint(joint.name, origin.p, axis, KDL::Joint::RotAxis);
  }
  return KDL::Segment(joint.child_link, kdl_joint, origin);
}

// The model's links as a KDL tree, rooted at its root link. Breadth first, so that every parent is
// in the tree before its children.
KDL::Tree kdlTree(const LoadedModel& model) {
  std::multimap<std::string, const ModelJoint*> children;  // parent link -> joints
  for (const ModelJoint& joint : model.joints) children.emplace(joint.parent_link, &joint);
  KDL::Tree tree(model.root_link);
  std::vector<std::string> order{model.root_link};
  for (std::size_t i = 0; i < order.size(); ++i) {
    const auto range = children.equal_range(order[i]);
    for (auto it = range.first; it != range.second; ++it) {
      // A link that two joints claim (urdfdom accepts that) keeps its first place.
      if (tree.getSegment(it->second->child_link) != tree.getSegments().end()) continue;
      if (!tree.addSegment(toSegment(*it->second), order[i])) {
        throw std::logic_error("KDL refused link '" + it->second->child_link + "' of model '" +
                               model.name + "'");
      }
      order.push_back(it->second->child_link);
    }
  }
  return tree;
}

}  // namespace

std::map<std::string, Eigen::Isometry3d> forwardKinematics(
    const LoadedModel& model, const Eigen::Isometry3d& world_from_root,
    const std::map<std::string, double>& joint_values) {
  const KDL::Tree tree = kdlTree(model);
  std::map<std::string, Eigen::Isometry3d> poses;
  for (const auto& segment : tree.getSegments()) {
    const std::string& link = segment.first;
    KDL::Chain chain;
    if (!tree.getChain(model.root_link, link, chain)) {
      throw std::logic_error("KDL has no chain to link '" + link + "' of model '" + model.name +
                             "'");
    }
    // The chain's movable joints in order, as ChainFkSolverPos_recursive reads them.
    KDL::JntArray q(chain.getNrOfJoints());
    unsigned int next = 0;
    for (unsigned int i = 0; i < chain.getNrOfSegments(); ++i) {
      const KDL::Joint& joint = chain.getSegment(i).getJoint();
      if (joint.getType() == KDL::Joint::Fixed) continue;
      const auto value = joint_values.find(joint.getName());
      q(next++) = value == joint_values.end() ? 0.0 : value->second;
    }
    KDL::Frame root_from_link;
    if (KDL::ChainFkSolverPos_recursive(chain).JntToCart(q, root_from_link) < 0) {
      throw std::logic_error("KDL cannot place link '" + link + "' of model '" + model.name + "'");
    }
    poses[link] = world_from_root * fromKdl(root_from_link);
  }
  return poses;
}

core::FramePoses framePosesFromLinks(const core::Scene& scene,
                                     const std::map<std::string, Eigen::Isometry3d>& link_poses) {
  core::FramePoses poses;
  core::resolveFramePoses(
      scene,
      [&](const std::string& frame, Eigen::Isometry3d& pose) {
        const auto it = link_poses.find(frame);
        if (it == link_poses.end()) return false;
        pose = it->second;
        return true;
      },
      &poses);
  return poses;
}

Eigen::Isometry3d poseFromXyzRpy(double x, double y, double z, double roll, double pitch,
                                 double yaw) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                   Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                   Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                      .toRotationMatrix();
  pose.translation() = Eigen::Vector3d(x, y, z);
  return pose;
}

}  // namespace laser_raycast
