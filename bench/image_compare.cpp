// Compares a Ferry render with a reference render of the same scene by another
// renderer (../shared/references), for bench/fidelity (issue 14, item 6).
//
// Both images are box-averaged to a common comparison resolution (by default
// a quarter of the reference's width and height: the reference's own noise
// and Ferry's per-pixel noise both average down, and a 256x256 render of a
// 1024x1024 reference needs no resampling), then averaged again over BxB
// blocks. Three figures come out:
//   bias   per channel, mean(image) / mean(reference) - 1: energy gained or
//          lost over the whole picture, which noise does not move (only its
//          mean matters), so a few percent of bias is a real difference;
//   block relative RMSE   sqrt(mean over blocks and channels of (F_b - R_b)^2)
//          divided by the mean over blocks and channels of R_b: where the
//          energy is, at a scale coarse enough that per-pixel noise is small,
//          so a wrong shadow or a missing highlight counts and Monte Carlo
//          noise counts little;
//   p99 ratio   the 99th-percentile pixel luminance, image over reference:
//          fireflies (a heavy tail) read far above 1.
// One normalisation for all blocks (the mean, not each block's own value)
// keeps dark blocks, where a relative error is mostly noise, from dominating.
//
// The side-by-side PNG (reference | image | difference) is for looking:
// the first two are tone mapped identically (one linear scale, clamped,
// sRGB), the third is the signed luminance difference relative to the
// reference's mean luminance, so that it shows what the RMSE weighs.
#include <fmt/format.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <fstream>
#include <limits>
#include <string>
#include <tuple>
#include <vector>

#include "core/error.h"
#include "io/images/image_io.h"
#include "render/camera.h"

namespace {

using namespace ferry;

struct Options {
  std::string reference;
  std::string image;
  std::string size;  // WxH; empty: a quarter of the reference's
  int block = 4;
  std::string sideBySide;
  std::string json;
  float exposure = 0;         // stops on top of the automatic scale
  float diffRange = 0.5f;     // the difference saturates at +-this times the mean luminance
  std::string referenceCrop;  // x0,x1,y0,y1: compare with this part of the reference only
  // x0,x1,y0,y1 windows (fractions of the compared image, y down) whose
  // blocks are left out of the block figures: where the reference is known
  // to be wrong (docs/fidelity.md).
  std::vector<std::string> exclude;
};

// Doubles throughout: the means and sums of squares run over a million
// pixels, and floats would lose the last digits the tests compare.
using Rgb = std::array<double, 3>;

struct Image {
  int width = 0;
  int height = 0;
  std::vector<Rgb> pixels;  // row-major, row 0 at the top
};

constexpr std::array<double, 3> kLuminance = {0.2126, 0.7152, 0.0722};  // Rec. 709, linear

double luminance(const Rgb& c) {
  return kLuminance[0] * c[0] + kLuminance[1] * c[1] + kLuminance[2] * c[2];
}

std::pair<int, int> parseSize(const std::string& text) {
  int w = 0, h = 0;
  char x = 0, extra = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || x != 'x' || w <= 0 ||
      h <= 0)
    throw InputError(fmt::format("--size {}: expected WIDTHxHEIGHT, e.g. 256x256", text));
  return {w, h};
}

Image load(const std::string& path) {
  HdrImage hdr = readHdrImage(path);  // throws InputError naming the file
  Image image{hdr.width, hdr.height, {}};
  image.pixels.reserve(hdr.pixels.size());
  for (const Vec3f& p : hdr.pixels) image.pixels.push_back({p.x, p.y, p.z});
  return image;
}

