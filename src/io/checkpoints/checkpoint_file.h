// A long render's checkpoint (`ferry render --checkpoint FILE`): the
// accumulated image as the exact fixed-point sums of the frame buffer
// (render/frame_buffer.h), how many frames they hold, and a hash of
// everything that shapes the image (scene, size, samples, depth, seed,
// view), so that `--resume FILE` continues the render and gives, bit for
// bit, the image an uninterrupted render would have, or refuses.
//
// Binary, little-endian (the machines Ferry runs on):
//   "FERRYCKP" | u32 version (1) | u32 fraction bits | u64 identity |
//   i32 width | i32 height | i32 frames | i32 samples per pixel |
//   u32 description bytes | description (UTF-8: what the identity hashes) |
//   width * height * 3 i64 sums | u64 XXH64 of everything before it.
// Written through a temporary file and a rename (io/images/image_io.h), so a
// checkpoint is whole or absent.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace ferry {

struct Checkpoint {
  uint64_t identity = 0;    // hash of the scene and the settings that shape the image
  std::string description;  // what was hashed, readable: named in a mismatch message
  int width = 0, height = 0;
  int frames = 0;             // frames accumulated in `sums`
  int samplesPerPixel = 0;    // per frame
  std::vector<int64_t> sums;  // 3 per pixel, FrameBuffer::kFractionBits fixed point
};

void writeCheckpoint(const std::string& path, const Checkpoint& checkpoint);
// Throws InputError naming the file: missing, truncated, corrupt (hash), or
// not a checkpoint of this version.
Checkpoint readCheckpoint(const std::string& path);

}  // namespace ferry
