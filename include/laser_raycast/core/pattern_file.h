// A scan pattern read from a file, as the simulation files of non-repetitive and solid-state
// scanners are written (Livox's among them): CSV rows `Time/s,Azimuth/deg,Zenith/deg` with an
// optional fourth column `Line`, zenith measured from the sensor's +z axis and azimuth
// counter-clockwise from its x axis. The file is a loop: scan after scan takes the next rows.
#pragma once

#include <cstdint>
#include <istream>
#include <string>
#include <vector>

#include "laser_raycast/core/beam_list.h"

namespace laser_raycast {
namespace core {

class PatternFile {
 public:
  struct Row {
    double time;     // s, as the file gives it (read and checked; the cast's times come from the
                     // point rate, see scan())
    double azimuth;  // rad, counter-clockwise from x
    double zenith;   // rad, from +z, in [0, pi]
    int line;        // the laser line (0 without a Line column)
  };

  // Reads a file. Throws std::invalid_argument naming the file, the line and the bad value: no
  // header or an unexpected one, a row of the wrong number of fields, a field that is not a finite
  // number, a zenith outside [0, 180] degrees, a line outside [0, 255], no rows at all, or more
  // rows than FanSpec::kMaxBeams.
  static PatternFile load(const std::string& path);
  static PatternFile parse(std::istream& in, const std::string& name);

  const std::vector<Row>& rows() const { return rows_; }
  int size() const { return static_cast<int>(rows_.size()); }
  bool hasLines() const { return has_lines_; }

  // The beams of one scan: `count` rows from row `start` on (wrapping round the file's end), beam
  // k at k / point_rate s, its direction from the row's azimuth and zenith, its line the row's.
  BeamList scan(std::int64_t start, int count, double point_rate) const;

 private:
  std::vector<Row> rows_;
  // Each row's zenithDirection, made once when read (a scan takes thousands, each a sine and a
  // cosine twice).
  std::vector<Eigen::Vector3d> directions_;
  bool has_lines_ = false;
};

// The unit direction of azimuth and zenith (rad): sin(zenith) (cos, sin)(azimuth), cos(zenith).
Eigen::Vector3d zenithDirection(double azimuth, double zenith);

}  // namespace core
}  // namespace laser_raycast
