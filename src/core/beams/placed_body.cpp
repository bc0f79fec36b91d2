#include "beams/placed_body.h"

namespace laser_raycast {
namespace core {

PlacedBody placeBody(const Scene& scene, int index, const Eigen::Isometry3d& sensor_from_frame) {
  PlacedBody a;
  a.index = index;
  a.sensor_from_body = sensor_from_frame * scene.bodies()[index].frame_from_body;
  a.center = a.sensor_from_body * scene.sphereCenter(index);
  a.radius = scene.sphereRadius(index);
  return a;
}

void placeSensorInBody(PlacedBody* a) {
  a->body_from_sensor_rot = a->sensor_from_body.linear().transpose();
  a->sensor_in_body = -(a->body_from_sensor_rot * a->sensor_from_body.translation());
}

void viewPlacedBody(const Scene& scene, double angle_min, bool elevations, PlacedBody* a,
                    const Spread& spread) {
  const Eigen::Matrix3d& rot = a->sensor_from_body.linear();
  a->view = boxView(scene.boxCenter(a->index), scene.boxHalf(a->index), rot, rot.cwiseAbs(),
                    a->sensor_from_body.translation(), angle_min, elevations, spread);
  placeSensorInBody(a);
}

}  // namespace core
}  // namespace laser_raycast
