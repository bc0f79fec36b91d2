#include "laser_raycast/node/point_cloud.h"

#include <sensor_msgs/PointField.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace laser_raycast {
namespace {

using sensor_msgs::PointField;

bool hostIsBigEndian() {
  const std::uint16_t one = 1;
  std::uint8_t first;
  std::memcpy(&first, &one, 1);
  return first == 0;
}

// What one beam gives its point's fields.
struct Beam {
  Eigen::Vector3f xyz;  // NaN without a return
  float intensity;      // NaN without a return
  int ring;
  double time;   // s after the stamp
  double range;  // m; 0 without a return
};

// The bytes of a field of type `datatype`.
constexpr std::uint32_t fieldBytes(std::uint8_t datatype) {
  switch (datatype) {
    case PointField::INT8:
    case PointField::UINT8:
      return 1;
    case PointField::INT16:
    case PointField::UINT16:
      return 2;
    case PointField::INT32:
    case PointField::UINT32:
    case PointField::FLOAT32:
      return 4;
    default:
      return 8;
  }
}

// Whether a layout's fields, one after the other from offset 0, fill its points: no padding.
template <std::size_t N>
constexpr bool everyByteIsAField(const PointLayoutTable<N>& table) {
  std::uint32_t end = 0;
  for (const PointLayoutField& f : table.fields) {
    if (f.offset != end) return false;
    end += fieldBytes(f.datatype);
  }
  return end == table.point_step;
}
static_assert(everyByteIsAField(point_layouts::kVelodyne), "velodyne_pointcloud packs its points");

// memcpy: the data buffer gives no alignment guarantee.
template <typename T>
void put(T value, std::uint8_t* out) {
  std::memcpy(out, &value, sizeof value);
}

// std::round of v >= 0 (halves away from zero) without a call into libm, which every point paid
// for its ring (x86-64's baseline has no rounding instruction): the whole part by truncation, exact
// below 2^52, from where every double is whole.
double roundNonNegative(double v) {
  if (!(v < 0x1p52)) return v;
  const double whole = static_cast<double>(static_cast<std::int64_t>(v));
  return v - whole >= 0.5 ? whole + 1 : whole;
}

// An integer field: rounded to nearest and clamped to its type; NaN (no return) is 0.
template <typename T>
void putInteger(double value, std::uint8_t* out) {
  const double max = std::numeric_limits<T>::max();
  put(static_cast<T>(value > 0 ? std::min(roundNonNegative(value), max) : 0.0), out);
}

// The stamp plus `time` s, in whole ns: the absolute fields are computed from it, each with one
// rounding at the end.
std::int64_t stampNanoseconds(std::int64_t stamp_ns, double time) {
  return stamp_ns + std::llround(time * 1e9);
}

// PointValue::kReflectivity of an intensity (rho cos(theta)): NaN stays NaN.
double reflectivityValue(double intensity) {
  if (std::isnan(intensity)) return intensity;
  const double percent = 100.0 * intensity;
  return percent > 0 ? std::min(roundNonNegative(percent), 255.0) : 0.0;
}

// Value V of `beam` as a double, for writeField to convert to the field's type.
template <PointValue V>
double valueOf(const Beam& beam, std::int64_t stamp_ns) {
  if constexpr (V == PointValue::kX) return beam.xyz.x();
  if constexpr (V == PointValue::kY) return beam.xyz.y();
  if constexpr (V == PointValue::kZ) return beam.xyz.z();
  if constexpr (V == PointValue::kIntensity) return beam.intensity;
  if constexpr (V == PointValue::kReflectivity) return reflectivityValue(beam.intensity);
  if constexpr (V == PointValue::kSignal) {
    const double reflectivity = reflectivityValue(beam.intensity);
    if (std::isnan(reflectivity) || reflectivity == 0) return reflectivity;
    const double scale = 10.0 / beam.range;
    return std::min(65535.0, roundNonNegative(reflectivity * scale * scale));
  }
  if constexpr (V == PointValue::kRing) return beam.ring;
  if constexpr (V == PointValue::kTimeSeconds) return beam.time;
  if constexpr (V == PointValue::kTimeNanoseconds) return beam.time * 1e9;
  if constexpr (V == PointValue::kStampSeconds) {
    // Whole seconds and the rest apart, so that the rest is not rounded with the seconds.
    const std::int64_t ns = stampNanoseconds(stamp_ns, beam.time);
    return static_cast<double>(ns / 1000000000) + static_cast<double>(ns % 1000000000) * 1e-9;
  }
  if constexpr (V == PointValue::kStampNanoseconds) {
    return static_cast<double>(stampNanoseconds(stamp_ns, beam.time));
  }
  if constexpr (V == PointValue::kRangeMillimetres) return beam.range * 1000;
  return 0;  // kZero
}

template <PointValue V, std::uint8_t D>
void writeField(const Beam& beam, std::int64_t stamp_ns, std::uint8_t* out) {
  const double value = valueOf<V>(beam, stamp_ns);
  if constexpr (D == PointField::FLOAT32) {
    put(static_cast<float>(value), out);
  } else if constexpr (D == PointField::FLOAT64) {
    put(value, out);
  } else if constexpr (D == PointField::UINT8) {
    putInteger<std::uint8_t>(value, out);
  } else if constexpr (D == PointField::UINT16) {
    putInteger<std::uint16_t>(value, out);
  } else {
    static_assert(D == PointField::UINT32, "a field type the layouts do not use");
    putInteger<std::uint32_t>(value, out);
  }
}

// Every field of a point of the layout `Ref` refers to: one call per field, each resolved when
// this is compiled.
template <class Ref, std::size_t... I>
void writePoint(const Beam& beam, std::int64_t stamp_ns, std::uint8_t* out,
                std::index_sequence<I...>) {
  constexpr const auto& fields = Ref::table.fields;
  (writeField<fields[I].value, fields[I].datatype>(beam, stamp_ns, out + fields[I].offset), ...);
}

// The largest of values and `floor`.
template <typename T>
T maxOf(const std::vector<T>& values, T floor) {
  T m[4] = {floor, floor, floor, floor};
  const std::size_t n = values.size(), quads = n - n % 4;
  for (std::size_t i = 0; i < quads; i += 4) {
    for (int k = 0; k < 4; ++k) m[k] = std::max(m[k], values[i + k]);
  }
  for (std::size_t i = quads; i < n; ++i) m[0] = std::max(m[0], values[i]);
  return std::max(std::max(m[0], m[1]), std::max(m[2], m[3]));
}

void checkSizes(const core::ScanPattern& pattern, const core::MeasuredScan& scan,
                const std::vector<double>& column_times, PointLayout layout) {
  const std::size_t beams = pattern.size();
  std::string problem;
  const double last_time =
      column_times.empty() ? 0.0 : *std::max_element(column_times.begin(), column_times.end());
  if (scan.ranges.size() != beams) {
    problem = "the scan has " + std::to_string(scan.ranges.size()) + " ranges";
  } else if (!scan.intensities.empty() && scan.intensities.size() != beams) {
    problem = "the scan has " + std::to_string(scan.intensities.size()) + " intensities";
  } else if (!column_times.empty() &&
             column_times.size() != static_cast<std::size_t>(pattern.azimuthCount())) {
    problem = std::to_string(column_times.size()) + " column times are given";
  } else {
    problem = pointLayoutLimit(layout, pattern.ringCount(), last_time);
    if (problem.empty()) return;
  }
  throw std::invalid_argument("buildPointCloud: " + problem + " for a pattern of " +
                              std::to_string(pattern.ringCount()) + " rings x " +
                              std::to_string(pattern.azimuthCount()) + " azimuths");
}

}  // namespace

