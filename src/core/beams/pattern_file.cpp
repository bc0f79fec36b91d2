#include "laser_raycast/core/pattern_file.h"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "laser_raycast/core/scan_pattern.h"

namespace laser_raycast {
namespace core {
namespace {

std::string trim(const std::string& s) {
  const std::size_t a = s.find_first_not_of(" \t\r");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t\r") - a + 1);
}

std::vector<std::string> splitFields(const std::string& line) {
  std::vector<std::string> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    fields.push_back(trim(line.substr(start, comma - start)));
    if (comma == std::string::npos) return fields;
    start = comma + 1;
  }
}

}  // namespace

Eigen::Vector3d zenithDirection(double azimuth, double zenith) {
  const double s = std::sin(zenith);
  return Eigen::Vector3d(s * std::cos(azimuth), s * std::sin(azimuth), std::cos(zenith));
}

PatternFile PatternFile::load(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument("pattern file " + path + ": cannot be opened");
  return parse(in, path);
}

PatternFile PatternFile::parse(std::istream& in, const std::string& name) {
  PatternFile out;
  std::string line;
  int number = 0;
  auto fail = [&](const std::string& what) {
    throw std::invalid_argument("pattern file " + name + " line " + std::to_string(number) + ": " +
                                what);
  };
  std::size_t columns = 0;
  while (std::getline(in, line)) {
    ++number;
    if (trim(line).empty()) continue;
    const std::vector<std::string> fields = splitFields(line);
    if (columns == 0) {
      const bool three = fields.size() == 3 || fields.size() == 4;
      if (!three || fields[0] != "Time/s" || fields[1] != "Azimuth/deg" ||
          fields[2] != "Zenith/deg" || (fields.size() == 4 && fields[3] != "Line")) {
        fail("header '" + trim(line) + "', expected 'Time/s,Azimuth/deg,Zenith/deg' (and ',Line')");
      }
      columns = fields.size();
      out.has_lines_ = columns == 4;
      continue;
    }
    if (fields.size() != columns) {
      fail(std::to_string(fields.size()) + " fields, expected " + std::to_string(columns));
    }
    double v[4] = {0, 0, 0, 0};
    for (std::size_t k = 0; k < columns; ++k) {
      char* end = nullptr;
      v[k] = std::strtod(fields[k].c_str(), &end);
      if (fields[k].empty() || *end != '\0' || !std::isfinite(v[k])) {
        fail("field " + std::to_string(k + 1) + " '" + fields[k] + "' is not a finite number");
      }
    }
    if (!(v[2] >= 0 && v[2] <= 180)) fail("zenith " + fields[2] + " deg is outside [0, 180]");
    if (columns == 4 && !(v[3] >= 0 && v[3] <= 255 && v[3] == std::floor(v[3]))) {
      fail("line " + fields[3] + " is not an integer in [0, 255]");
    }
    if (out.rows_.size() >= static_cast<std::size_t>(FanSpec::kMaxBeams)) {
      fail("more than " + std::to_string(FanSpec::kMaxBeams) + " rows");
    }
    out.rows_.push_back(Row{v[0], v[1] * M_PI / 180, v[2] * M_PI / 180, static_cast<int>(v[3])});
  }
  if (columns == 0) {
    number = 0;
    fail("empty, expected the header 'Time/s,Azimuth/deg,Zenith/deg'");
  }
  if (out.rows_.empty()) fail("no rows after the header");
  out.directions_.reserve(out.rows_.size());
  for (const Row& r : out.rows_) out.directions_.push_back(zenithDirection(r.azimuth, r.zenith));
  return out;
}

BeamList PatternFile::scan(std::int64_t start, int count, double point_rate) const {
  BeamList beams;
  beams.directions.reserve(count);
  beams.times.reserve(count);
  beams.lines.reserve(count);
  const std::int64_t n = size();
  std::int64_t row = ((start % n) + n) % n;
  for (int k = 0; k < count; ++k) {
    beams.directions.push_back(directions_[row]);
    beams.times.push_back(k / point_rate);
    beams.lines.push_back(rows_[row].line);
    if (++row == n) row = 0;
  }
  return beams;
}

}  // namespace core
}  // namespace laser_raycast
