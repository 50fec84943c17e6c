// Progress on long work: a redrawn bar when stderr is a terminal, a plain
// line per step when it is not (logs, CI, mpirun without a tty).
#pragma once

#include <string>

#include "core/clock.h"

namespace ferry {

class Progress {
 public:
  // `enabled` false silences it (e.g. on every rank but 0).
  Progress(std::string label, int total, bool enabled = true);
  ~Progress();
  void update(int done, const std::string& detail = {});
  void finish(const std::string& detail = {});

 private:
  std::string label_;
  int total_;
  bool enabled_;
  bool terminal_;
  bool finished_ = false;
  Clock::time_point start_;
};

}  // namespace ferry
