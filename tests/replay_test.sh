#!/usr/bin/env bash
# The replay path layout (docs/data-parallel.md, "Above 64 ranks: replay"):
#  1. Forced at 3 and 4 ranks (--path-layout replay), every forwarding mode
#     renders the 1-rank image (same tolerance as distributed_test.sh), with no
#     revisit and forwards = receives. With one owner per instance
#     (round-robin) the replay and mask layouts make exactly the same
#     forwarding decisions, so their ray counters are equal.
#  2. One real run above 64 ranks (65, where masks no longer fit and `auto`
#     picks replay): the image equals the 1-rank image, no ray visits a rank
#     twice, and the counters are printed.
#  3. A part directory written in format 1 (before owner sets grew past 64
#     ranks) still renders.
set -euo pipefail
ferry=$1
source_dir=$2
source "$source_dir/tests/tools/multirank_test_env.sh"
start=$SECONDS

cornell="builtin:cornell"
cornell_args="--size 40x40 --spp 2 --max-depth 4 --seed 3 -q"
island="builtin:island?scale=0.05"
island_args="--size 48x32 --spp 1 --max-depth 3 --seed 3 -q"

# Stats fields a replay run must show; $2: expected ranks.
check_layout() {
  python3 - "$1" "$2" "$3" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))["settings"]
assert s["path_layout"] == sys.argv[3], s["path_layout"]
assert s["ranks"] == int(sys.argv[2]), s["ranks"]
assert s["path_bytes"] == {"mask8": 36, "replay": 40, "mask64": 56}[sys.argv[3]], s["path_bytes"]
PY
}

echo "== 1. replay forced at 3 and 4 ranks"
"$ferry" render "$cornell" $cornell_args -o "$work/cornell.pfm"
"$ferry" render "$island" $island_args -o "$work/island.pfm"
"$ferry" render "$cornell" $cornell_args --path-layout replay -o "$work/cornell-1-replay.pfm"
$compare "$work/cornell.pfm" "$work/cornell-1-replay.pfm" --rel 0 --abs 0
for ranks in 3 4; do
  for forwarding in proxies ring broadcast; do
    out="$work/cornell-$ranks-$forwarding.pfm"
    mpirun_n "$ranks" "$ferry" render "$cornell" $cornell_args --threads 1 --path-layout replay \
      --forwarding "$forwarding" --partition random -o "$out" --stats "$out.json"
    echo "cornell, $ranks ranks, $forwarding, random partition, replay:"
    $compare "$work/cornell.pfm" "$out" --outliers 0.002
    check_stats "$out.json"
    check_layout "$out.json" "$ranks" replay
  done
done
for forwarding in proxies ring broadcast; do
  for layout in replay mask; do
    out="$work/island-4-$forwarding-$layout.pfm"
    mpirun_n 4 "$ferry" render "$island" $island_args --threads 1 --path-layout "$layout" \
      --forwarding "$forwarding" --partition round-robin -o "$out" --stats "$out.json"
  done
  echo "island, 4 ranks, $forwarding, replay:"
  $compare "$work/island.pfm" "$work/island-4-$forwarding-replay.pfm" --outliers 0.002
  echo "island, 4 ranks, $forwarding, mask:"
  $compare "$work/island.pfm" "$work/island-4-$forwarding-mask.pfm" --outliers 0.002
  check_stats "$work/island-4-$forwarding-replay.pfm.json"
  check_layout "$work/island-4-$forwarding-replay.pfm.json" 4 replay
  check_layout "$work/island-4-$forwarding-mask.pfm.json" 4 mask8
  # One owner per instance: the same decisions, ray for ray.
  python3 - "$work/island-4-$forwarding-replay.pfm.json" "$work/island-4-$forwarding-mask.pfm.json" <<'PY'
import json, sys
r, m = (json.load(open(p))["render"]["total"] for p in sys.argv[1:])
for key in ("camera_paths", "continuation_rays", "shadow_rays"):
    assert r[key] == m[key], (key, r[key], m[key])
for key in ("closest", "occlusion", "retrace"):
    assert r["traces"][key] == m["traces"][key], (key, r["traces"][key], m["traces"][key])
for key in ("rays_forwarded", "rounds", "visits_without_hit"):
    assert r["exchange"][key] == m["exchange"][key], (key, r["exchange"][key], m["exchange"][key])
print(f"  replay = mask: forwarded {r['exchange']['rays_forwarded']}, "
      f"closest traces {r['traces']['closest']}, replay queries {r['traces']['replay_queries']}")
PY
done
echo "  (${SECONDS}s so far)"

echo "== 2. 65 ranks"
# From a part directory: made on the fly, every rank would generate the whole
# island first (about a minute of the 2 shared cores for 65 ranks); from
# parts (format 2, owner sets of two words) each rank reads only its own.
# 65 ranks take about 2 GB of memory (30 MB each).
big_args="--size 96x54 --spp 1 --max-depth 3 --seed 3 -q"
"$ferry" render "$island" $big_args -o "$work/island-big.pfm"
"$ferry" partition "$island" --ranks 65 --partitioner best -o "$work/island-65-parts" -q
t0=$SECONDS
OMPI_MCA_mpi_yield_when_idle=1 mpirun_n 65 "$ferry" render "$work/island-65-parts" $big_args --threads 1 \
  -o "$work/island-65.pfm" --stats "$work/island-65.json"
echo "island, 65 ranks (auto layout), best partition from parts, $((SECONDS - t0)) s:"
$compare "$work/island-big.pfm" "$work/island-65.pfm" --outliers 0.002
check_stats "$work/island-65.json"
check_layout "$work/island-65.json" 65 replay
python3 - "$work/island-65.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
r = s["render"]
t = r["total"]
fwd = t["exchange"]["rays_forwarded"]
print(f"  65 ranks: {s['seconds']['total']:.1f} s total, forwarded {fwd}, rounds {t['exchange']['rounds']}, "
      f"revisits {r['revisits']}, replay queries {t['traces']['replay_queries']} "
      f"({t['traces']['replay_queries'] / max(1, fwd):.2f} per forward), "
      f"max peak resident {s['memory']['max_peak_resident_bytes'] / 2**20:.0f} MiB per rank")
assert fwd > 0
PY
echo "  (${SECONDS}s so far)"

echo "== 3. format 1 part directory"
mpirun_n 3 "$ferry" render "$source_dir/tests/corpus/parts-v1" $cornell_args --threads 1 \
  -o "$work/cornell-v1.pfm"
$compare "$work/cornell.pfm" "$work/cornell-v1.pfm" --outliers 0.002
echo "replay_test: all passed in ${SECONDS}s"
