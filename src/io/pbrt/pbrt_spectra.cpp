#include "io/pbrt/pbrt_spectra.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "core/error.h"
#include "io/byte_stream.h"
#include "io/pbrt/pbrt_params.h"

namespace ferry {
namespace {

constexpr float kLambdaMin = 360, kLambdaMax = 830;

float lobe(float x, float mu, float sigmaLow, float sigmaHigh) {
  float t = (x - mu) / (x < mu ? sigmaLow : sigmaHigh);
  return std::exp(-0.5f * t * t);
}

Vec3f cmf(float nm) {
  float x = 1.056f * lobe(nm, 599.8f, 37.9f, 31.0f) + 0.362f * lobe(nm, 442.0f, 16.0f, 26.7f) -
            0.065f * lobe(nm, 501.1f, 20.4f, 26.2f);
  float y = 0.821f * lobe(nm, 568.8f, 46.9f, 40.5f) + 0.286f * lobe(nm, 530.9f, 16.3f, 31.1f);
  float z = 1.217f * lobe(nm, 437.0f, 11.8f, 36.0f) + 0.681f * lobe(nm, 459.0f, 26.0f, 13.8f);
  return {x, y, z};
}

float yIntegral() {
  static const float integral = [] {
    double sum = 0;
    for (float l = kLambdaMin; l <= kLambdaMax; l += 1) sum += cmf(l).y;
    return float(sum);
  }();
  return integral;
}

template <typename F>
Vec3f integrateXyz(F&& spectrum) {
  double x = 0, y = 0, z = 0;
  for (float l = kLambdaMin; l <= kLambdaMax; l += 1) {
    Vec3f c = cmf(l);
    double s = spectrum(l);
    x += c.x * s;
    y += c.y * s;
    z += c.z * s;
  }
  float n = yIntegral();
  return {float(x / n), float(y / n), float(z / n)};
}

Vec3f xyzToLinearSrgb(Vec3f c) {
  return {3.2404542f * c.x - 1.5371385f * c.y - 0.4985314f * c.z,
          -0.9692660f * c.x + 1.8760108f * c.y + 0.0415560f * c.z,
          0.0556434f * c.x - 0.2040259f * c.y + 1.0572252f * c.z};
}

// RGB of the constant spectrum 1, for white-balancing reflectances.
Vec3f whiteRgb() {
  static const Vec3f white = xyzToLinearSrgb(integrateXyz([](float) { return 1.0; }));
  return white;
}

SampledSpectrum table(std::initializer_list<float> values) {
  SampledSpectrum s;
  float l = 400;
  for (float v : values) {
    s.lambda.push_back(l);
    s.value.push_back(v);
    l += 50;
  }
  return s;
}

SampledSpectrum constant(float v) {
  return SampledSpectrum{{550.0f}, {v}};
}

}  // namespace

float SampledSpectrum::at(float nm) const {
  if (lambda.empty()) return 0;
  if (nm <= lambda.front()) return value.front();
  if (nm >= lambda.back()) return value.back();
  auto it = std::upper_bound(lambda.begin(), lambda.end(), nm);
  size_t i = size_t(it - lambda.begin()) - 1;
  float t = (nm - lambda[i]) / (lambda[i + 1] - lambda[i]);
  return value[i] * (1 - t) + value[i + 1] * t;
}

std::optional<SampledSpectrum> SampledSpectrum::fromInterleaved(const std::vector<float>& pairs) {
  if (pairs.size() < 2 || pairs.size() % 2 != 0) return std::nullopt;
  SampledSpectrum s;
  for (size_t i = 0; i < pairs.size(); i += 2) {
    if (!s.lambda.empty() && pairs[i] <= s.lambda.back()) return std::nullopt;
    s.lambda.push_back(pairs[i]);
    s.value.push_back(pairs[i + 1]);
  }
  return s;
}

Vec3f spectrumToRgb(const SampledSpectrum& s, SpectrumUse use) {
  Vec3f rgb = xyzToLinearSrgb(integrateXyz([&](float l) { return s.at(l); }));
  if (use == SpectrumUse::Reflectance) rgb = rgb / whiteRgb();
  return max(rgb, Vec3f(0));
}

float spectrumLuminance(const SampledSpectrum& s) {
  return integrateXyz([&](float l) { return s.at(l); }).y;
}

SampledSpectrum blackbodySpectrum(float kelvin) {
  SampledSpectrum s;
  if (!(kelvin > 0)) return constant(0);
  auto planck = [&](double nm) {
    const double c = 299792458.0, h = 6.62606957e-34, kb = 1.3806488e-23;
    double l = nm * 1e-9;
    return (2 * h * c * c) / (std::pow(l, 5) * (std::exp((h * c) / (l * kb * kelvin)) - 1));
  };
  double peakNm = 2.8977721e-3 / kelvin * 1e9;  // Wien's displacement law
  double peak = planck(peakNm);
  for (float l = kLambdaMin; l <= kLambdaMax; l += 5) {
    s.lambda.push_back(l);
    s.value.push_back(float(planck(l) / peak));
  }
  return s;
}

Vec3f conductorReflectance(const SampledSpectrum& eta, const SampledSpectrum& k, float outside) {
  auto f0 = [&](float l) {
    double n = eta.at(l) / outside, kk = k.at(l) / outside;
    return ((n - 1) * (n - 1) + kk * kk) / ((n + 1) * (n + 1) + kk * kk);
  };
  Vec3f rgb = xyzToLinearSrgb(integrateXyz(f0)) / whiteRgb();
  return min(max(rgb, Vec3f(0)), Vec3f(1));
}

std::optional<SampledSpectrum> namedSpectrum(std::string_view name) {
  // 400, 450, 500, 550, 600, 650, 700 nm.
  if (name == "metal-Ag-eta")
    return table({0.173f, 0.152f, 0.130f, 0.125f, 0.124f, 0.139f, 0.142f});
  if (name == "metal-Ag-k") return table({1.950f, 2.471f, 2.917f, 3.340f, 3.731f, 4.129f, 4.524f});
  if (name == "metal-Al-eta")
    return table({0.490f, 0.618f, 0.768f, 0.959f, 1.197f, 1.475f, 1.838f});
  if (name == "metal-Al-k") return table({4.860f, 5.469f, 6.079f, 6.687f, 7.257f, 7.794f, 8.314f});
  if (name == "metal-Au-eta")
    return table({1.658f, 1.509f, 0.850f, 0.350f, 0.220f, 0.167f, 0.160f});
  if (name == "metal-Au-k") return table({1.956f, 1.879f, 1.887f, 2.715f, 3.000f, 3.138f, 3.964f});
  if (name == "metal-Cu-eta")
    return table({1.175f, 1.166f, 1.134f, 0.958f, 0.390f, 0.217f, 0.215f});
  if (name == "metal-Cu-k") return table({2.130f, 2.394f, 2.575f, 2.577f, 2.943f, 3.638f, 4.164f});
  if (name == "metal-MgO-eta")
    return table({1.762f, 1.752f, 1.745f, 1.741f, 1.737f, 1.734f, 1.731f});
  if (name == "metal-MgO-k") return constant(0);
  if (name == "metal-TiO2-eta")
    return table({3.400f, 3.165f, 3.030f, 2.955f, 2.900f, 2.860f, 2.830f});
  if (name == "metal-TiO2-k") return constant(0);
  if (name == "glass-BK7") return constant(1.5185f);
  if (name == "glass-BAF10") return constant(1.6731f);
  if (name == "glass-FK51A") return constant(1.4878f);
  if (name == "glass-LASF9") return constant(1.8558f);
  if (name == "glass-F5") return constant(1.6771f);
  if (name == "glass-F10") return constant(1.7337f);
  if (name == "glass-F11") return constant(1.7911f);
  if (name == "stdillum-A") return blackbodySpectrum(2856);
  if (name == "stdillum-D50") return blackbodySpectrum(5003);
  if (name == "stdillum-D65") return blackbodySpectrum(6504);
  if (name == "stdillum-E") return constant(1);
  return std::nullopt;
}

std::string namedSpectrumList() {
  return "metal-{Ag,Al,Au,Cu,MgO,TiO2}-{eta,k}, glass-{BK7,BAF10,FK51A,LASF9,F5,F10,F11}, "
         "stdillum-{A,D50,D65,E}";
}

SampledSpectrum readSpdFile(const std::string& path) {
  ByteStream in = ByteStream::openFile(path);
  if (in.size() > (uint64_t(64) << 20))
    throw InputError(fmt::format("{}: {} bytes is too large for a spectrum file", path, in.size()));
  std::vector<float> values;
  std::string word;
  int line = 1, wordLine = 1;
  auto flush = [&]() {
    if (word.empty()) return;
    std::optional<double> v = parsePbrtNumber(word);
    if (!v)
      throw InputError(SourceLocation{path, wordLine}, fmt::format("'{}' is not a number", word));
    values.push_back(float(*v));
    word.clear();
  };
  for (int c; (c = in.get()) >= 0;) {
    if (c == '#') {
      flush();
      while ((c = in.get()) >= 0 && c != '\n') {
      }
      ++line;
      continue;
    }
    if (c == '\n') {
      flush();
      ++line;
    } else if (c == ' ' || c == '\t' || c == '\r' || c == ',') {
      flush();
    } else {
      if (c == 0) throw InputError(SourceLocation{path, line}, "NUL byte: not a text file");
      if (word.empty()) wordLine = line;
      if (word.size() > 64) throw InputError(SourceLocation{path, line}, "not a spectrum file");
      word.push_back(char(c));
    }
  }
  flush();
  if (values.empty()) throw InputError(fmt::format("{}: no values: not a spectrum file", path));
  if (values.size() % 2 != 0)
    throw InputError(fmt::format("{}: {} numbers: a spectrum file needs wavelength-value pairs",
                                 path, values.size()));
  auto s = SampledSpectrum::fromInterleaved(values);
  if (!s) throw InputError(fmt::format("{}: wavelengths must increase", path));
  return *s;
}

}  // namespace ferry
