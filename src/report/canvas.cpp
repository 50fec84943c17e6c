#include "report/canvas.h"

#include <stb/stb_easy_font.h>

#include <algorithm>
#include <cmath>

namespace ferry {

Canvas::Canvas(int width, int height, Rgba background)
    : width_(width), height_(height), pixels_(size_t(width) * size_t(height) * 4) {
  for (size_t i = 0; i < pixels_.size(); i += 4) {
    pixels_[i] = background.r;
    pixels_[i + 1] = background.g;
    pixels_[i + 2] = background.b;
    pixels_[i + 3] = background.a;
  }
}

Rgba Canvas::at(int x, int y) const {
  const uint8_t* p = &pixels_[(size_t(y) * width_ + x) * 4];
  return {p[0], p[1], p[2], p[3]};
}

void Canvas::blend(int x, int y, Rgba c, float opacity) {
  if (x < 0 || y < 0 || x >= width_ || y >= height_) return;
  const float a = std::clamp(opacity * float(c.a) / 255.0f, 0.0f, 1.0f);
  uint8_t* p = &pixels_[(size_t(y) * width_ + x) * 4];
  p[0] = uint8_t(std::lround(p[0] * (1 - a) + c.r * a));
  p[1] = uint8_t(std::lround(p[1] * (1 - a) + c.g * a));
  p[2] = uint8_t(std::lround(p[2] * (1 - a) + c.b * a));
  p[3] = uint8_t(std::max<int>(p[3], std::lround(255 * a)));
}

void Canvas::fillRect(int x0, int y0, int x1, int y1, Rgba c, float opacity) {
  for (int y = std::max(0, y0); y < std::min(height_, y1); ++y)
    for (int x = std::max(0, x0); x < std::min(width_, x1); ++x) blend(x, y, c, opacity);
}

void Canvas::line(float x0, float y0, float x1, float y1, Rgba c, float thickness, float opacity,
                  float dash) {
  const float dx = x1 - x0, dy = y1 - y0;
  const float length = std::sqrt(dx * dx + dy * dy);
  const int steps = std::max(1, int(std::ceil(length * 2)));
  const int half = std::max(0, int(std::lround(thickness)) - 1) / 2;
  const int extra = std::max(0, int(std::lround(thickness)) - 1) - half;
  int lastX = INT32_MIN, lastY = INT32_MIN;
  for (int s = 0; s <= steps; ++s) {
    const float t = float(s) / float(steps);
    if (dash > 0 && std::fmod(t * length, 2 * dash) >= dash) continue;
    const int x = int(std::floor(x0 + dx * t)), y = int(std::floor(y0 + dy * t));
    if (x == lastX && y == lastY) continue;
    lastX = x;
    lastY = y;
    for (int oy = -half; oy <= extra; ++oy)
      for (int ox = -half; ox <= extra; ++ox) blend(x + ox, y + oy, c, opacity);
  }
}

void Canvas::text(int x, int y, const std::string& s, Rgba c, int scale) {
  std::vector<char> buffer(s.size() * 300 + 1024);
  std::string copy = s;
  const int quads =
      stb_easy_font_print(0, 0, copy.data(), nullptr, buffer.data(), int(buffer.size()));
  const float* v = reinterpret_cast<const float*>(buffer.data());
  for (int q = 0; q < quads; ++q) {
    // 4 vertices of 16 bytes (x, y, z, rgba): take the quad's extent.
    const float* quad = v + q * 16;
    float qx0 = quad[0], qy0 = quad[1], qx1 = quad[0], qy1 = quad[1];
    for (int k = 1; k < 4; ++k) {
      qx0 = std::min(qx0, quad[k * 4]);
      qx1 = std::max(qx1, quad[k * 4]);
      qy0 = std::min(qy0, quad[k * 4 + 1]);
      qy1 = std::max(qy1, quad[k * 4 + 1]);
    }
    fillRect(x + int(std::lround(qx0 * scale)), y + int(std::lround(qy0 * scale)),
             x + int(std::lround(qx1 * scale)), y + int(std::lround(qy1 * scale)), c);
  }
}

int Canvas::textWidth(const std::string& s, int scale) {
  std::string copy = s;
  return stb_easy_font_width(copy.data()) * scale;
}

Rgba rankColor(int rank) {
  static const Rgba palette[16] = {
      {230, 25, 75, 255},   {60, 180, 75, 255},   {0, 130, 200, 255},  {245, 130, 48, 255},
      {145, 30, 180, 255},  {70, 200, 200, 255},  {240, 50, 230, 255}, {170, 200, 40, 255},
      {250, 190, 190, 255}, {0, 128, 128, 255},   {150, 110, 60, 255}, {255, 225, 25, 255},
      {128, 0, 0, 255},     {100, 220, 150, 255}, {128, 128, 0, 255},  {0, 0, 128, 255}};
  return palette[((rank % 16) + 16) % 16];
}

}  // namespace ferry
