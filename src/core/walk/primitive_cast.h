// A URDF primitive (box, cylinder, sphere) against the open beams of a rectangle of the scan: four
// beams at a time through a conservative float test on the primitive's box, then the analytic
// test (primitives.h) for the beams let through.
#pragma once

#include <utility>
#include <vector>

#include "beams/beam_set.h"
#include "laser_raycast/core/cast_config.h"
#include "beams/placed_body.h"
#include "laser_raycast/core/scene.h"

namespace laser_raycast {
namespace core {

// Whether a walk should cast the primitive after everything else: it is large for its distance
// (its bounding sphere's radius beyond its nearest distance: a floor under the sensor, a wall
// beside it), so taken nearest first it would be tested with every beam before the nearer things in
// front of most of it. Only speed depends on it.
inline bool deferLargePrimitive(const PlacedBody& a) { return a.radius > a.view.near; }

// The primitives a walk deferred (deferLargePrimitive) with the beams it met them with; cast()
// casts them once the walk is done, nearest first, each over its beams if any is still open.
class DeferredPrimitives {
 public:
  void add(const PlacedBody& a, const BeamRect& rect) { items_.emplace_back(a, rect); }
  void cast(BeamSet& beams, const Scene& scene, const CastConfig& config);

 private:
  std::vector<std::pair<PlacedBody, BeamRect>> items_;
};

// Casts the open beams of rect against the primitive body active.index of scene.
void castPrimitive(BeamSet& beams, const Scene& scene, const PlacedBody& active,
                   const CastConfig& config, const BeamRect& rect);
// The same for one beam, by the exact test alone (for one beam the view and the pre-test cost more
// than they save). Needs only active's pose and sensor_in_body (placeSensorInBody, placed_body.h).
void castPrimitiveBeam(BeamSet& beams, const Scene& scene, const PlacedBody& active,
                       const CastConfig& config, int row, int col);

}  // namespace core
}  // namespace laser_raycast
