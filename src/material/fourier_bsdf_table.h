// A tabulated isotropic BSDF in pbrt-v3's spline x Fourier basis (Jakob et
// al. 2014, "A Comprehensive Framework for Rendering Layered Materials"; the
// `.bsdf` files of layerlab and pbrt-v3's `fourier` material).
//
// For the cosines mu_i = cos(-wi) and mu_o = cos(wo) on the grid `mu`, entry
// (i, o) holds order(i, o) Fourier coefficients per channel of
// f(wi, wo) |mu_i| as a series in cos(phi), phi the azimuth between -wi and
// wo; between grid points the coefficients are Catmull-Rom interpolated in
// both cosines. Channels: 1 (luminance) or 3 (luminance, red, blue: green is
// derived, as pbrt-v3 does). Row o of `cdf` is the running integral over
// mu_i of the zeroth coefficient (luminance), which sampling inverts.
//
// The table is the scene's (Scene::bsdfTables, shared: materials name it by
// index); reading it is io/pbrt/fourier_bsdf_file, evaluating it
// render/fourier_bsdf.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace ferry {

struct FourierBsdfTable {
  // Evaluation sums series on the stack; layerlab's tables stay far below
  // (paint.bsdf: 74).
  static constexpr int32_t kMaxOrder = 1024;
  std::string name;  // the file it came from, for messages
  int32_t nMu = 0;
  int32_t nChannels = 0;
  int32_t mMax = 0;                 // the longest series in the table
  float eta = 1;                    // relative index of refraction, bottom over top
  std::vector<float> mu;            // nMu, increasing, in [-1, 1]
  std::vector<float> cdf;           // nMu * nMu, row o = mu_o
  std::vector<uint32_t> offset;     // nMu * nMu: where entry (i, o)'s coefficients start
  std::vector<int32_t> order;       // nMu * nMu: its series length
  std::vector<float> coefficients;  // order * nChannels per entry, channel after channel
  // Derived (finish()): each entry's zeroth luminance coefficient, 1/k,
  // whether any entry has light on the far side (mu_i mu_o > 0), and whether
  // the bottom reflects (mu_o < 0 < mu_i): its two sides then scatter
  // differently (paint.bsdf: a glossy coat of albedo 0.4 on top, a
  // Lambertian 0.6 beneath).
  std::vector<float> a0;
  std::vector<float> recip;
  bool hasTransmission = false;
  bool hasBackSide = false;

  size_t entry(int32_t i, int32_t o) const { return size_t(o) * size_t(nMu) + size_t(i); }
  // Entry (i, o)'s coefficients (channel c starts at c * m).
  const float* coefficientsAt(int32_t i, int32_t o, int32_t& m) const {
    const size_t e = entry(i, o);
    m = order[e];
    return coefficients.data() + offset[e];
  }
  // pbrt-v3's tables with eta != 1 describe an interface light crosses; any
  // table with light on the far side transmits.
  bool transmits() const { return eta != 1 || hasTransmission; }
  // Whether the side a ray arrives on matters: pbrt-v3 reads the table in its
  // shading frame, so a ray from below the shading normal sees the bottom.
  bool sided() const { return transmits() || hasBackSide; }

  // Checks every size, index and number, then computes the derived arrays;
  // returns what is wrong ("" when nothing): the reader and the part file
  // reader turn it into an InputError naming the file.
  std::string finish();
  uint64_t bytes() const;
};

}  // namespace ferry
