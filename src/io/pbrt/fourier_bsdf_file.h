// pbrt-v3's tabulated BSDF files (`.bsdf`, its `fourier` material; written by
// layerlab), read as pbrt-v3's FourierBSDFTable::Read reads them: a 64-byte
// header ("SCATFUN", version 1, flags, nMu, nCoeffs, mMax, nChannels,
// nBases, three metadata counts, eta, two roughnesses and padding), then mu,
// cdf, the offset and length of each entry's series, and the coefficients,
// all little-endian 32-bit. Read, like pbrt-v3: flags 1 (a BSDF), one basis
// (untextured), 1 or 3 channels. Not read, like pbrt-v3: harmonic
// extrapolation (flag 2), textured tables (nBases > 1), the metadata after
// the coefficients and the roughnesses.
//
// Every size is checked against the file's size before anything is
// allocated, and every entry's series against the coefficients; anything
// else is one InputError naming the file.
#pragma once

#include <memory>
#include <string>

#include "io/byte_stream.h"
#include "material/fourier_bsdf_table.h"

namespace ferry {

std::shared_ptr<const FourierBsdfTable> readFourierBsdfFile(const std::string& path);
// The same from an open stream (tests, the malformed corpus).
std::shared_ptr<const FourierBsdfTable> readFourierBsdf(ByteStream& in);

}  // namespace ferry
