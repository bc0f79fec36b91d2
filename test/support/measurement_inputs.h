// Hand-made inputs for the measurement model tests: range limits, a scene of labelled bodies, and uniform
// cast results.
#pragma once

#include <vector>

#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/measurement_model.h"
#include "laser_raycast/core/scene.h"

namespace laser_raycast_test {

inline laser_raycast::core::MeasurementConfig measurementConfig(
    double range_min, double range_max,
    laser_raycast::core::MinRangePolicy policy = laser_raycast::core::MinRangePolicy::kNegInf) {
  laser_raycast::core::MeasurementConfig c;
  c.range_min = range_min;
  c.range_max = range_max;
  c.min_range_policy = policy;
  return c;
}

// A scene with three labels and one sphere body per label (label i on body i), plus a fourth body
// sharing label 1, for hand-made ScanResults.
inline laser_raycast::core::Scene labelledScene() {
  using namespace laser_raycast::core;
  Scene scene;
  scene.addFrame("world");
  for (const char* name : {"wall", "table", "robot"}) scene.addLabel(name);
  for (const int label : {0, 1, 2, 1}) {
    Body body;
    body.shape = Sphere{0.1};
    body.label = label;
    scene.addBody(body);
  }
  return scene;
}

// A ScanResult of n beams, all hitting body 0 at `range` unless changed, cos_incidence 1.
inline laser_raycast::core::ScanResult uniformResult(int n, double range,
                                                     bool with_incidence = false) {
  laser_raycast::core::ScanResult r;
  r.range.assign(n, range);
  r.body.assign(n, 0);
  r.triangle.assign(n, -1);
  if (with_incidence) r.cos_incidence.assign(n, 1.0);
  return r;
}

}  // namespace laser_raycast_test
