#include "core/process_memory.h"

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

}  // namespace ferry