// The mean of each factor x factor square of pixels. Only whole integer
// factors, the same in x and y: anything else would be resampling, which
// blurs, and a different factor per axis means the two images do not frame
// the same picture.
Image boxAverage(const Image& in, int width, int height, const std::string& what) {
  if (in.width % width != 0 || in.height % height != 0 || in.width / width != in.height / height)
    throw InputError(fmt::format(
        "{}: {}x{} is not an integer multiple (the same in x and y) of the comparison size {}x{}; "
        "render at the comparison size or a multiple of it, or choose another --size",
        what, in.width, in.height, width, height));
  const int factor = in.width / width;
  if (factor == 1) return in;
  Image out{width, height, std::vector<Rgb>(size_t(width) * height, Rgb{0, 0, 0})};
  const double weight = 1.0 / (double(factor) * factor);
  for (int y = 0; y < in.height; ++y)
    for (int x = 0; x < in.width; ++x) {
      const Rgb& p = in.pixels[size_t(y) * in.width + x];
      Rgb& q = out.pixels[size_t(y / factor) * width + x / factor];
      for (int c = 0; c < 3; ++c) q[c] += p[c] * weight;
    }
  return out;
}

Rgb mean(const std::vector<Rgb>& pixels) {
  Rgb sum{0, 0, 0};
  for (const Rgb& p : pixels)
    for (int c = 0; c < 3; ++c) sum[c] += p[c];
  for (double& s : sum) s /= double(pixels.size());
  return sum;
}

// Quiet NaN when the reference has nothing in a channel (written as null).
double bias(double image, double reference) {
  return reference > 0 ? image / reference - 1 : std::numeric_limits<double>::quiet_NaN();
}

// One linear scale for both pictures, so that they can be compared by eye:
// the reference's mean luminance goes to 0.18 (middle grey), times 2^exposure.
std::vector<uint8_t> toneMap(const Image& image, double scale) {
  LinearImage linear{image.width, image.height, {}};
  linear.rgb.reserve(image.pixels.size());
  for (const Rgb& p : image.pixels)
    linear.rgb.push_back({float(p[0] * scale), float(p[1] * scale), float(p[2] * scale)});
  return toPng(linear);  // clamped to [0, 1], sRGB
}

// Signed false colour: black where the luminances agree, red where the image
// is brighter, blue where it is darker, full at +-range times `norm`.
std::vector<uint8_t> differenceMap(const Image& image, const Image& reference, double norm,
                                   double range) {
  std::vector<uint8_t> rgba;
  rgba.reserve(image.pixels.size() * 4);
  for (size_t i = 0; i < image.pixels.size(); ++i) {
    const double d = (luminance(image.pixels[i]) - luminance(reference.pixels[i])) / norm / range;
    const double t = std::clamp(std::abs(d), 0.0, 1.0);
    // Blue with some green: pure blue is too dark to read against black.
    const std::array<double, 3> hue =
        d > 0 ? std::array<double, 3>{1.0, 0.15, 0.1} : std::array<double, 3>{0.1, 0.45, 1.0};
    for (double h : hue) rgba.push_back(uint8_t(std::lround(255 * t * h)));
    rgba.push_back(255);
  }
  return rgba;
}

// reference | image | difference, with a grey gap between them.
void writeSideBySide(const std::string& path, int width, int height,
                     const std::array<std::vector<uint8_t>, 3>& panels) {
  constexpr int kGap = 4;
  const int total = 3 * width + 2 * kGap;
  std::vector<uint8_t> rgba(size_t(total) * height * 4, 96);
  for (int p = 0; p < 3; ++p)
    for (int y = 0; y < height; ++y)
      std::copy_n(&panels[p][size_t(y) * width * 4], size_t(width) * 4,
                  &rgba[(size_t(y) * total + size_t(p) * (width + kGap)) * 4]);
  for (size_t i = 3; i < rgba.size(); i += 4) rgba[i] = 255;
  writePng(path, total, height, rgba);
}

// The part of `in` a crop window selects, with pbrt's (and ferry render
// --crop's) rounding, so that a cropped render meets the same pixels.
Image cropped(const Image& in, const CropWindow& crop) {
  const FilmWindow w = filmWindow(in.width, in.height, crop);
  Image out{w.width, w.height, {}};
  out.pixels.reserve(size_t(w.width) * size_t(w.height));
  for (int y = w.y0; y < w.y0 + w.height; ++y)
    for (int x = w.x0; x < w.x0 + w.width; ++x)
      out.pixels.push_back(in.pixels[size_t(y) * in.width + x]);
  return out;
}

