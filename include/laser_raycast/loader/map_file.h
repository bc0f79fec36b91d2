// map_server map files: a YAML file that names an image (PGM or PNG) and says how its pixels map to
// occupancy and where the map lies. Read into an OccupancyMap (map_walls.h) as map_server would
// classify its cells; docs/maps.md gives the rules.
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "laser_raycast/core/enum_names.h"
#include "laser_raycast/core/scene.h"
#include "laser_raycast/loader/map_walls.h"
#include "laser_raycast/loader/package_resolver.h"

namespace laser_raycast {

// The YAML's `mode`: how a pixel becomes an occupancy.
enum class MapMode {
  kTrinary,  // "trinary" (the default): occupied, free or unknown by the two thresholds
  kScale,    // "scale": as trinary for what counts as occupied (between the thresholds a value)
  kRaw,      // "raw": the pixel value is the occupancy in percent (0 to 100; above: unknown)
};
inline const core::EnumNames<MapMode, 3> kMapModeNames{{{
    {MapMode::kTrinary, "trinary"},
    {MapMode::kScale, "scale"},
    {MapMode::kRaw, "raw"},
}}};

// A map file as read: its settings and which cells are occupied.
struct MapFile {
  std::string yaml_path;   // the YAML file (a package:// URI resolved)
  std::string image_path;  // the image, its `image` resolved against the YAML's directory
  double resolution = 0;   // m per cell
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // x, y (m), yaw (rad)
  bool negate = false;
  double occupied_thresh = 0, free_thresh = 0;
  MapMode mode = MapMode::kTrinary;
  OccupancyMap map;  // cell (i, j) is pixel (i, image height - 1 - j): image rows run downwards
  std::vector<std::string> warnings;  // keys map_server does not read (ignored)
};

// Reads the map file at uri (a path or a package:// URI, found through resolver) and its image.
// A cell is occupied if its occupancy p exceeds occupied_thresh, p being for a pixel of mean
// colour v (the mean of its colour channels, not its alpha) out of maxval: (maxval - v) / maxval,
// or v / maxval with negate; in raw mode p = v / 100 for v <= 100 (v, or maxval - v with negate),
// and a larger v is unknown. Unknown and free cells are not occupied. Throws SceneLoadError naming
// the file (and the image) and the problem: no such file, YAML that does not parse, a required key
// (image, resolution, origin, negate, occupied_thresh, free_thresh) missing or of the wrong type,
// a resolution not > 0, thresholds outside [0, 1] or free_thresh > occupied_thresh, an unknown
// mode, an image that cannot be read.
MapFile readMapFile(const std::string& uri, const PackageResolver& resolver);

// readMapFile, then addMapWalls with the file's map: the walls of a map file in a scene. Errors
// (SceneLoadError) name the file; the file's warnings are in the result.
LoadedMap addMapFile(const std::string& uri, const PackageResolver& resolver,
                     const MapWallOptions& options, core::Scene* scene);

}  // namespace laser_raycast
