#include "laser_raycast/node/point_layout.h"

#include <limits>

#include "param_reader.h"

namespace laser_raycast {

std::string pointLayoutLimit(PointLayout layout, int rings, double sweep_duration) {
  using sensor_msgs::PointField;
  const std::string name = kPointLayoutNames.name(layout);
  const double max_time = std::numeric_limits<std::uint32_t>::max() * 1e-9;  // s
  return withPointLayout(layout, [&](auto ref) -> std::string {
    for (const PointLayoutField& f : ref.table.fields) {
      if (f.value == PointValue::kRing && f.datatype == PointField::UINT8 && rings > 256) {
        return "'" + name + "' numbers rings in uint8 (its field " + f.name +
               "): at most 256, got " + std::to_string(rings) + " rings";
      }
      if (f.value == PointValue::kRing && rings > std::numeric_limits<std::uint16_t>::max() + 1) {
        return "'" + name + "' numbers rings in uint16 (its field " + f.name +
               "): at most 65536, got " + std::to_string(rings) + " rings";
      }
      if (f.value == PointValue::kTimeNanoseconds && !(sweep_duration <= max_time)) {
        return "'" + name + "' gives a point's time in uint32 ns (its field " + f.name +
               "): at most " + formatNumber(max_time) + " s after the stamp, but the sweep lasts " +
               formatNumber(sweep_duration) + " s";
      }
    }
    return "";
  });
}

}  // namespace laser_raycast
