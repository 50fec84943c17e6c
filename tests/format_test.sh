#!/usr/bin/env bash
# Formatting: every C++ source in the tree is clean under the repository's
# .clang-format (Debian's clang-format), so formatting never drifts again.
# Fix a failure with: clang-format -i FILE (or scripts/format.sh for all).
set -euo pipefail
source_dir=$2
cd "$source_dir"
if ! command -v clang-format >/dev/null; then
  echo "format_test: clang-format is not installed (scripts/install-deps.sh installs it)" >&2
  exit 1
fi
mapfile -t files < <(bash scripts/format.sh --list)
unclean=()
for f in "${files[@]}"; do
  clang-format --dry-run --Werror "$f" >/dev/null 2>&1 || unclean+=("$f")
done
echo "format_test: ${#files[@]} files checked, ${#unclean[@]} not clean"
if ((${#unclean[@]})); then
  printf '  %s\n' "${unclean[@]}"
  echo "fix with: bash scripts/format.sh" >&2
  exit 1
fi
