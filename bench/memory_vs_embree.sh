#!/usr/bin/env bash
# The memory estimate against Embree's memory monitor at scales the unit test
# (src/scene/memory_cost_test.cpp) does not build: for each scene, the
# accel + instances part of `ferry info --json` against the Embree bytes a
# one-rank render reports in its --stats (retained after the build, and peak).
# Counts, not timings: the machine's load does not matter.
#
#   bash bench/memory_vs_embree.sh [FERRY] [SCENE...]
#   bash bench/memory_vs_embree.sh build/ferry 'builtin:island?scale=1'
set -euo pipefail
ferry=${1:-build/ferry}
shift || true
scenes=("$@")
if [ ${#scenes[@]} -eq 0 ]; then
  scenes=(builtin:cornell builtin:furnace 'builtin:island?scale=0.1' 'builtin:landscape?scale=0.1'
          'builtin:island?scale=1' 'builtin:landscape?scale=1')
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

printf '%-28s %12s %12s %12s %10s %10s\n' scene "estimate B" "retained B" "peak B" est/ret est/peak
for scene in "${scenes[@]}"; do
  "$ferry" info "$scene" --json > "$work/info.json"
  "$ferry" render "$scene" --size 8x8 --spp 1 --max-depth 1 -q -o "$work/out.pfm" --stats "$work/stats.json"
  python3 - "$scene" "$work/info.json" "$work/stats.json" <<'EOF'
import json, sys
scene, info, stats = sys.argv[1], json.load(open(sys.argv[2])), json.load(open(sys.argv[3]))
m = info["memory_bytes"]
estimate = m["accel"] + m["instances"]
rank = stats["memory"]["per_rank"][0]
retained, peak = rank["embree_bytes"], rank["embree_peak_bytes"]
print(f"{scene:<28} {estimate:12.0f} {retained:12.0f} {peak:12.0f} {estimate / retained:10.3f} {estimate / peak:10.3f}")
EOF
done
