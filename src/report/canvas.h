// A small RGBA canvas for the partitioning reports' pictures (the max-part
// plot, the partition pictures): filled rectangles, anti-aliasing-free lines
// with alpha, dashes and thickness, and text from stb_easy_font's bitmap
// glyphs (part of the stb package Ferry already uses). No plotting library.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/math.h"

namespace ferry {

struct Rgba {
  uint8_t r = 0, g = 0, b = 0, a = 255;
};

class Canvas {
 public:
  Canvas(int width, int height, Rgba background = {255, 255, 255, 255});
  int width() const { return width_; }
  int height() const { return height_; }
  const std::vector<uint8_t>& rgba() const { return pixels_; }

  Rgba at(int x, int y) const;
  // Blends `c` (with its alpha scaled by `opacity`) over the pixel.
  void blend(int x, int y, Rgba c, float opacity = 1.0f);
  void fillRect(int x0, int y0, int x1, int y1, Rgba c,
                float opacity = 1.0f);  // [x0, x1) x [y0, y1)
  // `dash`: 0 solid, else on/off length in pixels.
  void line(float x0, float y0, float x1, float y1, Rgba c, float thickness = 1.0f,
            float opacity = 1.0f, float dash = 0);
  // Text with its top-left corner at (x, y); `scale` multiplies the 12-pixel glyphs.
  void text(int x, int y, const std::string& s, Rgba c, int scale = 1);
  static int textWidth(const std::string& s, int scale = 1);
  static int textHeight(int scale = 1) { return 12 * scale; }

 private:
  int width_, height_;
  std::vector<uint8_t> pixels_;
};

// Distinct colours for ranks (cycling after 16).
Rgba rankColor(int rank);

}  // namespace ferry