namespace {

// The cloud of `beams` beams as height x width (organized) or one row of the valid returns, in the
// order beam(0), beam(1), ...: beam b with a valid range r is the point at(b, r), with ring ring(b)
// and time time(b). With last (dual returns), each beam's return in last follows its own in scan,
// and a `return` field says which.
template <class Order, class At, class Ring, class Time>
void fillCloud(int beams, int height, int width, const core::MeasuredScan& scan,
               const std_msgs::Header& header, const CloudOptions& options, Order&& beam_at,
               At&& at, Ring&& ring, Time&& time, sensor_msgs::PointCloud2* cloud,
               const core::MeasuredScan* last = nullptr) {
  const int returns = last ? 2 : 1;
  int points = beams * returns;
  if (!options.organized) {
    points = 0;
    for (const float r : scan.ranges) points += std::isfinite(r);
    if (last) {
      for (const float r : last->ranges) points += std::isfinite(r);
    }
  }
  width *= returns;

  cloud->header = header;
  cloud->height = options.organized ? height : 1;
  cloud->width = options.organized ? width : points;
  cloud->is_bigendian = hostIsBigEndian();
  cloud->fields.clear();
  withPointLayout(options.layout, [&](auto ref) {
    for (const PointLayoutField& f : ref.table.fields) {
      PointField field;
      field.name = f.name;
      field.offset = f.offset;
      field.datatype = f.datatype;
      field.count = 1;
      cloud->fields.push_back(field);
    }
    cloud->point_step = ref.table.point_step;
  });
  if (last) {
    PointField field;
    field.name = kReturnField;
    field.offset = cloud->point_step;
    field.datatype = PointField::UINT8;
    field.count = 1;
    cloud->fields.push_back(field);
    cloud->point_step += 1;
  }
  cloud->row_step = cloud->width * cloud->point_step;
  // Every byte is written: the fields below, and the padding zeroed where the layout has some, so
  // that equal clouds are equal bytes. A packed layout's bytes are all fields: its buffer is only
  // sized (a cloud built into the last one's, as the node's are, writes over it in place).
  const std::size_t bytes = static_cast<std::size_t>(points) * cloud->point_step;
  withPointLayout(options.layout, [&](auto ref) {
    if constexpr (everyByteIsAField(decltype(ref)::table)) {
      cloud->data.resize(bytes);
    } else {
      cloud->data.assign(bytes, 0);
    }
  });

  constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
  const auto stamp_ns = static_cast<std::int64_t>(header.stamp.toNSec());
  bool all_valid = true;
  std::uint8_t* out = cloud->data.data();
  // One loop per layout, its fields written as constants.
  withPointLayout(options.layout, [&](auto ref) {
    using Ref = decltype(ref);
    const auto each_field = std::make_index_sequence<Ref::table.fields.size()>();
    for (int p = 0; p < beams; ++p) {
      const int b = beam_at(p);
      for (int k = 0; k < returns; ++k) {
        const core::MeasuredScan& from = k == 0 ? scan : *last;
        const float range = from.ranges[b];
        const bool valid = std::isfinite(range);
        all_valid = all_valid && valid;
        if (!valid && !options.organized) continue;
        Beam beam;
        beam.ring = ring(b);
        beam.time = time(b);
        if (valid) {
          beam.xyz = at(b, static_cast<double>(range)).template cast<float>();
          beam.intensity = from.intensities.empty() ? 0.0f : from.intensities[b];
          beam.range = range;
        } else {
          beam.xyz.setConstant(kNan);
          beam.intensity = kNan;
          beam.range = 0;
        }
        writePoint<Ref>(beam, stamp_ns, out, each_field);
        if (last) out[Ref::table.point_step] = static_cast<std::uint8_t>(k + 1);
        out += cloud->point_step;
      }
    }
  });
  cloud->is_dense = !options.organized || all_valid;
}

}  // namespace

