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
#   3. memory per rank (estimated, Embree retained, resident), from --stats;
#   CPU seconds per frame summed over ranks ("cpu_seconds"), against 1 rank:
#   the work that distribution adds, apart from waiting and time-slicing.
# Data groups, stage shares, queries per camera path and what time-slicing
# alone costs (N ranks in N groups): bench/data_groups.sh.
# Every mpirun gets --bind-to none: Open MPI binds each rank to one core when
# it starts at most two, which left the 1-rank baseline's two threads on one
# core (0.51 s/frame instead of 0.28 on the island: every ratio measured
# before 2026-11-24 was against that handicapped baseline).
# THREADS=split (default) gives N ranks --threads max(1, CORES / N); THREADS=all
# gives every rank --threads CORES (more threads than cores when N > 1: a rank
# that waits leaves its cores to the others' threads).
# Frame time is the median over all measured frames of all rounds of a
# configuration (a frame's time is the slowest rank's); ROUNDS cycle through
# the configurations so a busy machine slows all alike. Counters are exact
# and independent of timing.
#
#   4. with BASELINE=old/ferry: the same proxies runs of another build in the
#      same rounds (interleaved), and its frame time per rank count against
#      this build's: before/after under the same load.
#   5. both exchanges (EXCHANGES, default "overlapped bulk"): every rank count
#      above 1 runs with each in the same rounds, so the overlapped exchange
#      (issue 13) and the paper's bulk rounds are compared under the same
#      load; the table gives each one's ratio to the same 1-rank frames, and
#      the share of stage time spent waiting (overlapped: idle in "wait";
#      bulk: inside the collectives, part of "exchange").
#
#   bash bench/distribution_cost.sh [FERRY]             (default build/ferry)
#   SCENE='builtin:island' SIZE=640x360 SPP=1 FRAMES=3 ROUNDS=3 CORES=$(nproc) \
#     PARTITION=best EXCHANGES="overlapped bulk" bash bench/distribution_cost.sh
# The camera: the scene's default view, VIEW=name, or any camera with
# LOOK_FROM=x,y,z LOOK_AT=x,y,z (and UP=x,y,z FOV=degrees), as ferry render's flags.
set -euo pipefail
ferry=$(realpath "${1:-build/ferry}")
SCENE=${SCENE:-builtin:island}
SIZE=${SIZE:-640x360}
SPP=${SPP:-1}
FRAMES=${FRAMES:-3}
ROUNDS=${ROUNDS:-3}
CORES=${CORES:-$(nproc)}
RANKS=${RANKS:-1 2 4 8}
PARTITION=${PARTITION:-best}
EXCHANGES=${EXCHANGES:-overlapped bulk}
THREADS=${THREADS:-split}
camera=()
[ -n "${VIEW:-}" ] && camera+=(--view "$VIEW")
[ -n "${LOOK_FROM:-}" ] && camera+=(--look-from "$LOOK_FROM")
[ -n "${LOOK_AT:-}" ] && camera+=(--look-at "$LOOK_AT")
[ -n "${UP:-}" ] && camera+=(--up "$UP")
[ -n "${FOV:-}" ] && camera+=(--fov "$FOV")
BASELINE=${BASELINE:+$(realpath "$BASELINE")}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none OMPI_MCA_mpi_yield_when_idle=1

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# run RANKS FORWARDING TAG [BINARY [EXTRA FLAGS...]]: one render; its stats go to $work/TAG.json.
run() {
  local n=$1 mode=$2 tag=$3 binary=${4:-$ferry} threads=$((CORES / $1))
  shift 4 2> /dev/null || shift $#
  [ "$threads" -ge 1 ] || threads=1
  [ "$THREADS" = all ] && threads=$CORES
  mpirun --oversubscribe --bind-to none -np "$n" "$binary" render "$SCENE" --size "$SIZE" --spp "$SPP" --frames "$FRAMES" \
    --threads "$threads" --forwarding "$mode" --partition "$PARTITION" -q -o "$work/out.pfm" \
    --stats "$work/$tag.json" "${camera[@]}" "$@"
}

echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)," \
  "$(free -g | awk '/Mem:/ {print $2}') GiB; load before: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "scene $SCENE, $SIZE, $SPP spp, $FRAMES frames, $ROUNDS rounds, $CORES cores for every configuration," \
  "partition $PARTITION, threads $THREADS, camera ${camera[*]:-default view}"

for round in $(seq "$ROUNDS"); do
  for n in $RANKS; do
    if [ "$n" -eq 1 ]; then
      run "$n" proxies "time-$n-$round"
    else
      first=1
      for exchange in $EXCHANGES; do
        run "$n" proxies "$exchange-$n-$round" "$ferry" --exchange "$exchange"
        if [ $first -eq 1 ]; then cp "$work/$exchange-$n-$round.json" "$work/time-$n-$round.json"; fi
        first=0
      done
    fi
    if [ -n "$BASELINE" ]; then run "$n" proxies "base-$n-$round" "$BASELINE"; fi
  done
done
# The forwarding modes at 4 and 8 ranks, where RANKS has them.
forwarding_ranks=""
for n in 4 8; do
  if [[ " $RANKS " == *" $n "* ]]; then
    forwarding_ranks+=" $n"
    for mode in ring broadcast; do run "$n" "$mode" "$mode-$n"; done
  fi
done
export FORWARDING_RANKS=$forwarding_ranks

python3 - "$work" "$ROUNDS" "$CORES" "${BASELINE:-none}" "$EXCHANGES" "$THREADS" $RANKS <<'EOF'
import json, os, statistics, sys
work, rounds, cores, baseline = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
exchanges, threads_mode = sys.argv[5].split(), sys.argv[6]
ranks = [int(r) for r in sys.argv[7:]]
load = lambda tag: json.load(open(f"{work}/{tag}.json"))
MiB = 1 / 2**20

print("\nframe time (median over frames and rounds; ratio to 1 rank, > 1: slower)")
frame = {}
for n in ranks:
    times = [f["seconds"] for r in range(1, rounds + 1) for f in load(f"time-{n}-{r}")["render"]["frames"]]
    frame[n] = statistics.median(times)
