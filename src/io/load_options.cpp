#include "io/load_options.h"

#include <algorithm>
#include <cstdio>

#include <fmt/format.h>

namespace ferry {

void LoadWarnings::once(const std::string& key, const std::string& message) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!said_.insert(key).second) return;
  }
  if (options_.warn) {
    options_.warn(message);
  } else {
    fmt::print(stderr, "ferry: warning: {}\n", message);
  }
}

LoadProgress::LoadProgress(const LoadOptions& options, std::string what, uint64_t totalBytes,
                           uint64_t minimumBytes)
    : options_(options),
      what_(std::move(what)),
      total_(totalBytes),
      step_(std::max<uint64_t>(totalBytes / 100, 1)),
      next_(step_),
      enabled_(bool(options.progress) && totalBytes >= minimumBytes) {}

void LoadProgress::update(uint64_t doneBytes) {
  if (!enabled_ || doneBytes < next_) return;
  next_ = doneBytes + step_;
  options_.progress(std::min(doneBytes, total_), total_, what_);
}

void LoadProgress::finish() {
  if (!enabled_) return;
  options_.progress(total_, total_, what_);
  enabled_ = false;
}

}  // namespace ferry
