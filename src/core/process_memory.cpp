#include "core/process_memory.h"

#include <unistd.h>

#include <fstream>
#include <sstream>
#include <string>

namespace ferry {

ProcessMemory readProcessMemory() {
  ProcessMemory m;
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string key;
    uint64_t kib = 0;
    fields >> key >> kib;
    if (key == "VmRSS:") m.residentBytes = kib * 1024;
    if (key == "VmHWM:") m.peakResidentBytes = kib * 1024;
  }
  return m;
}

uint64_t physicalMemoryBytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), size = ::sysconf(_SC_PAGESIZE);
  return pages > 0 && size > 0 ? uint64_t(pages) * uint64_t(size) : 0;
}

}  // namespace ferry
