#!/usr/bin/env bash
# Data groups (--data-groups G): N ranks in G groups that each hold the whole
# scene over N/G ranks and render every G-th sample give the 1-rank image bit
# for bit, on the fly and from a part directory made for N/G ranks (the
# island and volume bricks); a checkpoint made with groups resumes without
# them; G that does not divide N is one message on every rank.
set -uo pipefail
ferry=$1
source_dir=$2
source "$source_dir/tests/tools/multirank_test_env.sh"
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

island="builtin:island?scale=0.05"
args="--size 48x32 --spp 4 --max-depth 3 --seed 7 -q --threads 1"
"$ferry" render "$island" $args -o "$work/one.pfm" || fail "one rank"
mpirun_n 4 "$ferry" render "$island" $args --data-groups 2 -o "$work/g2.pfm" --stats "$work/g2.json" \
  || fail "4 ranks in 2 groups"
cmp -s "$work/one.pfm" "$work/g2.pfm" || fail "4 ranks in 2 groups: not the 1-rank image"
/usr/bin/python3 - "$work/g2.json" << 'PY' || fail "the stats do not name the groups"
import json, sys
s = json.load(open(sys.argv[1]))
assert s["settings"]["data_groups"] == 2
assert [r["data_group"] for r in s["memory"]["per_rank"]] == [0, 0, 1, 1]
PY
"$ferry" partition "$island" --ranks 2 -o "$work/parts" -q || fail "partition for 2 ranks"
mpirun_n 6 "$ferry" render "$work/parts" $args --data-groups 3 -o "$work/g3.pfm" \
  || fail "a 2-rank part directory on 6 ranks in 3 groups"
cmp -s "$work/one.pfm" "$work/g3.pfm" || fail "6 ranks in 3 groups from parts: not the 1-rank image"
echo "  island: 1 rank = 4 ranks in 2 groups = 6 ranks in 3 groups from a 2-rank part directory"

# Checkpoints: made with groups, resumed without (and the image of the whole render).
"$ferry" render "$island" $args --frames 4 -o "$work/four.pfm" || fail "4 frames"
mpirun_n 4 "$ferry" render "$island" $args --data-groups 2 --frames 2 --checkpoint "$work/c.ckpt" \
  -o "$work/two.pfm" || fail "2 frames in groups, with a checkpoint"
mpirun_n 2 "$ferry" render "$island" $args --frames 4 --resume "$work/c.ckpt" -o "$work/resumed.pfm" \
  || fail "resumed"
cmp -s "$work/four.pfm" "$work/resumed.pfm" || fail "a checkpoint made in groups resumed: not the 4-frame image"
echo "  a checkpoint made in 2 groups resumes on 2 ranks to the same image"

# Volume bricks in groups.
"$ferry" render "builtin:volume?size=24" --volume-bricks 8 $args -o "$work/vol1.pfm" || fail "volume, 1 rank"
mpirun_n 4 "$ferry" render "builtin:volume?size=24" --volume-bricks 8 $args --data-groups 2 \
  -o "$work/vol4.pfm" || fail "volume, 4 ranks in 2 groups"
cmp -s "$work/vol1.pfm" "$work/vol4.pfm" || fail "volume bricks in 2 groups: not the 1-rank image"
echo "  volume bricks: 1 rank = 4 ranks in 2 groups"

# The bench runs (small): it checks every image against the 1-rank image.
SCENE="$island" SIZE=32x24 SPP=2 FRAMES=1 ROUNDS=1 CONFIGS="1x1 4x2" \
  bash "$source_dir/bench/data_groups.sh" "$ferry" > "$work/bench.log" 2>&1 \
  || { cat "$work/bench.log"; fail "bench/data_groups.sh"; }
echo "  bench/data_groups.sh (32x24, 1x1 and 4x2): $(tail -1 "$work/bench.log")"

start=$SECONDS
if timeout 60 mpirun --oversubscribe -np 4 "$ferry" render "$island" $args --data-groups 3 \
  -o "$work/bad.pfm" 2> "$work/stderr"; then
  fail "3 groups of 4 ranks were accepted"
fi
grep -q "data-groups 3" "$work/stderr" || fail "no message naming --data-groups 3: $(head -c 300 "$work/stderr")"
echo "  --data-groups 3 on 4 ranks: refused after $((SECONDS - start)) s: $(grep -m1 error "$work/stderr")"

if [ $failures -ne 0 ]; then
  echo "data_groups_test: $failures failure(s)"
  exit 1
fi
echo "data_groups_test: passed"
