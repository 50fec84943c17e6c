#include "io/checkpoints/checkpoint_file.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "core/error.h"

namespace ferry {
namespace {

namespace fs = std::filesystem;

Checkpoint sample() {
  Checkpoint c;
  c.identity = 0x1234567890abcdefull;
  c.description = "scene builtin:cornell, 3x2, 4 spp per frame";
  c.width = 3;
  c.height = 2;
  c.frames = 7;
  c.samplesPerPixel = 4;
  for (int i = 0; i < 18; ++i) c.sums.push_back(int64_t(i) * 123456789 - 5);
  return c;
}

class CheckpointFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("ferry-checkpoint-test-" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::string bytesOf(const std::string& p) const {
    std::ifstream in(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }
  void write(const std::string& p, const std::string& bytes) const {
    std::ofstream(p, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
  }
  // readCheckpoint must throw an InputError naming the file and saying `what`.
  void expectRejected(const std::string& p, const std::string& what) const {
    try {
      readCheckpoint(p);
      ADD_FAILURE() << "accepted: " << what;
    } catch (const InputError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(p), std::string::npos) << message;
      EXPECT_NE(message.find(what), std::string::npos) << message;
    }
  }
  fs::path dir_;
};

TEST_F(CheckpointFile, RoundTripsEveryField) {
  const Checkpoint c = sample();
  writeCheckpoint(path("a.ckpt"), c);
  const Checkpoint r = readCheckpoint(path("a.ckpt"));
  EXPECT_EQ(r.identity, c.identity);
  EXPECT_EQ(r.description, c.description);
  EXPECT_EQ(r.width, 3);
  EXPECT_EQ(r.height, 2);
  EXPECT_EQ(r.frames, 7);
  EXPECT_EQ(r.samplesPerPixel, 4);
  EXPECT_EQ(r.sums, c.sums);
  // Nothing but the file itself is left in the directory (written through a rename).
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);
}

// The malformed-input corpus: each way a file can be wrong gets its own message.
TEST_F(CheckpointFile, RejectsMalformedFiles) {
  writeCheckpoint(path("good.ckpt"), sample());
  const std::string good = bytesOf(path("good.ckpt"));

  expectRejected(path("missing.ckpt"), "no such checkpoint");
  write(path("empty.ckpt"), "");
  expectRejected(path("empty.ckpt"), "truncated");
  write(path("png.ckpt"), std::string("\x89PNG\r\n\x1a\n", 8) + good.substr(8));
  expectRejected(path("png.ckpt"), "not a Ferry checkpoint");
  std::string version = good;
  version[8] = 9;
  write(path("version.ckpt"), version);
  expectRejected(path("version.ckpt"), "version 9");
  write(path("short.ckpt"), good.substr(0, good.size() - 20));
  expectRejected(path("short.ckpt"), "truncated");
  write(path("long.ckpt"), good + "x");
  expectRejected(path("long.ckpt"), "bytes");
  std::string flipped = good;
  flipped[good.size() - 30] ^= 1;  // a bit of the sums
  write(path("flipped.ckpt"), flipped);
  expectRejected(path("flipped.ckpt"), "corrupt");
  std::string huge = good;
  const int32_t side = 1 << 30;  // width: must fail on the header, not allocate
  std::memcpy(huge.data() + 24, &side, 4);
  write(path("huge.ckpt"), huge);
  expectRejected(path("huge.ckpt"), "bad checkpoint header");
}

TEST_F(CheckpointFile, AFailedWriteLeavesThePreviousCheckpoint) {
  writeCheckpoint(path("c.ckpt"), sample());
  Checkpoint bad = sample();
  bad.sums.pop_back();  // sums that do not fit the size: refused before writing
  EXPECT_ANY_THROW(writeCheckpoint(path("c.ckpt"), bad));
  EXPECT_EQ(readCheckpoint(path("c.ckpt")).sums, sample().sums);
  EXPECT_THROW(writeCheckpoint((dir_ / "no" / "such" / "dir.ckpt").string(), sample()), InputError);
}

}  // namespace
}  // namespace ferry
