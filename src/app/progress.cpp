#include "app/progress.h"

#include <fmt/format.h>
#include <unistd.h>

#include <cstdio>

namespace ferry {

Progress::Progress(std::string label, int total, bool enabled)
    : label_(std::move(label)),
      total_(total),
      enabled_(enabled),
      terminal_(isatty(STDERR_FILENO) != 0),
      start_(Clock::now()) {}

Progress::~Progress() {
  if (enabled_ && terminal_ && !finished_) fmt::print(stderr, "\n");
}

void Progress::update(int done, const std::string& detail) {
  if (!enabled_) return;
  double elapsed = secondsSince(start_);
  double fraction = total_ > 0 ? double(done) / total_ : 1.0;
  if (terminal_) {
    constexpr int kWidth = 30;
    int filled = int(fraction * kWidth + 0.5);
    double eta = fraction > 0 ? elapsed / fraction - elapsed : 0;
    fmt::print(stderr, "\r{} [{}{}] {:3.0f}% {:.1f}s (eta {:.1f}s) {}\033[K", label_,
               std::string(filled, '#'), std::string(kWidth - filled, '.'), fraction * 100, elapsed,
               eta, detail);
  } else {
    fmt::print(stderr, "{}: {}/{} ({:.1f}s) {}\n", label_, done, total_, elapsed, detail);
  }
  std::fflush(stderr);
}

void Progress::finish(const std::string& detail) {
  if (!enabled_ || finished_) return;
  update(total_, detail);
  if (terminal_) fmt::print(stderr, "\n");
  finished_ = true;
}

}  // namespace ferry
