// A VLP-16 as its user manual fires it, worked out by hand for the tests: laser id i of firing
// sequence q fires at q * 55.296 + i * 2.304 us after the stamp; the head's azimuth is pi at the
// stamp and turns clockwise once a turn; ring r (-15 + 2r deg) is laser id 2r below the horizon
// and 2(r - 8) + 1 above it.
#pragma once

#include <cmath>
#include <cstdint>

namespace laser_raycast_test {

constexpr double kVlp16SequencePeriod = 55.296e-6;  // s
constexpr double kVlp16LaserPeriod = 2.304e-6;      // s

// s after the stamp.
inline double vlp16FiringTime(long sequence, int laser_id) {
  return sequence * kVlp16SequencePeriod + laser_id * kVlp16LaserPeriod;
}
// rad: the head's azimuth t s after the stamp, in a turn of `turn` s.
inline double vlp16HeadAzimuth(double t, double turn) { return M_PI - 2 * M_PI * t / turn; }

// A point's firing, from its ring and its time (as a cloud's fields give them).
struct Vlp16Firing {
  int id;  // laser id
  long sequence;
  double time;     // s after the stamp
  double azimuth;  // rad, the head's then
};
inline Vlp16Firing vlp16Firing(std::uint16_t ring, float time, double turn) {
  Vlp16Firing f;
  f.id = ring < 8 ? 2 * ring : 2 * (ring - 8) + 1;
  f.sequence = std::lround((time - f.id * kVlp16LaserPeriod) / kVlp16SequencePeriod);
  f.time = vlp16FiringTime(f.sequence, f.id);
  f.azimuth = vlp16HeadAzimuth(f.time, turn);
  return f;
}

}  // namespace laser_raycast_test
