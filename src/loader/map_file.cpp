#include "laser_raycast/loader/map_file.h"

#include <yaml-cpp/yaml.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <set>
#include <sstream>

#include "map_image.h"
#include "mesh_file.h"

namespace laser_raycast {
namespace {

namespace fs = std::filesystem;

// The keys map_server reads; any other is ignored with a warning.
const std::set<std::string> kKnownKeys = {"image",           "resolution",  "origin", "negate",
                                          "occupied_thresh", "free_thresh", "mode"};

std::string formatValue(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

// The node under key, which must be there. Throws SceneLoadError naming it.
YAML::Node required(const YAML::Node& doc, const std::string& key) {
  const YAML::Node node = doc[key];
  if (!node) throw SceneLoadError("key '" + key + "' is missing");
  return node;
}

// A scalar of type T (what names the type in the message). Throws SceneLoadError naming the key
// and what it holds.
template <typename T>
T scalar(const YAML::Node& node, const std::string& key, const char* what) {
  try {
    if (node.IsScalar()) return node.as<T>();
  } catch (const YAML::Exception&) {
  }
  std::ostringstream held;
  held << node;
  throw SceneLoadError("key '" + key + "': '" + held.str() + "' is not " + what);
}

double number(const YAML::Node& doc, const std::string& key) {
  const double value = scalar<double>(required(doc, key), key, "a number");
  if (!std::isfinite(value)) {
    throw SceneLoadError("key '" + key + "' must be finite, got " + formatValue(value));
  }
  return value;
}

// negate: 0 or 1 as map_server writes it, or a YAML boolean.
bool negateOf(const YAML::Node& doc) {
  const YAML::Node node = required(doc, "negate");
  if (node.IsScalar() && (node.Scalar() == "0" || node.Scalar() == "1")) {
    return node.Scalar() == "1";
  }
  return scalar<bool>(node, "negate", "0, 1, true or false");
}

Eigen::Vector3d originOf(const YAML::Node& doc) {
  const YAML::Node node = required(doc, "origin");
  std::ostringstream held;
  held << node;
  if (!node.IsSequence() || node.size() != 3) {
    throw SceneLoadError("key 'origin': '" + held.str() + "' is not [x, y, yaw]");
  }
  Eigen::Vector3d origin;
  for (int k = 0; k < 3; ++k) origin[k] = scalar<double>(node[k], "origin", "[x, y, yaw]");
  if (!origin.allFinite()) throw SceneLoadError("key 'origin': '" + held.str() + "' is not finite");
  return origin;
}

// The settings of the YAML (everything but the image's pixels). Throws SceneLoadError.
void readSettings(const YAML::Node& doc, const std::string& yaml_dir,
                  const PackageResolver& resolver, MapFile* map) {
  if (!doc.IsMap()) throw SceneLoadError("not a YAML map of keys");
  for (auto it = doc.begin(); it != doc.end(); ++it) {
    if (!it->first.IsScalar()) throw SceneLoadError("a key that is not a name");
    const std::string key = it->first.Scalar();
    if (!kKnownKeys.count(key)) {
      map->warnings.push_back("key '" + key + "' is not one map_server reads (ignored)");
    }
  }
  const std::string image = scalar<std::string>(required(doc, "image"), "image", "a file name");
  if (image.empty()) throw SceneLoadError("key 'image' is empty");
  try {
    map->image_path = mesh_file::resolveUri(image, yaml_dir, resolver);
  } catch (const SceneLoadError& e) {
    throw SceneLoadError("key 'image': '" + image + "': " + e.what());
  }
  map->resolution = number(doc, "resolution");
  if (!(map->resolution > 0)) {
    throw SceneLoadError("key 'resolution' must be > 0 m, got " + formatValue(map->resolution));
  }
  map->origin = originOf(doc);
  map->negate = negateOf(doc);
  map->occupied_thresh = number(doc, "occupied_thresh");
  map->free_thresh = number(doc, "free_thresh");
  for (const auto& [key, value] :
       {std::pair{"occupied_thresh", map->occupied_thresh}, {"free_thresh", map->free_thresh}}) {
    if (!(value >= 0 && value <= 1)) {
      throw SceneLoadError(std::string("key '") + key + "' must be in [0, 1], got " +
                           formatValue(value));
    }
  }
  if (map->free_thresh > map->occupied_thresh) {
    throw SceneLoadError("free_thresh " + formatValue(map->free_thresh) +
                         " is above occupied_thresh " + formatValue(map->occupied_thresh));
  }
  if (const YAML::Node mode = doc["mode"]) {
    const std::string name = scalar<std::string>(mode, "mode", "a mode name");
    if (!kMapModeNames.parse(name, &map->mode)) {
      throw SceneLoadError("key 'mode': " + kMapModeNames.notOneOf(name));
    }
  }
}

// Which cells are occupied, from the image's pixels (docs/maps.md). Image row 0 is the top of the
// map: cell row j is image row height - 1 - j.
OccupancyMap occupancyOf(const map_image::Image& image, const MapFile& settings) {
  OccupancyMap map;
  map.width = image.width;
  map.height = image.height;
  map.resolution = settings.resolution;
  map.origin = Eigen::Translation3d(settings.origin.x(), settings.origin.y(), 0) *
               Eigen::AngleAxisd(settings.origin.z(), Eigen::Vector3d::UnitZ());
  map.occupied.resize(static_cast<std::size_t>(image.width) * image.height);
  const int channels = image.channels();
  const double maxval = image.maxval;
  for (int row = 0; row < image.height; ++row) {
    const std::uint16_t* pixel =
        image.samples.data() + static_cast<std::size_t>(row) * image.width * channels;
    std::uint8_t* cell =
        map.occupied.data() + static_cast<std::size_t>(image.height - 1 - row) * image.width;
    for (int i = 0; i < image.width; ++i, pixel += channels) {
      double sum = 0;
      for (int c = 0; c < image.colors; ++c) sum += pixel[c];
      double v = sum / image.colors;
      if (settings.negate) v = maxval - v;
      double p;
      if (settings.mode == MapMode::kRaw) {
        if (v > 100) continue;  // not an occupancy: unknown
        p = v / 100;
      } else {
        p = (maxval - v) / maxval;
      }
      cell[i] = p > settings.occupied_thresh;
    }
  }
  return map;
}

}  // namespace

MapFile readMapFile(const std::string& uri, const PackageResolver& resolver) {
  MapFile map;
  std::string where = "map '" + uri + "'";
  try {
    map.yaml_path = isPackageUri(uri) ? resolvePackageUri(uri, resolver) : uri;
    if (map.yaml_path != uri) where += " (" + map.yaml_path + ")";
    std::error_code ec;
    if (!fs::exists(map.yaml_path, ec)) throw SceneLoadError("file not found");
    if (fs::is_directory(map.yaml_path, ec)) throw SceneLoadError("a directory, not a map file");
    YAML::Node doc;
    try {
      doc = YAML::LoadFile(map.yaml_path);
    } catch (const YAML::BadFile&) {
      throw SceneLoadError("cannot open the file for reading");
    } catch (const YAML::Exception& e) {
      throw SceneLoadError(std::string("not valid YAML: ") + e.what());
    }
    std::string dir = fs::path(map.yaml_path).parent_path().string();
    if (dir.empty()) dir = ".";
    readSettings(doc, dir, resolver, &map);
    map_image::Image image;
    try {
      image = map_image::read(map.image_path);
    } catch (const SceneLoadError& e) {
      throw SceneLoadError("image '" + map.image_path + "': " + e.what());
    }
    map.map = occupancyOf(image, map);
  } catch (const SceneLoadError& e) {
    throw SceneLoadError(where + ": " + e.what());
  }
  return map;
}

LoadedMap addMapFile(const std::string& uri, const PackageResolver& resolver,
                     const MapWallOptions& options, core::Scene* scene) {
  const auto start = std::chrono::steady_clock::now();
  MapFile file = readMapFile(uri, resolver);
  const double read_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  LoadedMap out;
  try {
    out = addMapWalls(file.map, options, scene);
  } catch (const SceneLoadError& e) {
    throw SceneLoadError("map '" + uri + "': " + e.what());
  }
  out.read_seconds = read_seconds;
  for (std::string& warning : file.warnings)
    out.warnings.push_back("map '" + uri + "': " + warning);
  return out;
}

}  // namespace laser_raycast
