// Beam directions in the sensor frame: a planar fan (LaserScan), or rings of fans at several
// elevations.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <vector>

namespace laser_raycast {
namespace core {

// An azimuth fan. Give angle_increment or samples (the other 0):
// - increment: N = round((angle_max - angle_min) / angle_increment) + 1 beams from angle_min,
// spaced by
//   angle_increment; the last beam is at angle_min + (N - 1) * angle_increment.
// - samples: N = samples beams from angle_min to angle_max inclusive, spaced by (max - min) / (N -
// 1).
struct FanSpec {
  // The beams the node and cast_scan use when neither samples nor angle_increment is given: one a
  // degree over the full turn.
  static constexpr int kDefaultSamples = 360;
  double angle_min = -M_PI;    // rad, first beam, counter-clockwise from x about z
  double angle_max = M_PI;     // rad, > angle_min
  double angle_increment = 0;  // rad, > 0; or 0 to derive it from samples
  int samples = 0;             // >= 2; or 0 to derive it from angle_increment

  // Throws std::invalid_argument naming the field and its value: non-finite angles, angle_max <=
  // angle_min, both or neither of angle_increment and samples, a non-positive increment, samples <
  // 2, or more than kMaxBeams beams.
  void validate() const;
  int beamCount() const;     // N (after validate())
  double increment() const;  // the spacing actually used
  // At most this many beams in one scan (over all rings). It bounds what one scan allocates (about
  // 60 bytes a beam across the pattern, the cast result and the message: 0.6 GB here), so that a
  // slip such as angle_increment 1e-9 is refused with a message instead of exhausting memory. Real
  // sensors stay far below it (a 128-ring lidar at 2048 azimuths has 262,144 beams).
  static constexpr int kMaxBeams = 10000000;
};

class ScanPattern {
 public:
  // A planar fan in the sensor's xy plane.
  explicit ScanPattern(const FanSpec& fan);
  // One fan per elevation (rad, in [-pi/2, pi/2], positive up), ring-major: beam r * azimuthCount()
  // + i is azimuth i of ring r. Throws std::invalid_argument for an empty or out-of-range elevation
  // list.
  ScanPattern(const FanSpec& fan, std::vector<double> elevations);

  int size() const { return static_cast<int>(directions_.size()); }
  int azimuthCount() const { return azimuth_count_; }
  int ringCount() const { return static_cast<int>(elevations_.size()); }
  double angleMin() const { return angle_min_; }
  double angleIncrement() const { return angle_increment_; }
  double angleMax() const { return angle_min_ + (azimuth_count_ - 1) * angle_increment_; }
  double azimuth(int i) const { return angle_min_ + i * angle_increment_; }
  const std::vector<double>& elevations() const { return elevations_; }
  // A single ring at elevation exactly 0: every beam lies in the sensor's xy plane.
  bool planar() const { return elevations_.size() == 1 && elevations_[0] == 0.0; }
  // Unit directions in the sensor frame, ring-major.
  const std::vector<Eigen::Vector3d>& directions() const { return directions_; }

 private:
  double angle_min_, angle_increment_;
  int azimuth_count_;
  std::vector<double> elevations_;
  std::vector<Eigen::Vector3d> directions_;
};

}  // namespace core
}  // namespace laser_raycast
