// One libFuzzer target: built once per kind (ferry_fuzz_<kind>, with
// FERRY_FUZZ_KIND its name: tests/fuzz/CMakeLists.txt). Any exception other
// than the input's own error, any crash, leak, hang or sanitizer report is a
// bug (tests/fuzz/fuzz_inputs.h).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "fuzz/fuzz_inputs.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const ferry::fuzz::Kind& kind = ferry::fuzz::kind(FERRY_FUZZ_KIND);
  ferry::fuzz::runOne(kind, std::string_view(reinterpret_cast<const char*>(data), size));
  return 0;
}
