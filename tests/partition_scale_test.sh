#!/usr/bin/env bash
# Partitioning scales linearly (issue 48): the island at scale 1 (its
# instances become instanced proxies) and at scale 3 (they exceed
# --max-proxies and are merged as world boxes), on 8 ranks with `best`.
# Fails when CPU time or peak resident memory per instance grows more than
# 1.5x from scale 1 to scale 3, or when scale 3 under --memory-budget peaks
# above the budget plus the process's fixed overhead. The figures are the
# process's own (CPU seconds and peak resident set from /usr/bin/time); the
# full curve up to scale 30 is bench/partition_memory.sh's.
set -uo pipefail
ferry=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

# partition NAME SCENE [ARGS...]: runs `ferry partition` under /usr/bin/time;
# prints "cpu_seconds peak_bytes instances".
partition() {
  local name=$1 scene=$2
  shift 2
  /usr/bin/time -f "%U %S %M" -o "$work/$name.time" \
    "$ferry" partition "$scene" --ranks 8 --partitioner best -o "$work/$name" "$@" \
    > "$work/$name.log" 2>&1 || { fail "$name: ferry partition failed"; cat "$work/$name.log"; return 1; }
  local instances
  instances=$("$ferry" info --json "$scene" | python3 -c "import json, sys; print(json.load(sys.stdin)['instances'])")
  awk -v inst="$instances" '{printf "%.2f %d %d\n", $1 + $2, $3 * 1024, inst}' "$work/$name.time"
  rm -rf "${work:?}/$name"
}

read -r cpu1 peak1 inst1 < <(partition s1 'builtin:island?scale=1' -q) || exit 1
read -r cpu3 peak3 inst3 < <(partition s3 'builtin:island?scale=3') || exit 1
grep -q "merged from" "$work/s3.log" || fail "scale 3 did not reach --max-proxies (the test wants the merge)"
echo "  scale 1: $inst1 instances, ${cpu1} s CPU, peak $((peak1 >> 20)) MiB"
echo "  scale 3: $inst3 instances, ${cpu3} s CPU, peak $((peak3 >> 20)) MiB"
python3 - "$cpu1" "$peak1" "$inst1" "$cpu3" "$peak3" "$inst3" <<'PY' || fail "per-instance growth"
import sys
cpu1, peak1, inst1, cpu3, peak3, inst3 = map(float, sys.argv[1:])
time_growth = (cpu3 / inst3) / (cpu1 / inst1)
peak_growth = (peak3 / inst3) / (peak1 / inst1)
print(f"  per instance, scale 3 / scale 1: CPU time {time_growth:.2f}x, peak memory {peak_growth:.2f}x (limit 1.5x)")
sys.exit(0 if time_growth <= 1.5 and peak_growth <= 1.5 else 1)
PY

# Under a budget: the peak stays within the budget plus the fixed overhead
# of the process (libraries, allocator), taken as the peak of partitioning a
# small island.
read -r _ overhead _ < <(partition small 'builtin:island?scale=0.05' -q) || exit 1
budget_mib=200
read -r _ peakb _ < <(partition budget 'builtin:island?scale=3' --memory-budget ${budget_mib}MiB) || exit 1
grep -q "geometry out of memory" "$work/budget.log" || fail "the budget did not put the geometry out of memory"
limit=$(((budget_mib << 20) + overhead))
echo "  scale 3 under ${budget_mib} MiB: peak $((peakb >> 20)) MiB (limit: budget + $((overhead >> 20)) MiB overhead)"
if [ -n "${ASAN_OPTIONS:-}" ]; then
  # Under AddressSanitizer (scripts/sanitize.sh) the peak holds its shadow
  # memory and quarantine, not the program's own: the bound is not checked.
  echo "  (ASan: the budgeted peak is not the program's own; not checked)"
else
  ((peakb <= limit)) || fail "budgeted peak $((peakb >> 20)) MiB above $((limit >> 20)) MiB"
fi

if ((failures > 0)); then
  echo "$failures failure(s)"
  exit 1
fi
echo "partition_scale_test: all passed"
