#!/usr/bin/env bash
# The cost of distribution (issue 4), in one run:
#   1. frame time at 2, 4 and 8 ranks against the 1-rank render, as ratios,
#      on the same cores: the baseline is 1 rank with --threads $CORES, and N
#      ranks get --threads max(1, CORES / N) each, so every configuration has
#      the same cores and more ranks than cores means time-slicing
#      (--oversubscribe, with Open MPI told to yield when idle so a waiting
#      rank does not spin on a core a working rank needs);
#   2. rays forwarded, bytes sent and exchange rounds per frame for every
#      forwarding mode (proxies, ring, broadcast) at 4 and 8 ranks, from the
#      --stats counters ("render"."total"."exchange");
#   3. memory per rank (estimated, Embree retained, resident), from --stats.
# Frame time is the median over all measured frames of all rounds of a
# configuration (a frame's time is the slowest rank's); ROUNDS cycle through
# the configurations so a busy machine slows all alike. Counters are exact
# and independent of timing.
#
#   bash bench/distribution_cost.sh [FERRY]             (default build/ferry)
#   SCENE='builtin:island' SIZE=640x360 SPP=1 FRAMES=3 ROUNDS=3 CORES=$(nproc) \
#     PARTITION=round-robin bash bench/distribution_cost.sh
set -euo pipefail
ferry=$(realpath "${1:-build/ferry}")
SCENE=${SCENE:-builtin:island}
SIZE=${SIZE:-640x360}
SPP=${SPP:-1}
FRAMES=${FRAMES:-3}
ROUNDS=${ROUNDS:-3}
CORES=${CORES:-$(nproc)}
RANKS=${RANKS:-1 2 4 8}
PARTITION=${PARTITION:-round-robin}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none OMPI_MCA_mpi_yield_when_idle=1

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# run RANKS FORWARDING TAG: one render; its stats go to $work/TAG.json.
run() {
  local n=$1 mode=$2 tag=$3 threads=$((CORES / $1))
  [ "$threads" -ge 1 ] || threads=1
  mpirun --oversubscribe -np "$n" "$ferry" render "$SCENE" --size "$SIZE" --spp "$SPP" --frames "$FRAMES" \
    --threads "$threads" --forwarding "$mode" --partition "$PARTITION" -q -o "$work/out.pfm" --stats "$work/$tag.json"
}

echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)," \
  "$(free -g | awk '/Mem:/ {print $2}') GiB; load before: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "scene $SCENE, $SIZE, $SPP spp, $FRAMES frames, $ROUNDS rounds, $CORES cores for every configuration," \
  "partition $PARTITION"

for round in $(seq "$ROUNDS"); do
  for n in $RANKS; do run "$n" proxies "time-$n-$round"; done
done
for n in 4 8; do
  for mode in ring broadcast; do run "$n" "$mode" "$mode-$n"; done
done

python3 - "$work" "$ROUNDS" "$CORES" $RANKS <<'EOF'
import json, statistics, sys
work, rounds, cores, ranks = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), [int(r) for r in sys.argv[4:]]
load = lambda tag: json.load(open(f"{work}/{tag}.json"))
MiB = 1 / 2**20

print("\nframe time (median over frames and rounds; ratio to 1 rank, > 1: slower)")
frame = {}
for n in ranks:
    times = [f["seconds"] for r in range(1, rounds + 1) for f in load(f"time-{n}-{r}")["render"]["frames"]]
    frame[n] = statistics.median(times)
base = frame[ranks[0]]
for n in ranks:
    threads = max(1, cores // n)
    print(f"  {n} rank(s) x {threads} thread(s): {frame[n]:7.3f} s/frame   ratio {frame[n] / base:5.2f}"
          f"   (frames: {', '.join(f'{f:.2f}' for r in range(1, rounds + 1) for f in [x['seconds'] for x in load(f'time-{n}-{r}')['render']['frames']])})")

print("\nwhere the time goes (round 1, per frame): rays traced and forwarded (exact), stage seconds summed over ranks")
for n in ranks:
    s = load(f"time-{n}-1")
    t, f = s["render"]["total"], len(s["render"]["frames"])
    st = t["stage_seconds"]
    print(f"  {n} rank(s): traced {t['traces']['total'] / f:9.0f} (closest {t['traces']['closest'] / f:.0f},"
          f" shadow {t['traces']['occlusion'] / f:.0f}, re-trace {t['traces']['retrace'] / f:.0f}),"
          f" forwarded {t['exchange']['rays_forwarded'] / f:8.0f};"
          f" s: " + ", ".join(f"{k} {st[k] / f:.2f}" for k in ("generate", "trace", "exchange", "shade")))

print("\nrays forwarded per frame (exact counters; bytes and rounds per frame too)")
frames = lambda s: len(s["render"]["frames"])
for n in (4, 8):
    for mode in ("proxies", "ring", "broadcast"):
        s = load(f"time-{n}-1") if mode == "proxies" else load(f"{mode}-{n}")
        ex, t = s["render"]["total"]["exchange"], s["render"]["total"]
        paths = t["camera_paths"] / frames(s)
        print(f"  {n} ranks {mode:9}: {ex['rays_forwarded'] / frames(s):12.0f} rays/frame"
              f" ({ex['rays_forwarded'] / frames(s) / paths:5.2f} per camera path),"
              f" {ex['bytes_sent'] / frames(s) * MiB:8.2f} MiB/frame, {ex['rounds'] / frames(s):5.1f} rounds/frame,"
              f" rays traced {t['traces']['total'] / frames(s):10.0f}/frame")

print("\nmemory per rank, MiB (estimated / Embree retained / resident; max and mean over ranks)")
for n in ranks:
    m = load(f"time-{n}-1")["memory"]
    per = m["per_rank"]
    col = lambda k: [r[k] * MiB for r in per]
    fmt = lambda k: f"{max(col(k)):8.1f} max {statistics.mean(col(k)):8.1f} mean"
    print(f"  {n} rank(s): estimated {fmt('estimated_bytes')} | Embree {fmt('embree_bytes')} |"
          f" resident {fmt('resident_bytes')}   (whole scene estimated {m['scene_estimated_bytes'] * MiB:.1f})")
EOF
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
