#include "core/fault_injection.h"

#include <csignal>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

namespace ferry {

void maybeInjectFailure(const char* point, int rank) {
  const char* at = std::getenv("FERRY_FAIL_AT");
  const char* who = std::getenv("FERRY_FAIL_RANK");
  if (!at || !who || std::atoi(who) != rank) return;
  std::string where = at;
  if (where == point) throw std::runtime_error(fmt::format("injected failure at {}", point));
  if (where == std::string("signal-") + point) std::raise(SIGSEGV);
}

}  // namespace ferry
