#include "session/modes.h"

#include <gtest/gtest.h>

#include "core/error.h"

namespace ferry {
namespace {

// `parse(bad)` throws InputError with exactly `message` (the flag's message).
template <typename Parse>
void expectRefused(Parse parse, const std::string& bad, const std::string& message) {
  try {
    parse(bad);
    ADD_FAILURE() << "'" << bad << "' was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), message);
  }
}

TEST(Modes, PathLayoutsParseAndRoundTrip) {
  EXPECT_EQ(parsePathLayout("auto"), PathLayout::Auto);
  EXPECT_EQ(parsePathLayout("mask"), PathLayout::Mask);
  EXPECT_EQ(parsePathLayout("replay"), PathLayout::Replay);
  for (PathLayout layout : {PathLayout::Auto, PathLayout::Mask, PathLayout::Replay})
    EXPECT_EQ(parsePathLayout(toString(layout)), layout);
  expectRefused(parsePathLayout, "mask8", "path-layout 'mask8': expected auto, mask or replay");
  expectRefused(parsePathLayout, "", "path-layout '': expected auto, mask or replay");
  expectRefused(parsePathLayout, "Auto", "path-layout 'Auto': expected auto, mask or replay");
}

TEST(Modes, RetraceModesParseAndRoundTrip) {
  EXPECT_EQ(parseRetrace("remote"), Retrace::Remote);
  EXPECT_EQ(parseRetrace("all"), Retrace::All);
  for (Retrace retrace : {Retrace::Remote, Retrace::All})
    EXPECT_EQ(parseRetrace(toString(retrace)), retrace);
  expectRefused(parseRetrace, "none", "retrace 'none': expected remote or all");
  expectRefused(parseRetrace, "ALL", "retrace 'ALL': expected remote or all");
}

TEST(Modes, InstancingModesParseAndRoundTrip) {
  EXPECT_EQ(parseInstancing("shared"), Instancing::Shared);
  EXPECT_EQ(parseInstancing("always"), Instancing::Always);
  for (Instancing instancing : {Instancing::Shared, Instancing::Always})
    EXPECT_EQ(parseInstancing(toString(instancing)), instancing);
  expectRefused(parseInstancing, "never", "instancing 'never': expected shared or always");
  expectRefused(parseInstancing, " shared", "instancing ' shared': expected shared or always");
}

}  // namespace
}  // namespace ferry
