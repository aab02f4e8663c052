#include "render/image.h"

#include <png.h>

#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>

#include "format/file_io.h"

namespace gtn {

namespace {
// libpng reports errors through longjmp; the message is kept here for the Status.
struct PngErrorState {
  std::string message;
};

void pngError(png_structp png, png_const_charp msg) {
  auto* state = static_cast<PngErrorState*>(png_get_error_ptr(png));
  if (state) state->message = msg;
  png_longjmp(png, 1);
}
void pngWarning(png_structp, png_const_charp) {}

struct MemoryReader {
  const std::string* data;
  size_t pos;
};
void readFromMemory(png_structp png, png_bytep out, png_size_t n) {
  auto* r = static_cast<MemoryReader*>(png_get_io_ptr(png));
  if (r->pos + n > r->data->size()) png_error(png, "file is truncated");
  std::memcpy(out, r->data->data() + r->pos, n);
  r->pos += n;
}

// Writes the PNG to `file`; a plain function so no C++ object with a destructor lives across setjmp.
Status writePngStream(std::FILE* file, const Image& image, const std::string& path) {
  PngErrorState state;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &state, pngError, pngWarning);
  if (!png) return ioError(path + ": cannot create a PNG writer");
  png_infop info = png_create_info_struct(png);
  if (!info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return ioError(path + ": cannot write PNG: " + state.message);
  }
  png_init_io(png, file);
  // Rendered images are small and written once per run: favour speed (level 1 costs a few percent
  // of size against the default 6, at a fraction of the time).
  png_set_compression_level(png, 1);
  png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB);
  png_set_IHDR(png, info, static_cast<png_uint_32>(image.width), static_cast<png_uint_32>(image.height), 8,
               PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int y = 0; y < image.height; ++y) png_write_row(png, const_cast<png_bytep>(image.pixel(0, y)));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return Status::ok();
}
}  // namespace

Status writePng(const std::string& path, const Image& image) {
  if (image.width <= 0 || image.height <= 0 || image.rgb.size() != static_cast<size_t>(image.width) * image.height * 3)
    return usageError(path + ": image has no pixels or an inconsistent size");
  return writeFileAtomically(path, [&](std::FILE* f) { return writePngStream(f, image, path); });
}

StatusOr<Image> readPng(const std::string& path) {
  GTN_ASSIGN_OR_RETURN(std::string bytes, readWholeFile(path, uint64_t{1} << 31));
  if (bytes.size() < 8 || png_sig_cmp(reinterpret_cast<png_const_bytep>(bytes.data()), 0, 8) != 0)
    return Status(StatusCode::kNotOurFile, path + ": not a PNG file (bad signature)");
  PngErrorState state;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &state, pngError, pngWarning);
  if (!png) return ioError(path + ": cannot create a PNG reader");
  png_infop info = png_create_info_struct(png);
  MemoryReader reader{&bytes, 0};
  Image* image = new Image();  // raw pointer: no destructor may be skipped by longjmp
  std::vector<png_bytep>* rows = new std::vector<png_bytep>();
  if (!info || setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    delete image;
    delete rows;
    return invalidData(path + ": corrupt PNG: " + state.message);
  }
  png_set_read_fn(png, &reader, readFromMemory);
  png_read_info(png, info);
  const png_uint_32 w = png_get_image_width(png, info), h = png_get_image_height(png, info);
  // Bound the allocation by what a PNG of this size could plausibly decompress to.
  if (w == 0 || h == 0 || static_cast<uint64_t>(w) * h > (uint64_t{1} << 28)) png_error(png, "image size out of range");
  png_set_strip_16(png);
  // Transparency is composited over black, the renderers' background: a transparent pixel is
  // background (stripping the alpha kept its colour).
  png_color_16 black{};
  png_set_background(png, &black, PNG_BACKGROUND_GAMMA_SCREEN, 0, 1.0);
  png_set_palette_to_rgb(png);
  png_set_expand_gray_1_2_4_to_8(png);
  png_set_gray_to_rgb(png);
  png_read_update_info(png, info);
  if (png_get_rowbytes(png, info) != static_cast<size_t>(w) * 3) png_error(png, "unexpected pixel layout");
  image->width = static_cast<int>(w);
  image->height = static_cast<int>(h);
  image->rgb.assign(static_cast<size_t>(w) * h * 3, 0);
  rows->resize(h);
  for (png_uint_32 y = 0; y < h; ++y) (*rows)[y] = image->pixel(0, static_cast<int>(y));
  png_read_image(png, rows->data());
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  Image result = std::move(*image);
  delete image;
  delete rows;
  return result;
}

StatusOr<ImageDifference> compareImages(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height)
    return usageError("images differ in size: " + std::to_string(a.width) + "x" + std::to_string(a.height) + " and " +
                      std::to_string(b.width) + "x" + std::to_string(b.height));
  ImageDifference d;
  double sum = 0;
  const size_t n = static_cast<size_t>(a.width) * a.height;
  for (size_t i = 0; i < n; ++i) {
    const uint8_t* pa = a.rgb.data() + 3 * i;
    const uint8_t* pb = b.rgb.data() + 3 * i;
    const bool bg_a = pa[0] == 0 && pa[1] == 0 && pa[2] == 0;
    const bool bg_b = pb[0] == 0 && pb[1] == 0 && pb[2] == 0;
    for (int c = 0; c < 3; ++c) {
      const int diff = std::abs(static_cast<int>(pa[c]) - static_cast<int>(pb[c]));
      if (diff > d.max_difference) d.max_difference = diff;
    }
    if (bg_a && bg_b) continue;
    ++d.pixels;
    for (int c = 0; c < 3; ++c) {
      const double diff = static_cast<double>(pa[c]) - pb[c];
      sum += diff * diff;
    }
  }
  d.rmse = d.pixels ? std::sqrt(sum / (3.0 * d.pixels)) : 0.0;
  d.psnr = d.rmse > 0 ? 20.0 * std::log10(255.0 / d.rmse) : std::numeric_limits<double>::infinity();
  return d;
}

}  // namespace gtn
