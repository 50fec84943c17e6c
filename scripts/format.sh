#!/usr/bin/env bash
# Formats every C++ source of Ferry with the repository's .clang-format
# (third-party code excepted). --list prints the files instead.
set -euo pipefail
cd "$(dirname "$0")/.."
list() { git ls-files --cached --others --exclude-standard -- '*.cpp' '*.h' | grep -v '^src/third_party/'; }
if [ "${1:-}" = "--list" ]; then
  list
else
  list | xargs clang-format -i
fi
