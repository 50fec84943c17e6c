#include "io/pbrt/fourier_bsdf_file.h"

#include <bit>
#include <cstring>

#include <fmt/format.h>

#include "core/error.h"

namespace ferry {

static_assert(std::endian::native == std::endian::little, ".bsdf files are little-endian");

namespace {

constexpr uint64_t kHeaderBytes = 64;

template <typename T>
void readArray(ByteStream& in, std::vector<T>& out, uint64_t count, const char* what) {
  out.resize(count);
  if (in.read(out.data(), count * sizeof(T)) != count * sizeof(T))
    throw InputError(fmt::format("{}: truncated in {}", in.name(), what));
}

}  // namespace

std::shared_ptr<const FourierBsdfTable> readFourierBsdf(ByteStream& in) {
  auto fail = [&](const std::string& what) -> void {
    throw InputError(fmt::format("{}: {}", in.name(), what));
  };
  unsigned char header[kHeaderBytes];
  const size_t got = in.read(header, kHeaderBytes);
  if (got >= 7 && std::memcmp(header, "SCATFUN", 7) != 0)
    fail("not a tabulated BSDF (no \"SCATFUN\" header)");
  if (got < kHeaderBytes) fail(fmt::format("truncated header ({} of {} bytes)", got, kHeaderBytes));
  if (header[7] != 1) fail(fmt::format("version {} (pbrt-v3 reads version 1)", int(header[7])));
  int32_t field[14];
  std::memcpy(field, header + 8, sizeof(field));
  const int32_t flags = field[0], nMu = field[1], nCoeffs = field[2], mMax = field[3],
                nChannels = field[4], nBases = field[5];
  float eta;
  std::memcpy(&eta, header + 44, 4);
  // What pbrt-v3 reads: a BSDF (flag 1) without harmonic extrapolation (2),
  // one basis (not textured), one or three channels.
  if (flags != 1)
    fail(fmt::format("flags {:#x} (only 1, a BSDF without harmonic extrapolation, is read)",
                     uint32_t(flags)));
  if (nBases != 1) fail(fmt::format("{} bases (textured tables are not read)", nBases));
  if (nChannels != 1 && nChannels != 3) fail(fmt::format("{} channels (1 or 3)", nChannels));
  if (nMu < 2) fail(fmt::format("{} elevation samples (at least 2)", nMu));
  if (nCoeffs < 0) fail(fmt::format("{} coefficients", nCoeffs));
  if (mMax < 1 || mMax > FourierBsdfTable::kMaxOrder)
    fail(fmt::format("longest series {} (1 to {})", mMax, FourierBsdfTable::kMaxOrder));

  // Sizes against the file before allocating: mu, cdf, offset and length,
  // coefficients, each 4 bytes. Divisions keep every product in range.
  const uint64_t remaining = in.remaining();
  const uint64_t entries = uint64_t(nMu) * uint64_t(nMu);  // < 2^62
  const bool fits = entries <= remaining / 12 && uint64_t(nCoeffs) <= remaining / 4 &&
                    4 * (uint64_t(nMu) + 3 * entries + uint64_t(nCoeffs)) <= remaining;
  if (!fits)
    fail(
        fmt::format("the header's sizes (nMu {}, {} coefficients) need more than the {} bytes "
                    "after it",
                    nMu, nCoeffs, remaining));

  auto table = std::make_shared<FourierBsdfTable>();
  table->name = in.name();
  table->nMu = nMu;
  table->nChannels = nChannels;
  table->mMax = mMax;
  table->eta = eta;
  readArray(in, table->mu, uint64_t(nMu), "mu");
  readArray(in, table->cdf, entries, "the cdf");
  std::vector<int32_t> offsetAndLength;
  readArray(in, offsetAndLength, 2 * entries, "the series offsets");
  readArray(in, table->coefficients, uint64_t(nCoeffs), "the coefficients");
  table->offset.resize(entries);
  table->order.resize(entries);
  for (size_t e = 0; e < entries; ++e) {
    const int32_t offset = offsetAndLength[2 * e], length = offsetAndLength[2 * e + 1];
    if (offset < 0 || length < 0)
      fail(fmt::format("entry {} has offset {} and length {}", e, offset, length));
    table->offset[e] = uint32_t(offset);
    table->order[e] = length;
  }
  if (std::string what = table->finish(); !what.empty()) fail(what);
  return table;
}

std::shared_ptr<const FourierBsdfTable> readFourierBsdfFile(const std::string& path) {
  ByteStream in = ByteStream::openFile(path);
  return readFourierBsdf(in);
}

}  // namespace ferry
