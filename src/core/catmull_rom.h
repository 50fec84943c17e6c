// Catmull-Rom splines through tabulated values at irregular nodes: the
// weights that interpolate them, their integral, and sampling in proportion
// to a 2D spline (what tabulated BSDFs and BSSRDFs read). The derivative at
// a node is the finite difference over its neighbours, one-sided at the ends.
#pragma once

#include <cstdint>
#include <span>

namespace ferry {

// The largest i in [0, size - 2] with pred(i) true (pred true, then false).
template <typename Pred>
int32_t findInterval(int32_t size, Pred pred) {
  int32_t first = 0, length = size;
  while (length > 0) {
    const int32_t half = length >> 1, middle = first + half;
    if (pred(middle)) {
      first = middle + 1;
      length -= half + 1;
    } else {
      length = half;
    }
  }
  return first - 1 < 0 ? 0 : (first - 1 > size - 2 ? size - 2 : first - 1);
}

// The weights of the 4 nodes from `offset` (some may be outside the table:
// their weights are then 0) that interpolate at x; false when x is outside
// the nodes.
bool catmullRomWeights(const float* nodes, int32_t n, float x, int32_t& offset, float weights[4]);

// The spline's integral from nodes[0] to each node (cdf[0] = 0; n entries);
// returns the whole integral.
float integrateCatmullRom(const float* nodes, int32_t n, const float* values, float* cdf);

// A 2D table: values[i * n2 + j] at (nodes1[i], nodes2[j]) and each row's
// cdf over nodes2 (integrateCatmullRom). Draws x in [nodes2[0], nodes2[n2 - 1]]
// with density proportional to the spline interpolated at `alpha` along
// nodes1; false when alpha is outside nodes1 or the row integrates to 0.
// `value`: the interpolated spline at x; `density`: x's density.
bool sampleCatmullRom2D(const float* nodes1, int32_t n1, const float* nodes2, int32_t n2,
                        const float* values, const float* cdf, float alpha, float u, float& x,
                        float* value = nullptr, float* density = nullptr);

}  // namespace ferry
