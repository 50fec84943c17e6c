// The render modes a command line chooses, parsed once where the flag is read
// and carried as enums from there on: one parse function per mode (throwing
// InputError with the flag's message) and one toString (the name the stats
// JSON records). Forwarding (distributed/forwarding.h) and the partitioner
// (partition/partitioner.h) have theirs next to their enums.
#pragma once

#include <cstdint>
#include <string>

#include "trace/trace_backend.h"

namespace ferry {

// The path on the wire (path/path.h).
enum class PathLayout : uint8_t {
  Auto,   // Path8 up to 8 ranks, Path64 up to 64, replay above
  Mask,   // Path8 or Path64 (at most 64 ranks)
  Replay  // the generating rank only, at any rank count
};
PathLayout parsePathLayout(const std::string& name);  // --path-layout
std::string toString(PathLayout layout);

// Which shaded paths re-trace their ray to recover the hit.
enum class Retrace : uint8_t {
  Remote,  // only those whose hit another rank found (a rank keeps the hits it found)
  All      // every one, as the paper (its compact path carries no hit)
};
Retrace parseRetrace(const std::string& name);  // --retrace
std::string toString(Retrace retrace);

Instancing parseInstancing(const std::string& name);  // --instancing
std::string toString(Instancing instancing);

}  // namespace ferry
