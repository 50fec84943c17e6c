// The fuzzed inputs: one entry point per parser or endpoint, shared by the
// libFuzzer targets (tests/fuzz/fuzz_target.cpp, one executable per kind)
// and the suite's replay of their corpora and regressions
// (src/io/fuzz_regression_test.cpp), so both run the same code on the same
// bytes. An entry returns normally or throws the input's own error
// (InputError; RequestError for the viewer's requests); anything else, a
// crash or a sanitizer report, is a bug.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace ferry::fuzz {

struct Kind {
  const char*
      name;  // the target is ferry_fuzz_<name>; corpora in tests/fuzz/{corpus,regressions}/<name>
  void (*run)(std::string_view bytes);
};

// Every kind: pbrt, ply, obj, gltf, glb, bsdf, part, manifest, checkpoint,
// camera (POST /camera and /focus bodies), settings (POST /settings bodies), raw (a
// raw volume's name and bytes), tf (transfer function files), bricks (a volume's
// bricks manifest), vdb (.vdb files), vdbgrids (grids OpenVDB writes).
const std::vector<Kind>& kinds();
const Kind& kind(std::string_view name);

// Runs `kind` on `bytes`; true if it loaded, false if it refused the input
// with its own error. Other exceptions pass through.
bool runOne(const Kind& kind, std::string_view bytes);

}  // namespace ferry::fuzz
