// Replays every fuzzing corpus (tests/fuzz/corpus/<kind>) and every input a
// fuzzer ever failed on (tests/fuzz/regressions/<kind>) through the fuzz
// targets' own entry points (tests/fuzz/fuzz_inputs.h): each input must load
// or be refused with the input's own error, nothing else. Under
// FERRY_SANITIZE (scripts/sanitize.sh) this is the fuzzers' findings
// replayed with their sanitizers.
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "fuzz/fuzz_inputs.h"

namespace ferry::fuzz {
namespace {

namespace fs = std::filesystem;

const fs::path kFuzz = fs::path(FERRY_SOURCE_DIR) / "tests" / "fuzz";

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

TEST(FuzzRegressions, EveryKindHasACorpusAndEveryCorpusAKind) {
  std::set<std::string> dirs;
  for (const auto& entry : fs::directory_iterator(kFuzz / "corpus"))
    if (entry.is_directory()) dirs.insert(entry.path().filename().string());
  std::set<std::string> names;
  for (const Kind& k : kinds()) names.insert(k.name);
  EXPECT_EQ(dirs, names) << "tests/fuzz/corpus/<kind> makes the target ferry_fuzz_<kind>";
}

class Replay : public testing::TestWithParam<std::string> {};

TEST_P(Replay, InputsLoadOrFailCleanly) {
  const Kind& k = kind(GetParam());
  int files = 0, loaded = 0;
  for (const fs::path& dir : {kFuzz / "corpus" / k.name, kFuzz / "regressions" / k.name}) {
    if (!fs::is_directory(dir)) continue;
    for (const auto& entry : fs::directory_iterator(dir)) {
      if (!entry.is_regular_file()) continue;
      SCOPED_TRACE(entry.path().string());
      try {
        loaded += runOne(k, slurp(entry.path()));
      } catch (const std::exception& e) {
        ADD_FAILURE() << entry.path() << ": not the input's own error: " << e.what();
      }
      ++files;
    }
  }
  EXPECT_GE(files, 3) << "a corpus of at least a few seeds";
  EXPECT_GE(loaded, 1) << "no seed loads: the fuzzer would only ever see errors";
}

std::vector<std::string> kindNames() {
  std::vector<std::string> names;
  for (const Kind& k : kinds()) names.push_back(k.name);
  return names;
}

INSTANTIATE_TEST_SUITE_P(Kinds, Replay, testing::ValuesIn(kindNames()),
                         [](const testing::TestParamInfo<std::string>& info) {
                           return info.param;
                         });

}  // namespace
}  // namespace ferry::fuzz
