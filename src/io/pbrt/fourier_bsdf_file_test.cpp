// The .bsdf reader: paint.bsdf from the breakfast scene (../shared, skipped
// when absent) read with its header's values, and the malformed corpus
// (tests/corpus/bsdf, made by make_bsdf_corpus.py): each file one InputError
// naming it and saying what is wrong.
#include "io/pbrt/fourier_bsdf_file.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "core/error.h"

namespace ferry {
namespace {

namespace fs = std::filesystem;

const fs::path kCorpus = fs::path(FERRY_SOURCE_DIR) / "tests" / "corpus" / "bsdf";
const fs::path kPaint = fs::path(FERRY_SHARED_SCENES) / "breakfast" / "bsdfs" / "paint.bsdf";

TEST(FourierBsdfFile, ReadsPaint) {
  if (!fs::exists(kPaint)) GTEST_SKIP() << kPaint << " is not available";
  const auto t = readFourierBsdfFile(kPaint.string());
  // The header (its bytes 8-63): flags 1, nMu 102, nCoeffs 95991, mMax 74,
  // 3 channels, 1 basis, eta 1.
  EXPECT_EQ(t->nMu, 102);
  EXPECT_EQ(t->coefficients.size(), 95991u);
  EXPECT_EQ(t->mMax, 74);
  EXPECT_EQ(t->nChannels, 3);
  EXPECT_EQ(t->eta, 1.0f);
  EXPECT_EQ(t->mu.front(), -1.0f);
  EXPECT_EQ(t->mu.back(), 1.0f);
  ASSERT_EQ(t->a0.size(), 102u * 102u);
  ASSERT_EQ(t->recip.size(), 74u);
  EXPECT_FLOAT_EQ(t->recip[3], 1.0f / 3);
  // a0 is each entry's first coefficient; the longest series is mMax.
  int32_t longest = 0;
  for (size_t e = 0; e < t->order.size(); ++e) {
    longest = std::max(longest, t->order[e]);
    EXPECT_EQ(t->a0[e], t->order[e] > 0 ? t->coefficients[t->offset[e]] : 0.0f);
  }
  EXPECT_EQ(longest, 74);
  // Paint on an opaque base: no light on the far side.
  EXPECT_FALSE(t->transmits());
  // Each cdf row grows from 0 (light arriving from above, mu_o > 0, is
  // reflected into mu_i < 0).
  for (int32_t o = 0; o < t->nMu; ++o) {
    EXPECT_EQ(t->cdf[t->entry(0, o)], 0.0f);
    for (int32_t i = 1; i < t->nMu; ++i)
      EXPECT_GE(t->cdf[t->entry(i, o)], t->cdf[t->entry(i - 1, o)] - 1e-6f) << i << " " << o;
  }
  EXPECT_GT(t->cdf[t->entry(t->nMu - 1, t->nMu - 1)], 0.0f);
}

TEST(FourierBsdfFile, ReadsTheValidCorpusTable) {
  const auto t = readFourierBsdfFile((kCorpus / "valid.bsdf").string());
  EXPECT_EQ(t->nMu, 5);
  EXPECT_EQ(t->nChannels, 1);
  EXPECT_EQ(t->mMax, 2);
  EXPECT_EQ(t->coefficients.size(), 50u);
}

TEST(FourierBsdfFile, MissingFileIsNamed) {
  try {
    readFourierBsdfFile((kCorpus / "no_such.bsdf").string());
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no_such.bsdf"), std::string::npos) << e.what();
  }
}

struct MalformedCase {
  const char* file;
  const char* message;  // part of the error
};

TEST(FourierBsdfFile, MalformedCorpus) {
  const MalformedCase cases[] = {
      {"empty.bsdf", "truncated header (0 of 64 bytes)"},
      {"truncated_header.bsdf", "truncated header (20 of 64 bytes)"},
      {"wrong_magic.bsdf", "no \"SCATFUN\" header"},
      {"version_2.bsdf", "version 2"},
      {"harmonic_extrapolation.bsdf", "flags 0x3"},
      {"textured.bsdf", "2 bases"},
      {"two_channels.bsdf", "2 channels"},
      {"huge_nmu.bsdf", "need more than the 520 bytes"},
      {"huge_ncoeffs.bsdf", "need more than the 520 bytes"},
      {"negative_ncoeffs.bsdf", "-5 coefficients"},
      {"truncated_data.bsdf", "need more than the 30 bytes"},
      {"offset_out_of_range.bsdf", "entry (2, 1) reads coefficients 1000 to 1002 of 50"},
      {"offset_negative.bsdf", "entry 3 has offset -8"},
      {"offset_overflow.bsdf", "series length 2147483647 (0 to 2)"},
      {"series_too_long.bsdf", "series length 3 (0 to 2)"},
      {"mu_not_increasing.bsdf", "mu[2] = 0 decreases"},
      {"nan_coefficient.bsdf", "not finite"},
  };
  size_t files = 0;
  for (const auto& entry : fs::directory_iterator(kCorpus))
    files += entry.path().extension() == ".bsdf";
  EXPECT_EQ(files, std::size(cases) + 1) << "a corpus file without a case (or the reverse)";
  for (const MalformedCase& c : cases) {
    const std::string path = (kCorpus / c.file).string();
    try {
      readFourierBsdfFile(path);
      ADD_FAILURE() << c.file << ": no error";
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(path + ": ", 0), 0u) << what;
      EXPECT_NE(what.find(c.message), std::string::npos) << c.file << ": " << what;
    }
  }
}

}  // namespace
}  // namespace ferry
