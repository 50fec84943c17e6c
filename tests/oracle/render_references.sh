#!/usr/bin/env bash
# Renders the differential cases (tests/oracle/cases/*.pbrt) with pbrt itself
# and writes tests/oracle/references/NAME.exr, and the exact command and the
# oracle's identity to tests/oracle/references/COMMANDS.md. v3-* cases go to
# pbrt-v3 as the published references were rendered (PUBLISHED=1 build),
# v4-* cases to pbrt-v4 (docs/pbrt-coverage.md says why).
#
#   bash tests/oracle/render_references.sh [NAME ...]   (default: every case)
#
# Settings (environment):
#   PBRT_V3=/tmp/pbrt-v3-published-build/pbrt   PUBLISHED=1 bash ../shared/tools/pbrt-v3/build.sh
#   PBRT_V4=/tmp/pbrt-v4-build/pbrt             bash ../shared/tools/pbrt-v4/build.sh
#   THREADS=2
# The oracle is a tool run by hand: Ferry neither builds nor needs it. The
# test (tests/oracle_test.sh) compares Ferry with the committed EXRs.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
PBRT_V3=${PBRT_V3:-/tmp/pbrt-v3-published-build/pbrt}
PBRT_V4=${PBRT_V4:-/tmp/pbrt-v4-build/pbrt}
THREADS=${THREADS:-2}
cases=("$@")
if ((${#cases[@]} == 0)); then
  for f in "$here"/cases/*.pbrt; do cases+=("$(basename "$f" .pbrt)"); done
fi
log="$here/references/COMMANDS.md"
if [ ! -f "$log" ]; then
  cat >"$log" <<'EOF'
# How each reference was rendered

Written by `tests/oracle/render_references.sh`; one line a case, the newest
last (a case rendered again gets a new line). Oracles: pbrt-v3 at mmp/pbrt-v3
13d871f built by `PUBLISHED=1 bash ../shared/tools/pbrt-v3/build.sh` (478b2e6
reverted), pbrt-v4 at mmp/pbrt-v4 5f7a606 built by
`bash ../shared/tools/pbrt-v4/build.sh`; 2 cores (AMD EPYC), Debian 12.

| case | oracle | command (from tests/oracle/cases) | seconds | date |
|---|---|---|---|---|
EOF
fi
for name in "${cases[@]}"; do
  scene="$here/cases/$name.pbrt"
  [ -f "$scene" ] || { echo "render_references: no case $scene" >&2; exit 2; }
  case "$name" in
    v3-*) pbrt=$PBRT_V3 oracle=pbrt-v3-published ;;
    v4-*) pbrt=$PBRT_V4 oracle=pbrt-v4 ;;
    *) echo "render_references: $name: a case's name starts with v3- or v4-" >&2; exit 2 ;;
  esac
  [ -x "$pbrt" ] || { echo "render_references: $oracle not built at $pbrt" >&2; exit 2; }
  out="$here/references/$name.exr"
  tmp="$out.tmp.exr"
  start=$(date +%s.%N)
  (cd "$here/cases" && timeout 1800 "$pbrt" --nthreads "$THREADS" --quiet --outfile "$tmp" "$name.pbrt")
  seconds=$(echo "$(date +%s.%N) - $start" | bc)
  mv "$tmp" "$out"
  printf '| %s | %s | `pbrt --nthreads %s --quiet --outfile %s.exr %s.pbrt` | %.1f | %s |\n' \
    "$name" "$oracle" "$THREADS" "$name" "$name" "$seconds" "$(date -u +%F)" >>"$log"
  echo "render_references: $name ($oracle) ${seconds%.*} s"
done
