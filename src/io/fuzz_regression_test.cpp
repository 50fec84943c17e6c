// Replays the fuzzing corpora (tests/fuzz/corpus/{pbrt,ply}, minimised) and
// every input a fuzzer ever crashed on (tests/fuzz/regressions/{pbrt,ply})
// through the same entry points as the fuzz targets in tests/fuzz: each must
// load or fail with an InputError, nothing else.
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "core/error.h"
#include "io/byte_stream.h"
#include "io/pbrt_parser.h"
#include "io/pbrt_tokenizer.h"
#include "io/ply_reader.h"

namespace ferry {
namespace {

namespace fs = std::filesystem;

const fs::path kFuzz = fs::path(FERRY_SOURCE_DIR) / "tests" / "fuzz";

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Calls `run` on every file of the corpus and the regressions of `kind`; returns how many.
template <typename F>
int replay(const std::string& kind, F&& run) {
  int files = 0;
  for (const fs::path& dir : {kFuzz / "corpus" / kind, kFuzz / "regressions" / kind}) {
    if (!fs::is_directory(dir)) continue;
    for (const auto& entry : fs::directory_iterator(dir)) {
      if (!entry.is_regular_file()) continue;
      SCOPED_TRACE(entry.path().string());
      std::string bytes = slurp(entry.path());
      try {
        run(bytes);
      } catch (const InputError&) {
      } catch (const std::exception& e) {
        ADD_FAILURE() << entry.path() << ": not an InputError: " << e.what();
      }
      ++files;
    }
  }
  return files;
}

TEST(FuzzRegressions, PlyInputsLoadOrFailCleanly) {
  int n = replay("ply", [](const std::string& bytes) {
    ByteStream s = ByteStream::fromMemory(bytes, "fuzz.ply");
    readPly(s);
  });
  EXPECT_GT(n, 20);
}

TEST(FuzzRegressions, PbrtInputsLoadOrFailCleanly) {
  int n = replay("pbrt", [](const std::string& bytes) {
    try {
      PbrtTokenizer tokens(ByteStream::fromMemory(bytes, "fuzz.pbrt"));
      while (tokens.next().kind != PbrtToken::Kind::End) {
      }
    } catch (const InputError&) {
    }
    LoadOptions options;
    options.warn = [](const std::string&) {};
    options.maxGeneratedTriangles = 1 << 20;
    loadPbrtFromString(bytes, "fuzz.pbrt", "/nonexistent-ferry-fuzz-dir", options);
  });
  EXPECT_GT(n, 20);
}

}  // namespace
}  // namespace ferry
