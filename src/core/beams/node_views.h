// How the four children of a wide BVH node look from the sensor, computed together in float with
// SSE2 (the x86-64 baseline): each child's nearest distance, and the azimuth and elevation windows
// its box can be seen in. Everything is conservative: every rounding and approximation widens a
// window and lowers a distance, so a beam whose exact ray enters a child's box is always inside the
// child's windows (the exact triangle tests at the leaves decide). The windows only decide how
// much work is done.
#pragma once

#include <emmintrin.h>

#include <Eigen/Geometry>

#include "accel/wide_bvh.h"
#include "beams/beam_window.h"
#include "util/float_rounding.h"

namespace laser_raycast {
namespace core {

// A sweep block's Spread (beam_window.h) for the views of four boxes at once: rounded outwards to
// float, and how a box's azimuth window is widened by it (NodeViews, SliceViews).
struct SpreadPs {
  explicit SpreadPs(const Spread& spread);

  // A window's half width widened by the spread's azimuths.
  __m128 widenHalf(__m128 half) const { return any ? _mm_add_ps(half, azimuth) : half; }
  // Which windows stay limited in azimuth (none when the spread may turn to every azimuth).
  __m128 keepLimited(__m128 limited) const { return every_azimuth ? _mm_setzero_ps() : limited; }

  bool any = false;            // Spread::any()
  bool every_azimuth = false;  // its azimuth widening reaches every azimuth
  __m128 shift, sin_tilt, turn, azimuth;
};

// A body's pose relative to the sensor, prepared for node views.
class ViewBasis {
 public:
  // planar: only whether a box meets the sensor's xy plane matters, not its elevations. spread:
  // the beams of a sweep's block leave from poses near the reference one (beam_window.h).
  ViewBasis(const Eigen::Isometry3d& sensor_from_body, bool planar, double tmax,
            const Spread& spread = Spread());

 private:
  friend struct NodeViews;
  friend int planeMask(const WideBvh::Node& node, const ViewBasis& basis);
  __m128 rot_[3][3], abs_rot_[3][3], trans_[3], abs_trans_[3];
  __m128 tmax_;
  SpreadPs spread_;
  bool planar_;
};

struct NodeViews {
  int mask;  // bit k: child k exists, may be nearer than tmax, and (planar) may meet the plane
  alignas(16) float near[4];       // no point of the child's box is nearer to the sensor
  alignas(16) float az_center[4];  // rad, the bearing of the box's centre
  alignas(16) float az_half[4];    // rad; negative: the box may be seen at every azimuth
  alignas(16) float el_lo[4];      // rad (not computed for planar frames)
  alignas(16) float el_hi[4];

  // Fills the views of node's children.
  void compute(const WideBvh::Node& node, const ViewBasis& basis);

 private:
  // The azimuth windows narrowed by the boxes' corners (simd::CornerTangents).
  static void narrowByCorners(const ViewBasis& f, const __m128 c[3], const __m128 eb[3],
                              const __m128 mag[3], __m128 rho2, __m128* center, __m128* half);
};

// Which of node's children may meet the sensor's xy plane (bit k for child k): the cheap part of
// NodeViews, for walks that need nothing else.
int planeMask(const WideBvh::Node& node, const ViewBasis& basis);

}  // namespace core
}  // namespace laser_raycast
