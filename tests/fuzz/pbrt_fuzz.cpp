// libFuzzer target: the pbrt tokenizer over the whole input, then the parser
// (directives, parameters, scene building) on the same bytes. Any exception
// other than InputError, any crash, hang or sanitizer report is a bug.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "core/error.h"
#include "io/byte_stream.h"
#include "io/load_options.h"
#include "io/pbrt_parser.h"
#include "io/pbrt_tokenizer.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    ferry::PbrtTokenizer tokens(ferry::ByteStream::fromMemory(text, "fuzz.pbrt"));
    while (tokens.next().kind != ferry::PbrtToken::Kind::End) {
    }
  } catch (const ferry::InputError&) {
  }
  try {
    ferry::LoadOptions options;
    options.warn = [](const std::string&) {};
    options.maxGeneratedTriangles = 1 << 20;  // stay within the fuzzer's memory limit
    // No directory with files: every Include, plymesh or texture is missing.
    ferry::loadPbrtFromString(text, "fuzz.pbrt", "/nonexistent-ferry-fuzz-dir", options);
  } catch (const ferry::InputError&) {
  }
  return 0;
}
