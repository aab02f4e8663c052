// 8-bit RGB images: PNG output (libpng, written atomically) and input, and the image difference
// metrics of the paper's section 6.3.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "mesh/status.h"

namespace gtn {

struct Image {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;  // row-major from the top-left, 3 bytes per pixel

  Image() = default;
  Image(int w, int h) : width(w), height(h), rgb(static_cast<size_t>(w) * h * 3, 0) {}
  uint8_t* pixel(int x, int y) { return rgb.data() + (static_cast<size_t>(y) * width + x) * 3; }
  const uint8_t* pixel(int x, int y) const { return rgb.data() + (static_cast<size_t>(y) * width + x) * 3; }
};

// Writes an 8-bit RGB PNG atomically ("-" writes to standard output).
Status writePng(const std::string& path, const Image& image);
// Reads a PNG of any libpng-supported layout, converted to 8-bit RGB (alpha and 16-bit are reduced).
StatusOr<Image> readPng(const std::string& path);

struct ImageDifference {
  uint64_t pixels = 0;     // pixels compared: those not background (black) in either image
  double rmse = 0;         // over the compared pixels and their three channels, 0-255 scale
  double psnr = 0;         // 20 log10(255 / rmse); infinity when rmse is 0
  int max_difference = 0;  // largest absolute channel difference over all pixels
};

// The paper's metric: RMSE excluding pixels that are black in both images (no ray contribution).
// Fails with kUsage when the sizes differ.
StatusOr<ImageDifference> compareImages(const Image& a, const Image& b);

}  // namespace gtn
