// Spectra to RGB for the pbrt loader: Ferry renders in linear sRGB, pbrt
// scenes give colours as spectra too (sampled lists, .spd files, pbrt-v4's
// named spectra, blackbody temperatures).
//
// Colour matching uses the CIE 1931 2-degree observer in the multi-lobe
// Gaussian fit of Wyman, Sloan and Shirley (JCGT 2013), accurate to about 1%
// of the tables, integrated from 360 to 830 nm in 1 nm steps.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/math.h"

namespace ferry {

// A piecewise-linear spectrum; constant beyond its ends.
struct SampledSpectrum {
  std::vector<float> lambda;  // nm, increasing
  std::vector<float> value;

  float at(float nm) const;
  bool empty() const { return lambda.empty(); }
  // From pbrt's interleaved "lambda value lambda value ..." list; nullopt if the
  // wavelengths do not increase.
  static std::optional<SampledSpectrum> fromInterleaved(const std::vector<float>& pairs);
};

// How a spectrum becomes RGB.
enum class SpectrumUse {
  // A reflectance: white-balanced so that the constant 1 becomes RGB (1, 1, 1).
  Reflectance,
  // Emitted radiance: XYZ / integral of y-bar, then sRGB (pbrt's convention).
  Illuminant,
};

Vec3f spectrumToRgb(const SampledSpectrum& s, SpectrumUse use);
float spectrumLuminance(const SampledSpectrum& s);  // Y, same normalisation as Illuminant

// pbrt-v4's named spectra: metal-{Ag,Al,Au,Cu,MgO,TiO2}-{eta,k},
// glass-{BK7,BAF10,FK51A,LASF9,F5,F10,F11} and stdillum-{A,D50,D65,E}.
// Metals and glasses are tabulated from 400 to 700 nm every 50 nm from the
// measured data pbrt ships (refractiveindex.info, CC0); stdillum-A is a
// 2856 K blackbody (its definition), D50 and D65 are daylight approximated by
// the blackbody of their correlated colour temperature, E is constant.
std::optional<SampledSpectrum> namedSpectrum(std::string_view name);
// The names namedSpectrum() knows, for messages.
std::string namedSpectrumList();

// Planck's law, normalised to 1 at its peak (pbrt's BlackbodyNormalized).
SampledSpectrum blackbodySpectrum(float kelvin);

// The reflectance at normal incidence of a conductor with complex index
// eta + i k, per wavelength, then to RGB as a reflectance.
// `outside`: the index of what the conductor is seen from (1: air; a coat's
// index under pbrt-v4's coatedconductor, which divides eta and k by it).
Vec3f conductorReflectance(const SampledSpectrum& eta, const SampledSpectrum& k, float outside = 1);

// An .spd file: "lambda value" pairs, whitespace separated, '#' comments.
// Throws InputError at file:line for anything else, an odd count or
// wavelengths that do not increase.
SampledSpectrum readSpdFile(const std::string& path);

}  // namespace ferry