base = frame[ranks[0]]
for n in ranks:
    threads = cores if threads_mode == "all" else max(1, cores // n)
    print(f"  {n} rank(s) x {threads} thread(s): {frame[n]:7.3f} s/frame   ratio {frame[n] / base:5.2f}"
          f"   (frames: {', '.join(f'{f:.2f}' for r in range(1, rounds + 1) for f in [x['seconds'] for x in load(f'time-{n}-{r}')['render']['frames']])})")

# CPU time per frame, summed over ranks and threads ("cpu_seconds", absent
# from builds before it was counted): the work distribution adds, apart from
# the waiting and time-slicing that stretch wall clock.
def median_cpu(tag_of):
    values = [f["cpu_seconds"] for r in range(1, rounds + 1) for f in load(tag_of(r))["render"]["frames"]
              if "cpu_seconds" in f]
    return statistics.median(values) if values else None
cpu1 = median_cpu(lambda r: f"time-{ranks[0]}-{r}")
if cpu1:
    print("\nCPU time per frame, summed over ranks and threads (median; ratio to 1 rank: the work distribution adds)")
    for n in ranks:
        c = median_cpu(lambda r: f"time-{n}-{r}")
        print(f"  {n} rank(s): {c:7.3f} CPU s/frame   ratio {c / cpu1:5.2f}"
              f"   (the cores were busy {100 * c / (cores * frame[n]):3.0f}% of the frame)")

def median_frame(tag_of):
    return statistics.median([f["seconds"] for r in range(1, rounds + 1)
                              for f in load(tag_of(r))["render"]["frames"]])

# Stage seconds summed over ranks and over the frames after the first: the
# first frame's generate stage also holds the wait for the slowest rank's
# set-up (its first collective), which is not a frame's work.
def stage_seconds(s):
    frames = s["render"]["frames"]
    frames = frames[1:] if len(frames) > 1 else frames
    return {k: sum(f["stage_seconds"].get(k, 0) for f in frames) for k in frames[0]["stage_seconds"]}, len(frames)

print("\nby exchange (same rounds; ratio to the same 1-rank frames; wait share: of the stage time summed over ranks,"
      " frames after the first)")
for exchange in exchanges:
    for n in ranks[1:]:
        t = median_frame(lambda r: f"{exchange}-{n}-{r}")
        st = stage_seconds(load(f"{exchange}-{n}-1"))[0]
        stages = sum(st.get(k, 0) for k in ("generate", "trace", "exchange", "shade", "wait"))
        waiting = st.get("wait", 0) if exchange == "overlapped" else st["exchange"]
        print(f"  {exchange:10} {n} ranks: {t:7.3f} s/frame   ratio {t / base:5.2f}"
              f"   {'idle wait' if exchange == 'overlapped' else 'exchange (collectives)'} {100 * waiting / max(1e-12, stages):4.0f}% of stage time"
              f"   generate {100 * st['generate'] / max(1e-12, stages):4.1f}%")

if baseline != "none":
    print(f"\nthis build against the baseline {baseline} (same rounds, interleaved; < 1: this build is faster)")
    for n in ranks:
        times = [f["seconds"] for r in range(1, rounds + 1) for f in load(f"base-{n}-{r}")["render"]["frames"]]
        base_n = statistics.median(times)
        base_1 = statistics.median([f["seconds"] for r in range(1, rounds + 1)
                                    for f in load(f"base-{ranks[0]}-{r}")["render"]["frames"]])
        print(f"  {n} rank(s): {frame[n]:7.3f} s against {base_n:7.3f} s   ratio {frame[n] / base_n:5.2f}"
              f"   (baseline's own ratio to 1 rank: {base_n / base_1:5.2f})")

print("\nwhere the time goes (round 1, per frame): rays traced and forwarded (exact), stage seconds summed over ranks"
      " (frames after the first)")
for n in ranks:
    s = load(f"time-{n}-1")
    t, f = s["render"]["total"], len(s["render"]["frames"])
    st, stage_frames = stage_seconds(s)
    print(f"  {n} rank(s): traced {t['traces']['total'] / f:9.0f} (closest {t['traces']['closest'] / f:.0f},"
          f" shadow {t['traces']['occlusion'] / f:.0f}, re-trace {t['traces']['retrace'] / f:.0f}),"
          f" forwarded {t['exchange']['rays_forwarded'] / f:8.0f};"
          f" proxy queries per camera path {t['traces']['proxy_queries'] / max(1, t['camera_paths']):.2f};"
          f" s: " + ", ".join(f"{k} {st.get(k, 0) / stage_frames:.2f}" for k in ("generate", "trace", "exchange", "shade", "wait"))
          + f" (generate {100 * st['generate'] / max(1e-12, sum(st.get(k, 0) for k in ('generate', 'trace', 'exchange', 'shade', 'wait'))):.0f}%)")

print("\nrays forwarded per frame (exact counters; bytes and rounds per frame too)")
frames = lambda s: len(s["render"]["frames"])
for n in (int(r) for r in os.environ["FORWARDING_RANKS"].split()):
    for mode in ("proxies", "ring", "broadcast"):
        s = load(f"time-{n}-1") if mode == "proxies" else load(f"{mode}-{n}")
        ex, t = s["render"]["total"]["exchange"], s["render"]["total"]
        paths = t["camera_paths"] / frames(s)
        print(f"  {n} ranks {mode:9}: {ex['rays_forwarded'] / frames(s):12.0f} rays/frame"
              f" ({ex['rays_forwarded'] / frames(s) / paths:5.2f} per camera path),"
              f" {ex['bytes_sent'] / frames(s) * MiB:8.2f} MiB/frame, {ex['rounds'] / frames(s):5.1f} rounds/frame,"
              f" {ex.get('messages', 0) / frames(s):7.0f} messages/frame,"
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
