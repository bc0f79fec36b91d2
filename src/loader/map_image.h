// The image of a map file: PGM (binary P5 and ASCII P2, read here) or PNG (through libpng). Private
// to the loader library; map_file.h turns its pixels into occupancy.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace laser_raycast {
namespace map_image {

struct Image {
  int width = 0, height = 0;
  int colors = 1;      // colour channels: 1 (grey) or 3 (RGB)
  bool alpha = false;  // a last channel of opacity follows the colours
  int maxval = 255;    // the largest sample value: white, or fully opaque
  // Row by row from the top row of the picture, each pixel's channels together.
  std::vector<std::uint16_t> samples;

  int channels() const { return colors + (alpha ? 1 : 0); }
};

// Reads a PGM or PNG file, told apart by its first bytes (not its name). Throws SceneLoadError
// naming the problem (not the file: the caller names it): unreadable, neither format, a header
// or data that is cut short or malformed, a size of 0 or over 2^31 pixels.
Image read(const std::string& path);

}  // namespace map_image
}  // namespace laser_raycast
