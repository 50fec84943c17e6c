// libFuzzer target: the PLY reader (header, size checks, ASCII and binary
// bodies) on arbitrary bytes. Any exception other than InputError, any crash,
// hang, sanitizer report or allocation beyond what the input can justify is a bug.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "core/error.h"
#include "io/byte_stream.h"
#include "io/ply_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view bytes(reinterpret_cast<const char*>(data), size);
  try {
    ferry::ByteStream stream = ferry::ByteStream::fromMemory(bytes, "fuzz.ply");
    ferry::readPly(stream);
  } catch (const ferry::InputError&) {
  }
  return 0;
}