void buildPointCloud(const core::ScanPattern& pattern, const core::MeasuredScan& scan,
                     const std::vector<double>& column_times, const std_msgs::Header& header,
                     const CloudOptions& options, sensor_msgs::PointCloud2* cloud,
                     const core::MeasuredScan* last) {
  checkSizes(pattern, scan, column_times, options.layout);
  if (last) checkSizes(pattern, *last, column_times, options.layout);
  const int azimuths = pattern.azimuthCount();
  // fillCloud asks for beams in ascending order: their ring and column follow by counting, with
  // no division per point.
  int row = 0, row_start = 0;
  auto locate = [&](int b) {
    while (b >= row_start + azimuths) {
      ++row;
      row_start += azimuths;
    }
    return b - row_start;
  };
  fillCloud(
      pattern.size(), pattern.ringCount(), azimuths, scan, header, options, [](int p) { return p; },
      [&](int b, double range) -> Eigen::Vector3d { return pattern.directions()[b] * range; },
      [&](int b) {
        locate(b);
        return row;
      },
      [&](int b) {
        const int col = locate(b);
        return column_times.empty() ? 0.0 : column_times[col];
      },
      cloud, last);
}

void buildBeamCloud(const core::BeamList& beams, const core::MeasuredScan& scan,
                    const std_msgs::Header& header, const CloudOptions& options,
                    sensor_msgs::PointCloud2* cloud) {
  const std::size_t n = beams.size();
  // Each vector on its own (an empty one is every beam's 0), four maxima at a time: one would
  // wait for the last at every beam (a fifth of the cloud's time for a 28,928-beam turn).
  const int lines = 1 + maxOf(beams.lines, 0);
  std::string problem;
  if (scan.ranges.size() != n) {
    problem = "the scan has " + std::to_string(scan.ranges.size()) + " ranges";
  } else if (!scan.intensities.empty() && scan.intensities.size() != n) {
    problem = "the scan has " + std::to_string(scan.intensities.size()) + " intensities";
  } else {
    problem = pointLayoutLimit(options.layout, lines, maxOf(beams.times, 0.0));
  }
  if (!problem.empty()) {
    throw std::invalid_argument("buildBeamCloud: " + problem + " for " + std::to_string(n) +
                                " beams");
  }
  // Organized, a row per line where every line has as many beams (a calibrated Velodyne's rings
  // or an Ouster's beams, as their drivers lay out their images: row r line r, its beams in firing
  // order); one row of every beam otherwise (a pattern file's lines).
  std::vector<int> order;
  int height = 1, width = beams.size();
  if (options.organized && !beams.lines.empty()) {
    std::vector<int> per_line(lines, 0);
    for (const int line : beams.lines) ++per_line[line];
    bool uniform = per_line.front() > 0;
    for (const int count : per_line) uniform = uniform && count == per_line.front();
    if (uniform) {
      height = lines;
      width = per_line.front();
      // Each line's beams in list order, line after line.
      order.resize(beams.size());
      std::vector<int> next(lines);
      for (int l = 0; l < lines; ++l) next[l] = l * width;
      for (int b = 0; b < beams.size(); ++b) order[next[beams.lines[b]]++] = b;
    }
  }
  fillCloud(
      beams.size(), height, width, scan, header, options,
      [&](int p) { return order.empty() ? p : order[p]; },
      [&](int b, double range) -> Eigen::Vector3d {
        return beams.origin(b) + beams.directions[b] * range;
      },
      [&](int b) { return beams.line(b); }, [&](int b) { return beams.time(b); }, cloud);
}

std::vector<double> rotatingColumnTimes(int azimuths, double time_increment) {
  std::vector<double> times(azimuths);
  for (int c = 0; c < azimuths; ++c) times[c] = c * time_increment;
  return times;
}

}  // namespace laser_raycast
