#include "core/catmull_rom.h"

#include <algorithm>
#include <cmath>

namespace ferry {

bool catmullRomWeights(const float* nodes, int32_t n, float x, int32_t& offset, float weights[4]) {
  if (!(x >= nodes[0] && x <= nodes[n - 1])) return false;
  const int32_t i = findInterval(n, [&](int32_t j) { return nodes[j] <= x; });
  offset = i - 1;
  const float x0 = nodes[i], x1 = nodes[i + 1];
  const float t = (x - x0) / (x1 - x0), t2 = t * t, t3 = t2 * t;
  // The Hermite basis, the derivatives at x0 and x1 taken as finite
  // differences over the neighbours (one-sided at the ends), folded into
  // the four nodes' weights.
  weights[1] = 2 * t3 - 3 * t2 + 1;
  weights[2] = -2 * t3 + 3 * t2;
  const float h10 = t3 - 2 * t2 + t, h11 = t3 - t2;
  if (i > 0) {
    const float w0 = h10 * (x1 - x0) / (x1 - nodes[i - 1]);
    weights[0] = -w0;
    weights[2] += w0;
  } else {
    weights[0] = 0;
    weights[1] -= h10;
    weights[2] += h10;
  }
  if (i + 2 < n) {
    const float w3 = h11 * (x1 - x0) / (nodes[i + 2] - x0);
    weights[1] -= w3;
    weights[3] = w3;
  } else {
    weights[1] -= h11;
    weights[2] += h11;
    weights[3] = 0;
  }
  return true;
}

float integrateCatmullRom(const float* nodes, int32_t n, const float* values, float* cdf) {
  float sum = 0;
  cdf[0] = 0;
  for (int32_t i = 0; i + 1 < n; ++i) {
    const float x0 = nodes[i], x1 = nodes[i + 1], f0 = values[i], f1 = values[i + 1];
    const float width = x1 - x0;
    const float d0 = i > 0 ? width * (f1 - values[i - 1]) / (x1 - nodes[i - 1]) : f1 - f0;
    const float d1 = i + 2 < n ? width * (values[i + 2] - f0) / (nodes[i + 2] - x0) : f1 - f0;
    // The Hermite cubic's integral over the segment.
    sum += ((d0 - d1) * (1.0f / 12.0f) + (f0 + f1) * 0.5f) * width;
    cdf[i + 1] = sum;
  }
  return sum;
}

// The row interpolated at alpha picks the segment through its cdf; Newton's
// method with bisection inverts the segment's integral.
bool sampleCatmullRom2D(const float* nodes1, int32_t n1, const float* nodes2, int32_t n2,
                        const float* values, const float* cdf, float alpha, float u, float& x,
                        float* value, float* density) {
  int32_t offset;
  float w[4];
  if (!catmullRomWeights(nodes1, n1, alpha, offset, w)) return false;
  auto at = [&](const float* array, int32_t i) {
    float v = 0;
    for (int32_t k = 0; k < 4; ++k)
      if (w[k] != 0) v += array[size_t(offset + k) * size_t(n2) + size_t(i)] * w[k];
    return v;
  };
  const float total = at(cdf, n2 - 1);
  if (!(total > 0)) return false;
  u *= total;
  const int32_t i = findInterval(n2, [&](int32_t j) { return at(cdf, j) <= u; });
  const float f0 = at(values, i), f1 = at(values, i + 1);
  const float x0 = nodes2[i], x1 = nodes2[i + 1], width = x1 - x0;
  if (!(width > 0)) {  // a repeated node
    x = x0;
    if (value) *value = f0;
    if (density) *density = 0;
    return true;
  }
  u = (u - at(cdf, i)) / width;
  const float d0 = i > 0 ? width * (f1 - at(values, i - 1)) / (x1 - nodes2[i - 1]) : f1 - f0;
  const float d1 = i + 2 < n2 ? width * (at(values, i + 2) - f0) / (nodes2[i + 2] - x0) : f1 - f0;
  // First guess: invert the linear interpolant's integral.
  float s =
      f0 != f1 ? (f0 - std::sqrt(std::max(0.0f, f0 * f0 + 2 * u * (f1 - f0)))) / (f0 - f1) : u / f0;
  float lo = 0, hi = 1, f = f0;
  for (int iteration = 0; iteration < 100; ++iteration) {
    if (!(s >= lo && s <= hi)) s = 0.5f * (lo + hi);
    // The Hermite cubic's integral from 0 to s (F) and the cubic (f).
    const float F = s * (f0 + s * (0.5f * d0 + s * ((1.0f / 3.0f) * (-2 * d0 - d1) + f1 - f0 +
                                                    s * (0.25f * (d0 + d1) + 0.5f * (f0 - f1)))));
    f = f0 + s * (d0 + s * (-2 * d0 - d1 + 3 * (f1 - f0) + s * (d0 + d1 + 2 * (f0 - f1))));
    if (std::abs(F - u) < 1e-6f || hi - lo < 1e-6f) break;
    if (F - u < 0)
      lo = s;
    else
      hi = s;
    s -= (F - u) / f;
  }
  x = x0 + width * std::clamp(s, 0.0f, 1.0f);
  if (value) *value = f;
  if (density) *density = f / total;
  return true;
}

}  // namespace ferry
