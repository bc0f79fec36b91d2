// map_server map files (map_file.h): PGM (P5, P2, 8 and 16 bits) and PNG (grey, RGB, alpha,
// palette, 16 bits) images, negate, the thresholds, the modes, the origin and its yaw, the image's
// rows read from the top, and every bad input named by file and problem. The expected cells are
// worked out by hand from map_server's rules (docs/maps.md).
#include <gtest/gtest.h>
#include <png.h>
#include <zlib.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "expect_invalid.h"
#include "laser_raycast/loader/map_file.h"
#include "temp_files.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast;

std::optional<std::string> noPackages(const std::string&) { return std::nullopt; }

// A map file beside its image: the YAML's keys after `image`, one a line.
std::string writeYaml(const std::string& name, const std::string& image,
                      const std::string& rest =
                          "resolution: 0.5\norigin: [0, 0, 0]\nnegate: 0\n"
                          "occupied_thresh: 0.65\nfree_thresh: 0.196\n") {
  return writeFile(name, "image: " + image + "\n" + rest);
}

// A binary PGM of 8 bits (maxval <= 255) or 16 (most significant byte first).
std::string writePgm(const std::string& name, int width, int height, int maxval,
                     const std::vector<int>& pixels) {
  std::string data = "P5\n# a comment\n" + std::to_string(width) + " " + std::to_string(height) +
                     "\n" + std::to_string(maxval) + "\n";
  for (const int v : pixels) {
    if (maxval > 255) data += static_cast<char>(v >> 8);
    data += static_cast<char>(v & 0xff);
  }
  return writeFile(name, data);
}

