#include "map_image.h"

#include <png.h>

#include <cctype>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>

#include "laser_raycast/loader/errors.h"

namespace laser_raycast {
namespace map_image {
namespace {

// Images larger than this are refused rather than allocated: 2^31 pixels is a map of 46,000 cells
// a side, 2.3 km at 5 cm.
constexpr double kMaxPixels = 2147483648.0;

void checkSize(double width, double height) {
  if (!(width > 0 && height > 0)) throw SceneLoadError("the image has no pixels");
  if (width * height > kMaxPixels) {
    throw SceneLoadError("the image of " + std::to_string(static_cast<long long>(width)) + " x " +
                         std::to_string(static_cast<long long>(height)) +
                         " pixels is larger than 2^31 pixels");
  }
}

// ---------------------------------------------------------------------------------------------------
// PGM: "P5" (binary) or "P2" (ASCII), white space and '#' comments, width, height, maxval (1 to
// 65535), then the samples: binary one byte each up to maxval 255, else two, most significant
// first; ASCII as decimal numbers.

class PgmReader {
 public:
  explicit PgmReader(std::string data) : data_(std::move(data)) {}

  Image read() {
    const bool ascii = data_.compare(0, 2, "P2") == 0;
    pos_ = 2;
    Image image;
    const long long width = number("width"), height = number("height");
    checkSize(double(width), double(height));
    image.width = static_cast<int>(width);
    image.height = static_cast<int>(height);
    const long long maxval = number("maxval");
    if (maxval < 1 || maxval > 65535) {
      throw SceneLoadError("PGM maxval must be in [1, 65535], got " + std::to_string(maxval));
    }
    image.maxval = static_cast<int>(maxval);
    const std::size_t count = static_cast<std::size_t>(width) * height;
    const std::size_t bytes = maxval > 255 ? 2 : 1;  // a binary sample's
    // A header that promises more samples than the file holds is refused before anything is
    // allocated for them: each takes at least a digit and a separator in ASCII (the last no
    // separator), one or two bytes in binary after the one white space byte that ends the header.
    const std::size_t rest = data_.size() - pos_;
    const std::size_t have = ascii ? rest : rest - std::min<std::size_t>(rest, 1);
    const std::size_t need = ascii ? 2 * count - 1 : count * bytes;
    if (have < need) {
      throw SceneLoadError("PGM data cut short: " + std::to_string(count) + " pixels need " +
                           (ascii ? "at least " : "") + std::to_string(need) +
                           " bytes, the file has " + std::to_string(have) + " after its header");
    }
    image.samples.resize(count);
    if (ascii) {
      for (std::size_t k = 0; k < count; ++k) image.samples[k] = sample(k, maxval);
    } else {
      // Exactly one white space character ends the header.
      if (!std::isspace(static_cast<unsigned char>(data_[pos_]))) {
        throw SceneLoadError("PGM header ends without white space before the pixels");
      }
      ++pos_;
      const auto* in = reinterpret_cast<const unsigned char*>(data_.data() + pos_);
      for (std::size_t k = 0; k < count; ++k) {
        const unsigned v = bytes == 2 ? (in[2 * k] << 8) | in[2 * k + 1] : in[k];
        if (v > maxval) throw outOfRange(k, v, maxval);
        image.samples[k] = static_cast<std::uint16_t>(v);
      }
    }
    return image;
  }

 private:
  // Skips white space and comments (from '#' to the end of the line).
  void skipSpace() {
    while (pos_ < data_.size()) {
      const char c = data_[pos_];
      if (c == '#') {
        while (pos_ < data_.size() && data_[pos_] != '\n' && data_[pos_] != '\r') ++pos_;
      } else if (std::isspace(static_cast<unsigned char>(c))) {
        ++pos_;
      } else {
        return;
      }
    }
  }

  // A decimal number after white space, at most 10 digits; what names it in the message.
  long long number(const std::string& what) {
    skipSpace();
    const std::size_t begin = pos_;
    long long value = 0;
    while (pos_ < data_.size() && std::isdigit(static_cast<unsigned char>(data_[pos_])) &&
           pos_ - begin < 10) {
      value = value * 10 + (data_[pos_++] - '0');
    }
    const bool ends = pos_ == data_.size() || std::isspace(static_cast<unsigned char>(data_[pos_]));
    if (pos_ == begin || !ends) {
      std::size_t end = begin;
      while (end < data_.size() && end - begin < 12 &&
             !std::isspace(static_cast<unsigned char>(data_[end]))) {
        ++end;
      }
      const std::string found =
          end > begin ? "'" + data_.substr(begin, end - begin) + "'" : "the end of the file";
      throw SceneLoadError("PGM " + what + ": expected a number, found " + found);
    }
    return value;
  }

  std::uint16_t sample(std::size_t k, long long maxval) {
    skipSpace();
    if (pos_ == data_.size()) {
      throw SceneLoadError("PGM data cut short: " + std::to_string(k) + " of the pixels");
    }
    const long long v = number("pixel " + std::to_string(k));
    if (v > maxval) throw outOfRange(k, v, maxval);
    return static_cast<std::uint16_t>(v);
  }

  static SceneLoadError outOfRange(std::size_t k, long long v, long long maxval) {
    return SceneLoadError("PGM pixel " + std::to_string(k) + " is " + std::to_string(v) +
                          ", above maxval " + std::to_string(maxval));
  }

