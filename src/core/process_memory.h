// Resident memory of this process, from /proc (Linux): what a rank really uses.
#pragma once

#include <cstdint>

namespace ferry {

struct ProcessMemory {
  uint64_t residentBytes = 0;      // VmRSS
  uint64_t peakResidentBytes = 0;  // VmHWM
};

ProcessMemory readProcessMemory();

// The machine's physical memory (0 if unknown).
uint64_t physicalMemoryBytes();

}  // namespace ferry
