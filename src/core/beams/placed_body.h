// A body placed for one scan: its pose relative to the sensor and what the walks cull it by. The
// walks share it (frame, mesh and slice walks, the primitives' cast), so it lives below them.
#pragma once

#include <Eigen/Geometry>

#include "beams/beam_window.h"
#include "laser_raycast/core/scene.h"

namespace laser_raycast {
namespace core {

class ColumnMotion;
struct ScanPlane;

struct PlacedBody {
  int index;
  Eigen::Isometry3d sensor_from_body;
  Eigen::Matrix3d body_from_sensor_rot;  // rotates sensor-frame directions into the body frame
  Eigen::Vector3d sensor_in_body;        // the sensor origin in the body frame
  Eigen::Vector3d center;                // bounding sphere centre, sensor frame
  double radius;
  View view;  // how the body's box looks from the sensor: nearest distance, windows
  // Planar fans: the scan plane in the body's frame's coordinates (slicer.h), and where the
  // body is in that frame: a mesh is cut there, as a kept slice of the frame is.
  const ScanPlane* plane = nullptr;
  Eigen::Isometry3d frame_from_body = Eigen::Isometry3d::Identity();
  // A block of a rotating sweep: each column's beams leave from the column's own pose
  // (column_motion.h); the view above is widened by its spread. Null for a scan from one pose.
  const ColumnMotion* motion = nullptr;
};

// A body placed in steps, so that a walk can cull by the cheap one first: its pose relative to the
// sensor and its bounding sphere there (placeBody); then the sensor in the body's frame (what the
// exact tests need, placeSensorInBody); then how its box looks from the sensor (with elevation
// windows if `elevations`, widened by a sweep block's spread; viewPlacedBody does both).
PlacedBody placeBody(const Scene& scene, int index, const Eigen::Isometry3d& sensor_from_frame);
void placeSensorInBody(PlacedBody* a);
void viewPlacedBody(const Scene& scene, double angle_min, bool elevations, PlacedBody* a,
                    const Spread& spread = Spread());

}  // namespace core
}  // namespace laser_raycast