int run(const Options& options) {
  const Image reference = options.referenceCrop.empty()
                              ? load(options.reference)
                              : cropped(load(options.reference),
                                        parseCropWindow("--reference-crop", options.referenceCrop));
  const Image image = load(options.image);

  int width = 0, height = 0;
  if (options.size.empty()) {
    if (reference.width % 4 != 0 || reference.height % 4 != 0)
      throw InputError(fmt::format(
          "{}: {}x{} does not divide by 4 for the default comparison size; give --size WxH",
          options.reference, reference.width, reference.height));
    width = reference.width / 4;
    height = reference.height / 4;
  } else {
    std::tie(width, height) = parseSize(options.size);
  }
  const int b = options.block;
  if (b <= 0 || width % b != 0 || height % b != 0)
    throw InputError(fmt::format("--block {}: the comparison size {}x{} is not a multiple of it", b,
                                 width, height));
  const Image r = boxAverage(reference, width, height, options.reference);
  const Image f = boxAverage(image, width, height, options.image);
  const Image rBlocks = boxAverage(r, width / b, height / b, "the reference");
  const Image fBlocks = boxAverage(f, width / b, height / b, "the image");

  // The blocks the figures count: those whose centre lies in no --exclude window.
  const int blocksX = width / b, blocksY = height / b;
  std::vector<CropWindow> excluded;
  for (const std::string& text : options.exclude)
    excluded.push_back(parseCropWindow("--exclude", text));
  std::vector<char> counted(rBlocks.pixels.size(), 1);
  size_t excludedBlocks = 0;
  for (int by = 0; by < blocksY; ++by)
    for (int bx = 0; bx < blocksX; ++bx) {
      const double cx = (bx + 0.5) / blocksX, cy = (by + 0.5) / blocksY;
      for (const CropWindow& w : excluded)
        if (cx >= w.x0 && cx < w.x1 && cy >= w.y0 && cy < w.y1) {
          counted[size_t(by) * size_t(blocksX) + size_t(bx)] = 0;
          ++excludedBlocks;
          break;
        }
    }
  if (excludedBlocks == counted.size())
    throw InputError("--exclude: the windows cover every block; nothing is left to compare");

  const Rgb rMean = mean(r.pixels);
  const Rgb fMean = mean(f.pixels);
  const double rLum = luminance(rMean);  // luminance is linear: the mean's is the mean
  const double fLum = luminance(fMean);
  // Each counted block's squared error (over its channels), for the RMSE
  // and for where the error is.
  double squares = 0, sum = 0;
  std::vector<std::pair<double, size_t>> blockErrors;
  for (size_t i = 0; i < rBlocks.pixels.size(); ++i) {
    if (!counted[i]) continue;
    double e = 0;
    for (int c = 0; c < 3; ++c) {
      const double d = fBlocks.pixels[i][c] - rBlocks.pixels[i][c];
      e += d * d;
      sum += rBlocks.pixels[i][c];
    }
    squares += e;
    blockErrors.emplace_back(e, i);
  }
  const double n = 3.0 * double(blockErrors.size());
  const double rmse =
      sum > 0 ? std::sqrt(squares / n) / (sum / n) : std::numeric_limits<double>::quiet_NaN();
  // Where the error is: blocks by their squared error, largest first, and
  // the share of the total the worst 1 % and 5 % hold (a few blocks holding
  // most of it is a local difference: a material, a light, fireflies).
  std::sort(blockErrors.begin(), blockErrors.end(), std::greater<>());
  auto shareOfWorst = [&](double fraction) {
    const size_t k = std::max<size_t>(1, size_t(fraction * double(blockErrors.size())));
    double part = 0;
    for (size_t i = 0; i < k && i < blockErrors.size(); ++i) part += blockErrors[i].first;
    return squares > 0 ? part / squares : 0.0;
  };
  const double worst1 = shareOfWorst(0.01), worst5 = shareOfWorst(0.05);
  // Fireflies: the 99th-percentile pixel luminance at the comparison size,
  // the image's over the reference's (a heavy tail reads far above 1).
  auto percentile99 = [](const Image& im) {
    std::vector<double> l;
    l.reserve(im.pixels.size());
    for (const Rgb& p : im.pixels) l.push_back(luminance(p));
    const size_t k = std::min(l.size() - 1, size_t(0.99 * double(l.size())));
    std::nth_element(l.begin(), l.begin() + ptrdiff_t(k), l.end());
    return l[k];
  };
  const double rP99 = percentile99(r), fP99 = percentile99(f);

  const auto signedOrNa = [](double v) {
    return std::isnan(v) ? std::string("n/a") : fmt::format("{:+.4f}", v);
  };
  fmt::print("reference  {} ({}x{})\n", options.reference, reference.width, reference.height);
  fmt::print("image      {} ({}x{})\n", options.image, image.width, image.height);
  fmt::print("compared   at {}x{}, {}x{}-pixel blocks ({}x{} blocks)\n", width, height, b, b,
             width / b, height / b);
  if (excludedBlocks > 0)
    fmt::print("excluded   {} of {} blocks (--exclude; the block figures below leave them out)\n",
               excludedBlocks, counted.size());
  fmt::print("{:<10} {:>12} {:>12} {:>9}\n", "channel", "reference", "image", "bias");
  const char* names[3] = {"R", "G", "B"};
  for (int c = 0; c < 3; ++c)
    fmt::print("{:<10} {:>12.6g} {:>12.6g} {:>9}\n", names[c], rMean[c], fMean[c],
               signedOrNa(bias(fMean[c], rMean[c])));
  fmt::print("{:<10} {:>12.6g} {:>12.6g} {:>9}\n", "luminance", rLum, fLum,
             signedOrNa(bias(fLum, rLum)));
  fmt::print("block relative RMSE  {}\n", std::isnan(rmse) ? "n/a" : fmt::format("{:.4f}", rmse));
  fmt::print("p99 pixel luminance  reference {:.6g}, image {:.6g}, ratio {}\n", rP99, fP99,
             rP99 > 0 ? fmt::format("{:.3f}", fP99 / rP99) : std::string("n/a"));
  fmt::print(
      "worst blocks         1 % of the blocks hold {:.1f} % of the squared error, 5 % hold "
      "{:.1f} %; the worst at block ({}, {})\n",
      100 * worst1, 100 * worst5,
      blockErrors.empty() ? 0 : blockErrors[0].second % size_t(width / b),
      blockErrors.empty() ? 0 : blockErrors[0].second / size_t(width / b));

  // The tone scale comes from the reference alone, so two images compared
  // with the same reference get the same picture of it.
  const double toneScale = (rLum > 0 ? 0.18 / rLum : 1.0) * std::exp2(double(options.exposure));
  if (!options.sideBySide.empty()) {
    // Excluded blocks are grey in the difference picture.
    std::vector<uint8_t> difference = differenceMap(f, r, rLum > 0 ? rLum : 1.0, options.diffRange);
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x)
        if (!counted[size_t(y / b) * size_t(blocksX) + size_t(x / b)])
          for (int c = 0; c < 3; ++c)
            difference[(size_t(y) * size_t(width) + size_t(x)) * 4 + c] = 96;
    writeSideBySide(options.sideBySide, width, height,
                    {toneMap(r, toneScale), toneMap(f, toneScale), std::move(difference)});
    fmt::print(
        "wrote      {}: reference | image | difference (both x{:.4g}, clamped, sRGB; difference: "
        "luminance (image - reference) / reference mean, red > 0 > blue, full at +-{:g}; "
        "excluded blocks grey)\n",
        options.sideBySide, toneScale, options.diffRange);
  }
  if (!options.json.empty()) {
    nlohmann::json out;
    out["reference"] = {
        {"path", options.reference}, {"width", reference.width}, {"height", reference.height}};
    out["image"] = {{"path", options.image}, {"width", image.width}, {"height", image.height}};
    out["size"] = {width, height};
    out["block"] = b;
    out["blocks"] = {width / b, height / b};
    for (int c = 0; c < 3; ++c)
      out["channels"][names[c]] = {{"reference_mean", rMean[c]},
                                   {"image_mean", fMean[c]},
                                   {"bias", bias(fMean[c], rMean[c])}};
    out["channels"]["luminance"] = {
        {"reference_mean", rLum}, {"image_mean", fLum}, {"bias", bias(fLum, rLum)}};
    out["block_relative_rmse"] = rmse;  // NaN is written as null
    out["excluded_blocks"] = excludedBlocks;
    out["exclude"] = options.exclude;
    out["squared_error_share_of_worst_blocks"] = {{"1%", worst1}, {"5%", worst5}};
    out["p99_luminance"] = {
        {"reference", rP99}, {"image", fP99}, {"ratio", rP99 > 0 ? fP99 / rP99 : std::nan("")}};
    nlohmann::json worst = nlohmann::json::array();
    for (size_t i = 0; i < std::min<size_t>(10, blockErrors.size()); ++i)
      worst.push_back({{"x", blockErrors[i].second % size_t(width / b)},
                       {"y", blockErrors[i].second / size_t(width / b)},
                       {"share", squares > 0 ? blockErrors[i].first / squares : 0.0},
                       {"reference_luminance", luminance(rBlocks.pixels[blockErrors[i].second])},
                       {"image_luminance", luminance(fBlocks.pixels[blockErrors[i].second])}});
    out["worst_blocks"] = worst;
    out["tone_scale"] = toneScale;
    out["difference_range"] = options.diffRange;
    writeFileAtomically(options.json, [&](const std::string& temp) {
      std::ofstream file(temp);
      file << out.dump(2) << "\n";
      if (!file) throw InputError(fmt::format("{}: cannot write", options.json));
    });
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  CLI::App app{
      "Compares a rendered image with a reference render of the same scene: per-channel mean\n"
      "bias and block relative RMSE at a common resolution (bench/fidelity, docs/fidelity.md)."};
  app.add_option("reference", options.reference, "Reference image (.exr, .pfm, .hdr)")->required();
  app.add_option("image", options.image, "Image to check (.exr, .pfm, .hdr)")->required();
  app.add_option("--size", options.size,
                 "Comparison resolution WxH (default: a quarter of the reference's width and "
                 "height); each image must be it times an integer, the same in x and y");
  app.add_option("--block", options.block, "Block size B in comparison pixels")
      ->capture_default_str();
  app.add_option("--side-by-side", options.sideBySide,
                 "Write reference | image | difference at the comparison size to this PNG");
  app.add_option("--json", options.json, "Write the figures as JSON to this file");
  app.add_option("--reference-crop", options.referenceCrop,
                 "Compare with this part of the reference only, X0,X1,Y0,Y1 as fractions (y down), "
                 "as ferry render --crop renders it");
  app.add_option("--exclude", options.exclude,
                 "Leave the blocks whose centre lies in this window, X0,X1,Y0,Y1 as fractions of "
                 "the compared image (y down), out of the block RMSE and the worst blocks "
                 "(repeatable; the bias still covers the whole image): for parts where the "
                 "reference is known to be wrong");
  app.add_option("--exposure", options.exposure,
                 "Stops added to the pictures' tone scale (which maps the reference's mean "
                 "luminance to 0.18)")
      ->capture_default_str();
  app.add_option("--diff-range", options.diffRange,
                 "The difference picture saturates at +- this times the reference's mean luminance")
      ->capture_default_str();
  app.footer(
      "Both images are box-averaged to the comparison size, then over BxB blocks. With\n"
      "R, F the reference and the image at the comparison size and R_b, F_b their block means:\n"
      "  bias (per channel c)  = mean(F_c) / mean(R_c) - 1   (luminance: Rec. 709 weights)\n"
      "  block relative RMSE   = sqrt(mean over blocks b and channels c of (F_bc - R_bc)^2)\n"
      "                          / (mean over blocks b and channels c of R_bc)\n"
      "  p99 ratio             = the 99th-percentile pixel luminance of F over that of R\n"
      "Exit status: 0 compared; 1 an image is missing or unreadable, or the sizes do not match.");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help
    fmt::print(stderr, "image_compare: error: {} (see image_compare --help)\n", e.what());
    return e.get_exit_code();
  }
  try {
    return run(options);
  } catch (const InputError& e) {
    fmt::print(stderr, "image_compare: error: {}\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    fmt::print(stderr, "image_compare: internal error: {}\n", e.what());
    return 2;
  }
}
