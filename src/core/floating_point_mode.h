// One floating-point mode for every thread that traces or shades: denormals
// flushed to zero (FTZ) and read as zero (DAZ), as Embree recommends for
// speed. Set explicitly: otherwise TBB runs its tasks with the mode of the
// thread that first started it, which Embree's builds change, and images
// differ wherever a denormal appears (docs/architecture.md, "One
// floating-point mode for every thread"). Call
// useFixedFloatingPointMode() first thing in main(), before any thread or
// TBB call: threads made afterwards inherit the mode, and TBB, started
// afterwards, runs its tasks with it.
#pragma once

namespace ferry {

// Sets FTZ and DAZ on the calling thread (no-op where the CPU has no such mode).
void useFixedFloatingPointMode();
// Whether the calling thread runs in that mode.
bool floatingPointModeIsFixed();

}  // namespace ferry
