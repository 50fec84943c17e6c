// Test-only failure injection, so the failure tests can make one rank fail at
// a chosen point of a real render: FERRY_FAIL_RANK=R FERRY_FAIL_AT=POINT
// throws on rank R when it reaches POINT ("load", "exchange", "composite"),
// FERRY_FAIL_AT=signal-POINT raises SIGSEGV there. Without both variables it
// does nothing (one getenv per call: never call it per ray).
#pragma once

namespace ferry {

void maybeInjectFailure(const char* point, int rank);

}  // namespace ferry
