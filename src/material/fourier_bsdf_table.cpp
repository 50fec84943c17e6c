#include "material/fourier_bsdf_table.h"

#include <cmath>

#include <fmt/format.h>

namespace ferry {

std::string FourierBsdfTable::finish() {
  // Catmull-Rom needs two nodes; pbrt-v3 reads only these channel counts.
  if (nMu < 2) return fmt::format("{} elevation samples (at least 2)", nMu);
  if (nChannels != 1 && nChannels != 3)
    return fmt::format("{} channels (1 or 3 are read)", nChannels);
  if (mMax < 1 || mMax > kMaxOrder)
    return fmt::format("longest series {} (1 to {})", mMax, kMaxOrder);
  if (!(std::isfinite(eta) && eta > 0)) return fmt::format("eta {} (positive)", eta);
  const size_t entries = size_t(nMu) * size_t(nMu);
  if (mu.size() != size_t(nMu) || cdf.size() != entries || offset.size() != entries ||
      order.size() != entries)
    return "array sizes do not match the header";
  for (int32_t i = 0; i < nMu; ++i) {
    if (!(mu[i] >= -1 && mu[i] <= 1)) return fmt::format("mu[{}] = {} outside [-1, 1]", i, mu[i]);
    // (Equal neighbours are allowed: layerlab's tables hold 0 twice, so
    // that no spline segment straddles the horizon.)
    if (i > 0 && !(mu[i] >= mu[i - 1])) return fmt::format("mu[{}] = {} decreases", i, mu[i]);
  }
  if (!(mu[nMu - 1] > mu[0])) return "mu spans no interval";
  for (size_t e = 0; e < entries; ++e)
    if (!std::isfinite(cdf[e])) return fmt::format("cdf entry {} is not finite", e);
  for (float c : coefficients)
    if (!std::isfinite(c)) return "a coefficient is not finite";
  a0.assign(entries, 0);
  hasTransmission = false;
  hasBackSide = false;
  for (int32_t o = 0; o < nMu; ++o)
    for (int32_t i = 0; i < nMu; ++i) {
      const size_t e = entry(i, o);
      const int64_t m = order[e];
      if (m < 0 || m > mMax)
        return fmt::format("entry ({}, {}) has series length {} (0 to {})", i, o, m, mMax);
      // 64-bit: offset + m * channels cannot wrap.
      if (uint64_t(offset[e]) + uint64_t(m) * uint64_t(nChannels) > coefficients.size())
        return fmt::format("entry ({}, {}) reads coefficients {} to {} of {}", i, o, offset[e],
                           uint64_t(offset[e]) + uint64_t(m) * uint64_t(nChannels),
                           coefficients.size());
      if (m > 0) {
        a0[e] = coefficients[offset[e]];
        if (mu[i] * mu[o] > 0 && a0[e] != 0) hasTransmission = true;
        if (mu[o] < 0 && mu[i] > 0 && a0[e] != 0) hasBackSide = true;
      }
    }
  recip.assign(size_t(mMax), 0);
  for (int32_t k = 1; k < mMax; ++k) recip[k] = 1.0f / float(k);
  return {};
}

uint64_t FourierBsdfTable::bytes() const {
  return sizeof(*this) + 4 * (mu.size() + cdf.size() + offset.size() + order.size() +
                              coefficients.size() + a0.size() + recip.size());
}

}  // namespace ferry
