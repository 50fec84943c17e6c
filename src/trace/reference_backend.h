// A second trace backend in plain C++, for tests: it proves the seam (the
// renderer and the distributed traversal run on it unchanged) and is the
// reference the Embree backend is checked against ray by ray
// (trace_backend_test.cpp). Median-split BVHs (one per object, one over the
// placed instances), double-precision Moeller-Trumbore triangle tests,
// instance transforms, the same alpha cut-outs (alpha_cutout.h) and hit
// naming as Embree. Slow next to Embree; not used by the `ferry` command.
#pragma once

#include <cstdint>
#include <memory>
#include <span>

#include "trace/trace_backend.h"

namespace ferry {

struct Scene;

// Builds over `ownedInstances` of `scene` (all instances when empty). The
// scene must outlive the backend. With Instancing::Shared an object placed
// once, untransformed, is entered without a transform and counted at the top
// level, as Embree's backend counts it.
std::unique_ptr<TraceBackend> makeReferenceBackend(const Scene& scene,
                                                   std::span<const int32_t> ownedInstances = {},
                                                   Instancing instancing = Instancing::Shared);

}  // namespace ferry