// A PNG through libpng: samples row by row from the top, `channels` per pixel (or one palette index
// per pixel with a palette).
std::string writePng(const std::string& name, int width, int height, int color_type, int depth,
                     const std::vector<int>& samples, const std::vector<png_color>& palette = {}) {
  const std::string path = (tempDir() / name).string();
  std::FILE* file = std::fopen(path.c_str(), "wb");
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  png_init_io(png, file);
  png_set_IHDR(png, info, width, height, depth, color_type, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  if (!palette.empty()) png_set_PLTE(png, info, palette.data(), static_cast<int>(palette.size()));
  png_write_info(png, info);
  const std::size_t per_row = samples.size() / height;
  std::vector<png_byte> row;
  for (int y = 0; y < height; ++y) {
    row.clear();
    for (std::size_t k = 0; k < per_row; ++k) {
      const int v = samples[y * per_row + k];
      if (depth == 16) row.push_back(static_cast<png_byte>(v >> 8));
      row.push_back(static_cast<png_byte>(v & 0xff));
    }
    png_write_row(png, row.data());
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  std::fclose(file);
  return path;
}

// The cells as rows of '#' (occupied) and '.', the top row (highest y) first, as the image shows
// them.
std::string picture(const OccupancyMap& map) {
  std::string out;
  for (int j = map.height - 1; j >= 0; --j) {
    for (int i = 0; i < map.width; ++i) out += map.at(i, j) ? '#' : '.';
    out += '\n';
  }
  return out;
}

// The message of the SceneLoadError that reading uri throws, with every one of `words` in it.
std::string refusal(const std::string& uri, const std::vector<std::string>& words = {}) {
  std::string message = "(accepted)";
  try {
    readMapFile(uri, noPackages);
  } catch (const SceneLoadError& e) {
    message = e.what();
  }
  for (const std::string& word : words) {
    EXPECT_NE(message.find(word), std::string::npos) << message;
  }
  return message;
}

// Pixel values and what map_server makes of them with the default thresholds (occupied above
// 0.65): p = (255 - v) / 255. 0 and 89 (p 0.6510) occupied; 90 (p 0.6471), 205 (the unknown grey,
// p 0.196) and 254 free or unknown, so no wall.
const std::vector<int> kPixels = {0, 89, 90, 205, 254, 0};  // 3 x 2, top row first
const char* const kPicture = "##.\n..#\n";

TEST(MapFile, BinaryPgmRowsFromTheTop) {
  const std::string image = writePgm("p5.pgm", 3, 2, 255, kPixels);
  const MapFile map = readMapFile(writeYaml("p5.yaml", "p5.pgm"), noPackages);
  EXPECT_EQ(picture(map.map), kPicture);
  EXPECT_EQ(map.image_path, image);
  EXPECT_EQ(map.map.resolution, 0.5);
  EXPECT_EQ(map.mode, MapMode::kTrinary);
  EXPECT_FALSE(map.negate);
  // Cell (0, 0) is the image's bottom left pixel: 205, no wall; (0, 1) its top left: 0.
  EXPECT_FALSE(map.map.at(0, 0));
  EXPECT_TRUE(map.map.at(0, 1));
  EXPECT_TRUE(map.warnings.empty());
}

TEST(MapFile, AsciiPgmWithComments) {
  writeFile("p2.pgm", "P2 # grey\n3 # width\n2\n255\n0 89 90\n# a row\n205 254\n0\n");
  EXPECT_EQ(picture(readMapFile(writeYaml("p2.yaml", "p2.pgm"), noPackages).map), kPicture);
}

TEST(MapFile, SixteenBitPgm) {
  // p = (65535 - v) / 65535 is above 0.65 for v below 22937.25: 22938 gives 0.649996, 22937
  // 0.650004.
  writePgm("p16.pgm", 2, 1, 65535, {22938, 22937});
  EXPECT_EQ(picture(readMapFile(writeYaml("p16.yaml", "p16.pgm"), noPackages).map), ".#\n");
  // A maxval of 1000 scales the same way: 349 gives 0.651.
  writeFile("p1000.pgm", "P2 2 1 1000 350 349\n");
  EXPECT_EQ(picture(readMapFile(writeYaml("p1000.yaml", "p1000.pgm"), noPackages).map), ".#\n");
}

TEST(MapFile, PngGreyColourAlphaPaletteAnd16Bits) {
  writePng("grey.png", 3, 2, PNG_COLOR_TYPE_GRAY, 8, kPixels);
  EXPECT_EQ(picture(readMapFile(writeYaml("grey.yaml", "grey.png"), noPackages).map), kPicture);
  // RGB: the mean of the channels. (0, 0, 267 / ...) -> means 0, 89, 90, 205, 254, 0.
  writePng("rgb.png", 3, 2, PNG_COLOR_TYPE_RGB, 8,
           {0, 0, 0, 0, 89, 178, 90, 90, 90, 205, 205, 205, 254, 254, 254, 0, 0, 0});
  EXPECT_EQ(picture(readMapFile(writeYaml("rgb.yaml", "rgb.png"), noPackages).map), kPicture);
  // Grey and alpha: the alpha takes no part in the mean, and a transparent black pixel is still
  // occupied (map_server decides occupied before it looks at the alpha).
  writePng("ga.png", 3, 2, PNG_COLOR_TYPE_GRAY_ALPHA, 8,
           {0, 0, 89, 255, 90, 0, 205, 255, 254, 0, 0, 128});
  EXPECT_EQ(picture(readMapFile(writeYaml("ga.yaml", "ga.png"), noPackages).map), kPicture);
  writePng("rgba.png", 3, 2, PNG_COLOR_TYPE_RGB_ALPHA, 8,
           {0,   0,   0,   255, 89,  89,  89,  255, 90, 90, 90, 255,
            205, 205, 205, 0,   254, 254, 254, 255, 0,  0,  0,  0});
  EXPECT_EQ(picture(readMapFile(writeYaml("rgba.yaml", "rgba.png"), noPackages).map), kPicture);
  // A palette: the colours' means.
  writePng("palette.png", 3, 2, PNG_COLOR_TYPE_PALETTE, 8, {0, 1, 2, 3, 4, 0},
           {{0, 0, 0}, {89, 89, 89}, {90, 90, 90}, {205, 205, 205}, {254, 254, 254}});
  EXPECT_EQ(picture(readMapFile(writeYaml("palette.yaml", "palette.png"), noPackages).map),
            kPicture);
  writePng("grey16.png", 2, 1, PNG_COLOR_TYPE_GRAY, 16, {22938, 22937});
  EXPECT_EQ(picture(readMapFile(writeYaml("grey16.yaml", "grey16.png"), noPackages).map), ".#\n");
}

TEST(MapFile, NegateThresholdsAndModes) {
  writePgm("modes.pgm", 6, 1, 255, {0, 100, 101, 66, 65, 255});
  const auto read = [](const std::string& name, const std::string& settings) {
    return picture(
        readMapFile(writeYaml(name, "modes.pgm", "resolution: 1\norigin: [0, 0, 0]\n" + settings),
                    noPackages)
            .map);
  };
  const std::string thresholds = "occupied_thresh: 0.65\nfree_thresh: 0.196\n";
  // p = (255 - v) / 255: only 0 (1.0) and 65 (0.745) and 66 (0.741) are above 0.65; 100 is 0.608.
  EXPECT_EQ(read("trinary.yaml", "negate: 0\n" + thresholds), "#..##.\n");
  EXPECT_EQ(read("scale.yaml", "negate: 0\nmode: scale\n" + thresholds), "#..##.\n");
  // negate: p = v / 255: only 255 (1.0) is above 0.65; 101 is 0.396.
  EXPECT_EQ(read("negate.yaml", "negate: 1\n" + thresholds), ".....#\n");
  EXPECT_EQ(read("negate_true.yaml", "negate: true\n" + thresholds), ".....#\n");
  // raw: p = v / 100 up to 100; 101 and 255 are no occupancy (unknown). 66 is above 0.65, 65 not.
  EXPECT_EQ(read("raw.yaml", "negate: 0\nmode: raw\n" + thresholds), ".#.#..\n");
  // raw and negate: 255 - v, so 255 -> 0, 0 -> 255 (unknown), 101 -> 154 (unknown), 100 -> 155.
  EXPECT_EQ(read("raw_negate.yaml", "negate: 1\nmode: raw\n" + thresholds), "......\n");
  // Lower thresholds: p above 0.1 (v below 229.5).
  EXPECT_EQ(read("low.yaml", "negate: 0\noccupied_thresh: 0.1\nfree_thresh: 0.05\n"), "#####.\n");
}

TEST(MapFile, OriginAndYaw) {
  writePgm("origin.pgm", 2, 2, 255, {0, 255, 255, 255});
  const MapFile map =
      readMapFile(writeYaml("origin.yaml", "origin.pgm",
                            "resolution: 0.25\norigin: [-1.5, 2.0, 1.5707963267948966]\nnegate: 0\n"
                            "occupied_thresh: 0.65\nfree_thresh: 0.196\n"),
                  noPackages);
  EXPECT_EQ(map.origin, Eigen::Vector3d(-1.5, 2.0, M_PI / 2));
  // The lower left corner of cell (0, 0) is at (-1.5, 2); the map's x runs along the frame's y.
  const Eigen::Vector3d corner = map.map.origin * Eigen::Vector3d(0, 0, 0);
  const Eigen::Vector3d along_x = map.map.origin * Eigen::Vector3d(0.25, 0, 0);
  EXPECT_NEAR((corner - Eigen::Vector3d(-1.5, 2.0, 0)).norm(), 0, 1e-15);
  EXPECT_NEAR((along_x - Eigen::Vector3d(-1.5, 2.25, 0)).norm(), 0, 1e-15);
  EXPECT_EQ(picture(map.map), "#.\n..\n");
}

TEST(MapFile, ImagePathsAbsoluteRelativeAndPackage) {
  const std::string image = writePgm("paths.pgm", 3, 2, 255, kPixels);
  std::filesystem::create_directories(tempDir() / "sub");
  // Relative to the YAML's directory, not the working directory.
  writeYaml("sub/relative.yaml", "../paths.pgm");
  EXPECT_EQ(picture(readMapFile((tempDir() / "sub/relative.yaml").string(), noPackages).map),
            kPicture);
  EXPECT_EQ(picture(readMapFile(writeYaml("absolute.yaml", image), noPackages).map), kPicture);
  // The YAML and the image through package:// URIs.
  const auto resolver = [](const std::string& package) -> std::optional<std::string> {
    if (package == "maps") return tempDir().string();
    return std::nullopt;
  };
  writeYaml("package.yaml", "package://maps/paths.pgm");
  const MapFile map = readMapFile("package://maps/package.yaml", resolver);
  EXPECT_EQ(picture(map.map), kPicture);
  EXPECT_EQ(map.yaml_path, (tempDir() / "package.yaml").string());
}

TEST(MapFile, KeysMapServerDoesNotReadAreWarnedAbout) {
  writePgm("extra.pgm", 3, 2, 255, kPixels);
  const MapFile map =
      readMapFile(writeYaml("extra.yaml", "extra.pgm",
                            "resolution: 0.5\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\n"
                            "free_thresh: 0.196\nocupied_thresh: 0.9\n"),
                  noPackages);
  ASSERT_EQ(map.warnings.size(), 1u);
  EXPECT_NE(map.warnings[0].find("'ocupied_thresh'"), std::string::npos) << map.warnings[0];
}

// Every bad input is a SceneLoadError whose message names the YAML and the problem.
TEST(MapFile, BadInputIsNamed) {
  writePgm("good.pgm", 3, 2, 255, kPixels);
  const std::string settings =
      "resolution: 0.5\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.2\n";
  const auto replaced = [&](const std::string& key, const std::string& line) {
    std::string out;
    std::size_t start = 0;
    while (start < settings.size()) {
      const std::size_t end = settings.find('\n', start);
      const std::string l = settings.substr(start, end - start);
      out += l.compare(0, key.size() + 1, key + ":") == 0 ? line : l + "\n";
      start = end + 1;
    }
    return out;
  };
  struct Case {
    std::string name, yaml;
    std::vector<std::string> words;
  };
  const std::vector<Case> cases = {
      {"bad_yaml", "image: good.pgm\nresolution: [0.5\n", {"not valid YAML"}},
      {"list", "- image\n- good.pgm\n", {"not a YAML map"}},
      {"list_key", "? [image, mode]\n: good.pgm\n" + settings, {"not a name"}},
      {"no_image", settings, {"key 'image' is missing"}},
      {"empty_image", "image: ''\n" + settings, {"key 'image' is empty"}},
      {"missing_image", "image: none.pgm\n" + settings, {"none.pgm", "cannot open"}},
      {"no_resolution", "image: good.pgm\n" + replaced("resolution", ""), {"'resolution'"}},
      {"zero_resolution",
       "image: good.pgm\n" + replaced("resolution", "resolution: 0\n"),
       {"'resolution'", "> 0", "got 0"}},
      {"negative_resolution",
       "image: good.pgm\n" + replaced("resolution", "resolution: -0.05\n"),
       {"'resolution'", "got -0.05"}},
      {"text_resolution",
       "image: good.pgm\n" + replaced("resolution", "resolution: fine\n"),
       {"'resolution'", "'fine'", "a number"}},
      {"nan_resolution",
       "image: good.pgm\n" + replaced("resolution", "resolution: .nan\n"),
       {"'resolution'", "finite"}},
      {"short_origin",
       "image: good.pgm\n" + replaced("origin", "origin: [1, 2]\n"),
       {"'origin'", "[x, y, yaw]"}},
      {"text_origin",
       "image: good.pgm\n" + replaced("origin", "origin: [1, 2, up]\n"),
       {"'origin'", "'up'"}},
      {"no_negate", "image: good.pgm\n" + replaced("negate", ""), {"'negate' is missing"}},
      {"bad_negate",
       "image: good.pgm\n" + replaced("negate", "negate: 2\n"),
       {"'negate'", "'2'", "0, 1"}},
      {"no_occupied",
       "image: good.pgm\n" + replaced("occupied_thresh", ""),
       {"'occupied_thresh' is missing"}},
      {"high_occupied",
       "image: good.pgm\n" + replaced("occupied_thresh", "occupied_thresh: 1.5\n"),
       {"'occupied_thresh'", "[0, 1]", "1.5"}},
      {"crossed",
       "image: good.pgm\n" + replaced("free_thresh", "free_thresh: 0.8\n"),
       {"free_thresh 0.8", "above occupied_thresh 0.65"}},
      {"bad_mode", "image: good.pgm\nmode: ternary\n" + settings, {"'mode'", "'ternary'", "raw"}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string path = writeFile(c.name + ".yaml", c.yaml);
    std::vector<std::string> words = c.words;
    words.push_back(path);
    refusal(path, words);
  }
}

TEST(MapFile, BadImagesAreNamed) {
  struct Case {
    std::string name, content;
    std::vector<std::string> words;
  };
  const std::vector<Case> cases = {
      {"text.pgm", "hello world", {"neither PGM", "PNG"}},
      {"p6.pgm", "P6 1 1 255\n\xff\xff\xff", {"neither PGM"}},
      {"cut.pgm", "P5 3 2 255\n\x01\x02", {"cut short", "6 pixels", "the file has 2"}},
      {"promise.pgm", "P5 40000 40000 255\n\x01", {"cut short", "1600000000 pixels"}},
      {"promise2.pgm", "P2 40000 40000 255\n1 2", {"cut short", "at least 3199999999 bytes"}},
      {"cut16.pgm", std::string("P5 1 1 65535\n\x01", 14), {"cut short", "2 bytes"}},
      {"no_height.pgm", "P5 3\n", {"height", "expected a number"}},
      {"word.pgm", "P2 3 two 255\n", {"height", "'two'"}},
      {"zero.pgm", "P5 0 2 255\n", {"no pixels"}},
      {"maxval.pgm", "P5 1 1 70000\n\x01", {"maxval", "[1, 65535]", "70000"}},
      {"over.pgm", "P2 2 1 100 5 101\n", {"pixel 1", "101", "above maxval 100"}},
      {"short.pgm", "P2 2 2 255 1 2 3\n", {"cut short"}},
      {"huge.pgm", "P5 100000 100000 255\n", {"larger than 2^31"}},
      {"cut.png", "\x89PNG\r\n\x1a\n\x00\x00", {"bad PNG"}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    std::vector<std::string> words = c.words;
    words.push_back(writeFile(c.name, c.content));
    words.push_back(writeYaml(c.name + ".yaml", c.name));
    refusal(words.back(), words);
  }
}

// A PNG chunk: length, type, data, CRC (zlib's crc32, over type and data).
std::string pngChunk(const std::string& type, const std::string& data) {
  std::string out;
  const auto u32 = [&out](std::uint32_t v) {
    for (int shift = 24; shift >= 0; shift -= 8) out += static_cast<char>(v >> shift & 0xff);
  };
  u32(static_cast<std::uint32_t>(data.size()));
  out += type + data;
  const std::string body = type + data;
  u32(static_cast<std::uint32_t>(
      crc32(0, reinterpret_cast<const Bytef*>(body.data()), static_cast<uInt>(body.size()))));
  return out;
}

// A PNG whose header promises 40000 x 40000 grey pixels, with one row of them: refused for its
// file's size before its pixels are allocated (3.2 GB as samples; a 16-bit RGBA header would ask
// for 12.8).
TEST(MapFile, PngHeadersPromisingMoreThanTheFileHoldsAreRefused) {
  const std::string ihdr("\x00\x00\x9c\x40\x00\x00\x9c\x40\x08\x00\x00\x00\x00", 13);
  const std::string row = std::string(1, '\0') + std::string(40000, '\xff');
  std::string idat(compressBound(row.size()), '\0');
  uLongf size = idat.size();
  compress(reinterpret_cast<Bytef*>(idat.data()), &size, reinterpret_cast<const Bytef*>(row.data()),
           row.size());
  idat.resize(size);
  writeFile("promise.png", "\x89PNG\r\n\x1a\n" + pngChunk("IHDR", ihdr) + pngChunk("IDAT", idat));
  refusal(writeYaml("promise_png.yaml", "promise.png"),
          {"promise.png", "40000 x 40000 pixels cannot be held in a file of"});
}

TEST(MapFile, MissingFilesAreNamed) {
  const std::string missing = (tempDir() / "no_such_map.yaml").string();
  refusal(missing, {missing + "': file not found"});
  refusal(tempDir().string(), {"a directory"});
  refusal("package://nowhere/map.yaml", {"unknown package 'nowhere'"});
}

}  // namespace
}  // namespace laser_raycast_test
