#include "core/number_list.h"

#include <cmath>
#include <cstdlib>

namespace ferry {

bool parseNumberList(const std::string& text, std::span<float> out) {
  size_t start = 0;
  for (size_t i = 0; i < out.size(); ++i) {
    const size_t end = i + 1 < out.size() ? text.find(',', start) : text.size();
    if (end == std::string::npos) return false;
    const std::string part = text.substr(start, end - start);
    if (part.empty()) return false;
    char* rest = nullptr;
    out[i] = std::strtof(part.c_str(), &rest);
    if (rest != part.c_str() + part.size() || !std::isfinite(out[i])) return false;
    start = end + 1;
  }
  return true;
}

}  // namespace ferry
