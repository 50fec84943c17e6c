// One floating-point mode for every thread that traces or shades: denormals
// flushed to zero (FTZ) and read as zero (DAZ), as Embree recommends for
// speed. Set explicitly, because otherwise a thread's mode is an accident of
// history: TBB runs its tasks with the mode of the thread that first started
// it, and Embree switches the mode on inside its builds, so a rank whose
// first TBB call happened inside a BVH build shaded with FTZ on and one that
// partitioned first shaded with it off, and their images differed wherever a
// denormal appeared (docs/memory.md, "Concurrent builds"). Call
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
