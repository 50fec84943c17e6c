#!/usr/bin/env bash
# Partitioning writes safely (issue 17, item 4): the parts go into a
# temporary directory next to the target, swapped in only when complete. A
# partition that fails half-way or is killed leaves the previous directory
# as it was (same manifest, still renders) and no half-written one; a
# killed run's leftovers are removed by the next run; a directory that is not
# a part directory is never replaced; a part swapped for another is caught by
# the manifest's hashes before any rank renders.
set -uo pipefail
ferry=$1
source_dir=$2
source "$source_dir/tests/tools/multirank_test_env.sh"
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

cornell="builtin:cornell"
args="--size 32x24 --spp 1 --max-depth 2 --seed 3 -q --threads 1"
dir="$work/parts"
"$ferry" partition "$cornell" --ranks 3 --partitioner bvh-style -o "$dir" -q || fail "first partition"
cp "$dir/manifest.json" "$work/manifest.before"
mpirun_n 3 "$ferry" render "$dir" $args -o "$work/before.pfm" || fail "render the first parts"
leftovers() { find "$work" -maxdepth 1 -name '.parts.tmp.*' | wc -l; }

# A failure after part 1 is written: exit non-zero, previous directory intact.
if FERRY_FAIL_RANK=1 FERRY_FAIL_AT=partition-write "$ferry" partition "builtin:island?scale=0.05" \
  --ranks 3 --partitioner best -o "$dir" -q 2> "$work/stderr"; then
  fail "an injected write failure exited 0"
fi
grep -q "injected failure at partition-write" "$work/stderr" || fail "no message for the failure"
cmp -s "$dir/manifest.json" "$work/manifest.before" || fail "the failed partition changed the manifest"
[ "$(leftovers)" -eq 0 ] || fail "the failed partition left its temporary directory"
mpirun_n 3 "$ferry" render "$dir" $args -o "$work/after.pfm" && cmp -s "$work/before.pfm" "$work/after.pfm" \
  || fail "the previous parts no longer render the same image"
echo "  failed half-way: previous directory intact, no temporary left"

# Killed half-way (SIGKILL: nothing cleans up): the directory is the old
# one or a complete new one, never a mix; the next run removes the leftovers.
"$ferry" partition "builtin:island?scale=2" --ranks 4 --partitioner best -o "$dir" -q &
pid=$!
sleep 1
kill -9 "$pid" 2> /dev/null
wait "$pid" 2> /dev/null
if cmp -s "$dir/manifest.json" "$work/manifest.before"; then
  echo "  killed half-way: previous directory intact ($(leftovers) leftover temporary)"
else
  mpirun_n 4 "$ferry" render "$dir" $args -o "$work/killed.pfm" || fail "killed run left a broken directory"
  echo "  the run finished before the kill: the new directory is complete"
fi
"$ferry" partition "$cornell" --ranks 3 --partitioner bvh-style -o "$dir" -q || fail "partition after a kill"
[ "$(leftovers)" -eq 0 ] || fail "a killed run's temporary directory was not removed by the next run"
mpirun_n 3 "$ferry" render "$dir" $args -o "$work/again.pfm" && cmp -s "$work/before.pfm" "$work/again.pfm" \
  || fail "partitioning again did not give the same image"
echo "  the next run replaced it and removed the leftovers"

# Never replaces a directory that is not a part directory.
mkdir -p "$work/photos"
echo "precious" > "$work/photos/holiday.jpg"
if "$ferry" partition "$cornell" --ranks 2 -o "$work/photos" -q 2> "$work/stderr"; then
  fail "partitioned over a directory that is not a part directory"
fi
grep -q "not a part directory" "$work/stderr" || fail "no message for a foreign directory"
[ "$(cat "$work/photos/holiday.jpg")" = "precious" ] || fail "a foreign directory was changed"
echo "  a directory that is not a part directory: refused, untouched"

# A part swapped for another (same size class, valid file): the hashes catch it.
cp "$dir/part-0001.fpart" "$dir/part-0000.fpart"
if mpirun_n 3 "$ferry" render "$dir" $args -o "$work/swapped.pfm" 2> "$work/stderr"; then
  fail "rendered a directory with a swapped part"
fi
grep -q "part-0000.fpart" "$work/stderr" || fail "the swapped part is not named"
echo "  swapped part: $(grep -m1 'error' "$work/stderr" | cut -c1-150)"

if [ $failures -ne 0 ]; then echo "partition_write_test: $failures failures"; exit 1; fi
echo "partition_write_test: all passed"