  std::string data_;
  std::size_t pos_ = 0;
};

// ---------------------------------------------------------------------------------------------------
// PNG through libpng. Its errors long-jump back to pngRead's setjmp, so that function holds only
// what a long jump may skip over: the image it fills lives in its caller.

struct PngState {
  std::FILE* file = nullptr;
  png_structp png = nullptr;
  png_infop info = nullptr;
  char message[256] = "";
};

void pngError(png_structp png, png_const_charp message) {
  auto* state = static_cast<PngState*>(png_get_error_ptr(png));
  std::snprintf(state->message, sizeof state->message, "%s", message);
  png_longjmp(png, 1);
}

void pngWarning(png_structp, png_const_charp) {}  // libpng's warnings are not errors

// Deflate compresses at most 1032 to 1: a PNG's rows, filter bytes included, are never more than
// this many times its file (plus a little for the smallest files).
constexpr double kMaxInflation = 1032;

// Fills image (its samples sized here) and returns true, or returns false with state->message.
// file_bytes: the file's size.
bool pngRead(PngState* state, double file_bytes, Image* image, std::vector<png_bytep>* rows) {
  if (setjmp(png_jmpbuf(state->png))) return false;
  png_init_io(state->png, state->file);
  png_read_info(state->png, state->info);
  // A header that promises more pixels than the file can hold is refused before anything is
  // allocated for them.
  const double stored = double(png_get_image_height(state->png, state->info)) *
                        (double(png_get_rowbytes(state->png, state->info)) + 1);
  if (stored > kMaxInflation * file_bytes + 4096) {
    std::snprintf(state->message, sizeof state->message,
                  "%u x %u pixels cannot be held in a file of %.0f bytes",
                  png_get_image_width(state->png, state->info),
                  png_get_image_height(state->png, state->info), file_bytes);
    return false;
  }
  // Palettes to RGB, grey of 1, 2 or 4 bits to 8, a transparent colour to an alpha channel; 16-bit
  // samples stay 16-bit. No gamma correction: the samples are taken as stored, as map_server does.
  png_set_expand(state->png);
  png_read_update_info(state->png, state->info);
  const png_uint_32 width = png_get_image_width(state->png, state->info);
  const png_uint_32 height = png_get_image_height(state->png, state->info);
  const int type = png_get_color_type(state->png, state->info);
  const int depth = png_get_bit_depth(state->png, state->info);
  const int channels = png_get_channels(state->png, state->info);
  if (!(width > 0 && height > 0) || double(width) * height > kMaxPixels) {
    std::snprintf(state->message, sizeof state->message, "an image of %u x %u pixels", width,
                  height);
    return false;
  }
  image->width = static_cast<int>(width);
  image->height = static_cast<int>(height);
  image->colors = (type & PNG_COLOR_MASK_COLOR) ? 3 : 1;
  image->alpha = (type & PNG_COLOR_MASK_ALPHA) != 0;
  image->maxval = depth == 16 ? 65535 : 255;
  if (channels != image->channels()) {
    std::snprintf(state->message, sizeof state->message, "%d channels for colour type %d", channels,
                  type);
    return false;
  }
  const std::size_t row_bytes = png_get_rowbytes(state->png, state->info);
  // The decoded rows go into the samples' storage and are widened in place afterwards: a 16-bit
  // sample is two bytes there already, an 8-bit one is spread from the back.
  image->samples.resize(static_cast<std::size_t>(width) * height * channels);
  rows->resize(height);
  auto* bytes = reinterpret_cast<png_bytep>(image->samples.data());
  const std::size_t stride = static_cast<std::size_t>(width) * channels * 2;
  if (row_bytes > stride) {
    std::snprintf(state->message, sizeof state->message, "rows of %zu bytes", row_bytes);
    return false;
  }
  for (png_uint_32 y = 0; y < height; ++y) (*rows)[y] = bytes + y * stride;
  png_read_image(state->png, rows->data());
  png_read_end(state->png, nullptr);
  for (png_uint_32 y = 0; y < height; ++y) {
    const png_bytep in = (*rows)[y];
    std::uint16_t* out = image->samples.data() + static_cast<std::size_t>(y) * width * channels;
    const std::size_t n = static_cast<std::size_t>(width) * channels;
    if (depth == 16) {
      for (std::size_t k = 0; k < n; ++k)
        out[k] = static_cast<std::uint16_t>(in[2 * k] << 8 | in[2 * k + 1]);
    } else {
      for (std::size_t k = n; k-- > 0;) out[k] = in[k];  // back to front: out overlaps in
    }
  }
  return true;
}

Image readPng(const std::string& path, double file_bytes) {
  PngState state;
  state.file = std::fopen(path.c_str(), "rb");
  if (!state.file) throw SceneLoadError("cannot open the image for reading");
  state.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &state, pngError, pngWarning);
  if (state.png) state.info = png_create_info_struct(state.png);
  Image image;
  std::vector<png_bytep> rows;
  const bool ok = state.png && state.info && pngRead(&state, file_bytes, &image, &rows);
  png_destroy_read_struct(state.png ? &state.png : nullptr, state.info ? &state.info : nullptr,
                          nullptr);
  std::fclose(state.file);
  if (!ok) throw SceneLoadError(std::string("bad PNG: ") + state.message);
  return image;
}

}  // namespace

Image read(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneLoadError("cannot open the image for reading");
  char magic[8] = {};
  in.read(magic, sizeof magic);
  if (in.gcount() == sizeof magic &&
      png_sig_cmp(reinterpret_cast<png_const_bytep>(magic), 0, 8) == 0) {
    in.seekg(0, std::ios::end);
    return readPng(path, static_cast<double>(in.tellg()));
  }
  if (in.gcount() >= 2 && magic[0] == 'P' && (magic[1] == '5' || magic[1] == '2')) {
    in.seekg(0);
    std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    return PgmReader(std::move(data)).read();
  }
  throw SceneLoadError("the image is neither PGM (P5 or P2) nor PNG");
}

}  // namespace map_image
}  // namespace laser_raycast
