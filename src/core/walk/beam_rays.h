// The rays a mesh walk (mesh_walk.cpp) tests a beam with: for the triangle tests in the sensor
// frame, for the box tests in the body's frame; from the sensor, or for a block of a rotating
// sweep (beams/column_motion.h) from the beam's own pose.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <optional>

#include "accel/wide_bvh.h"
#include "beams/beam_set.h"
#include "beams/column_motion.h"
#include "beams/placed_body.h"
#include "laser_raycast/core/aabb.h"
#include "laser_raycast/core/cast_config.h"
#include "laser_raycast/core/triangle.h"
#include "util/turn.h"

namespace laser_raycast {
namespace core {

template <TriangleMethod M>
class BeamRays {
 public:
  // bounds: the body's tree's, in its frame.
  BeamRays(const BeamSet& beams, const PlacedBody& active, const Aabb& bounds,
           const CastConfig& config)
      : beams_(beams),
        active_(active),
        bounds_(bounds),
        config_(config),
        motion_(active.motion),
        shift_(motion_ ? motion_->spread().shift : 0.0),
        // A sweep's block traces each column from its own origin, all within the shift.
        origin_(active.sensor_in_body, bounds, config.tmin, shift_) {}

  // The beam as a ray in the body's frame, for box tests: the same one for every box test of this
  // walk.
  WideBoxRay boxRay(int row, int col) const {
    return boxRayAlong(row, col, beams_.grid().rebuiltDirection(row, col));
  }
  // The beam at (row, col) along sensor-frame direction d as a ray in the body's frame for box
  // tests: from the sensor, or for a sweep's block turned with the beam's pose and from its
  // column's origin, the boxes grown by how far the column's beams leave from it (its row
  // classes', ColumnMotion::deviation: a calibrated Velodyne's lasers fire 35 us apart, each from
  // where the sensor is then), so that a column's beams share one. (origin_ holds every column's
  // origin, the box grown by the block's shift: a centimetre on every box makes a ray traced
  // through small boxes enter many more of them.)
  WideBoxRay boxRayAlong(int row, int col, const Eigen::Vector3d& d) const {
    if (!motion_) return WideBoxRay(origin_, turn(active_.body_from_sensor_rot, d));
    return WideBoxRay(boxOrigin(col), boxDirection(row, col, d));
  }
  // Its two parts: where the box tests of column col's beams start, and the direction of the beam
  // at (row, col) along sensor-frame d, in the body's frame.
  const WideBoxRay::Origin& boxOrigin(int col) const {
    return motion_ && shift_ != 0 ? originOf(motion_->refFromColumn(col)) : origin_;
  }
  Eigen::Vector3d boxDirection(int row, int col, const Eigen::Vector3d& d) const {
    return turn(active_.body_from_sensor_rot, motion_ ? motion_->direction(row, col, d) : d);
  }

  // Sub-ray s of the bundle's beam at (row, col) for the triangle tests and the box tests, as a
  // cast of its pattern tests it (a divergent beam's block has the sensor's pose at every column).
  PreparedRay<double, M> subRay(int s, int row, int col) const {
    if constexpr (M == TriangleMethod::kWatertight) {
      // A SubRayBundle's sub-ray, from the sensor's origin: its shear made once for the bundle.
      if (const BeamSet::SubShear* shears = beams_.subShears()) {
        return PreparedRay<double, M>(Eigen::Vector3d::Zero(), config_.tmin,
                                      config_.cull_backfaces, shears[s]);
      }
    }
    return rayAlong(row, col, beams_.subDirection(s));
  }
  WideBoxRay subBoxRay(int s, int row, int col) const {
    return boxRayAlong(row, col, beams_.subDirection(s));
  }
  // The beam at (row, col) along sensor-frame direction d for the triangle tests: from the
  // sensor, or for a sweep's block from the beam's pose, in the reference sensor frame.
  LASER_RAYCAST_HOT_INLINE PreparedRay<double, M> rayAlong(int row, int col,
                                                           const Eigen::Vector3d& d) const {
    if constexpr (M == TriangleMethod::kWatertight) {
      // Valid: the beam directions are finite unit vectors (a list's are checked when it is
      // validated, a pattern's when it is made), and a sweep casts only from poses that are
      // (ColumnPoses: isValidPose at both samples). Prepared from the beam's origin and direction
      // as from its ray, without the ray in between.
      using Prepared = PreparedRay<double, M>;
      if (!motion_) {
        return Prepared(Eigen::Vector3d::Zero(), config_.tmin, config_.cull_backfaces,
                        Prepared::shearOf(d));
      }
      Eigen::Vector3d origin, dir;
      motion_->beam(row, col, d, &origin, &dir);
      return Prepared(origin, config_.tmin, config_.cull_backfaces, Prepared::shearOf(dir));
    } else {
      Ray ray{Eigen::Vector3d::Zero(), d, config_.tmin};
      if (motion_) ray = motion_->ray(row, col, d, config_.tmin);
      return PreparedRay<double, M>(ray, config_.cull_backfaces);
    }
  }
  // The grid's beam for the triangle tests (rayAlong its direction; from the sensor, the grid's
  // prepared ray).
  PreparedRay<double, M> beamRay(int row, int col) const {
    if (!motion_) return beams_.grid().template sensorRay<M>(row, col);
    return rayAlong(row, col, beams_.grid().rebuiltDirection(row, col));
  }

 private:
  // Where the beams of a sweep's column start, for box tests in the body's frame (within the
  // block's deviation of its pose's origin): the same for every beam of the column, so the last
  // few are kept, by the pose's address (the block's poses stay where they are for the walk).
  const WideBoxRay::Origin& originOf(const ColumnMotion::Pose& pose) const {
    const auto key = reinterpret_cast<std::uintptr_t>(&pose);
    KeptOrigin& kept = origins_[(key / sizeof(ColumnMotion::Pose)) % origins_.size()];
    if (kept.pose != &pose) {
      kept.pose = &pose;
      const Eigen::Vector3d o =
          turn(active_.body_from_sensor_rot, pose.translation()) + active_.sensor_in_body;
      kept.origin.emplace(o, bounds_, config_.tmin, motion_->deviation());
    }
    return *kept.origin;
  }

  const BeamSet& beams_;
  const PlacedBody& active_;
  const Aabb& bounds_;
  const CastConfig& config_;
  const ColumnMotion* motion_;       // a sweep's block, or null
  const double shift_;               // the block's
  const WideBoxRay::Origin origin_;  // where the traced rays start, in the body's frame
  struct KeptOrigin {
    const ColumnMotion::Pose* pose = nullptr;
    std::optional<WideBoxRay::Origin> origin;
  };
  mutable std::array<KeptOrigin, 64> origins_;  // originOf()'s last ones
};

}  // namespace core
}  // namespace laser_raycast
