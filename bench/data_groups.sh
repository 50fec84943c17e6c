#!/usr/bin/env bash
# Distribution and data groups (docs/data-parallel.md, "Data groups") on the
# same cores, in one run: frame time against 1 rank (binding off; N ranks
# get max(1, CORES / N) threads each), CPU seconds a frame against 1 rank's
# (every rank's threads summed: on shared cores the frame ratio cannot fall
# below it while the 1-rank frame keeps the cores busy), rays forwarded per frame and per
# camera path, proxy queries per camera path, where the ranks' stage time
# goes (shares summed over ranks: generate, trace, exchange, shade, wait),
# the busiest rank's CPU over the mean rank's (a rank of one thread cannot
# take more than one core) and the largest rank's estimated memory. NxG is
# N ranks in G groups: NxN (groups of one rank: image parallel, no forwards,
# every rank the whole scene) is what time-slicing N processes on the cores
# costs by itself; when it ran, "x NxN" is each N-rank row's frame over it.
# Configurations alternate over ROUNDS; a frame's time is the slowest rank's,
# the median over frames and rounds. With fewer samples a frame than groups
# (SPP=1: the viewer's frames) the groups split a sample's pixels. With BASELINE=old/ferry
# the same configurations of another build run in the same rounds, and the
# table gives this build's frame time against it. THREADS=N gives every rank
# N threads instead (0: Ferry's default, workerThreads in session/session_settings.h).
#
#   bash bench/data_groups.sh [FERRY]
#   SCENE=builtin:island SIZE=480x270 SPP=8 FRAMES=3 ROUNDS=2 BASELINE=old/ferry \
#     PARTITION=ray-guided bash bench/data_groups.sh build/ferry
set -euo pipefail
ferry=$(realpath "${1:-build/ferry}")
SCENE=${SCENE:-builtin:island}
PARTITION=${PARTITION:-best}
SIZE=${SIZE:-480x270}
SPP=${SPP:-8}
FRAMES=${FRAMES:-3}
ROUNDS=${ROUNDS:-2}
CORES=${CORES:-$(nproc)}
THREADS=${THREADS:-}
CONFIGS=${CONFIGS:-"1x1 2x1 4x1 8x1 8x2 8x4 2x2 4x4 8x8"}  # ranks x groups
BASELINE=${BASELINE:-}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none OMPI_MCA_mpi_yield_when_idle=1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
builds="this"
[ -n "$BASELINE" ] && builds="this base"

echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs);" \
  "scene $SCENE, $SIZE, $SPP spp, $FRAMES frames, $ROUNDS rounds, $PARTITION, threads ${THREADS:-CORES/N}, ferry $(git -C "$(dirname "$0")" rev-parse --short HEAD 2> /dev/null || echo '(no git)')" \
  "${BASELINE:+, baseline $BASELINE}; load before: $(cut -d' ' -f1-3 /proc/loadavg)"
for round in $(seq "$ROUNDS"); do
  for config in $CONFIGS; do
    for build in $builds; do
      binary=$ferry
      [ "$build" = base ] && binary=$(realpath "$BASELINE")
      n=${config%x*} g=${config#*x}
      threads=${THREADS:-$((CORES / n))}
      [ -n "$THREADS" ] || [ "$threads" -ge 1 ] || threads=1
      mpirun --oversubscribe --bind-to none -np "$n" "$binary" render "$SCENE" --size "$SIZE" \
        --spp "$SPP" --frames "$FRAMES" --threads "$threads" --partition "$PARTITION" --data-groups "$g" -q \
        -o "$work/$build.$config.pfm" --stats "$work/$build.$config.$round.json"
    done
  done
done
for build in $builds; do
  for config in $CONFIGS; do
    cmp -s "$work/$build.1x1.pfm" "$work/$build.$config.pfm" \
      || { echo "FAIL: $build $config: not the 1-rank image"; exit 1; }
  done
done
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
/usr/bin/python3 - "$work" "$ROUNDS" "$builds" $CONFIGS << 'PY'
import json, statistics, sys
work, rounds, builds, configs = sys.argv[1], int(sys.argv[2]), sys.argv[3].split(), sys.argv[4:]
def load(b, c):
    return [json.load(open(f"{work}/{b}.{c}.{r}.json")) for r in range(1, rounds + 1)]
def frame(runs):
    return statistics.median(f["seconds"] for s in runs for f in s["render"]["frames"])
def cpu(runs):  # CPU seconds a frame, every rank's threads summed
    return statistics.median(f["cpu_seconds"] for s in runs for f in s["render"]["frames"])
def imbalance(runs, n):  # the busiest rank's CPU over the mean rank's, over all frames
    frames = [f for s in runs for f in s["render"]["frames"]]
    return n * sum(f["busiest_rank_cpu_seconds"] for f in frames) / max(1e-9, sum(f["cpu_seconds"] for f in frames))
base = frame(load("this", "1x1"))
base_cpu = cpu(load("this", "1x1"))
stages = ["generate", "trace", "exchange", "shade", "wait"]
print("\n| ranks | groups | ranks a group | frame (s) | x 1 rank | CPU x 1 rank | x NxN | busiest rank's CPU / mean |"
      + (" x baseline |" if "base" in builds else "")
      + " forwards / frame | forwards / camera path | proxy queries / camera path | "
      + " / ".join(stages) + " (% of stage time) | largest rank (MiB, estimated) |")
print("|---:|---:|---:|---:|---:|---:|---:|---:|" + ("---:|" if "base" in builds else "") + "---:|---:|---:|---|---:|")
for c in configs:
    runs = load("this", c)
    n, g = (int(v) for v in c.split("x"))
    t = runs[0]["render"]["total"]
    frames = len(runs[0]["render"]["frames"])
    paths = max(1, t["camera_paths"])
    fwd = t["exchange"]["rays_forwarded"]
    queries = t["traces"]["proxy_queries"]
    seconds = {k: sum(f["stage_seconds"][k] for s in runs for f in s["render"]["frames"]) for k in stages}
    total = max(1e-9, sum(seconds.values()))
    shares = " / ".join(f"{100 * seconds[k] / total:.0f}" for k in stages)
    mem = runs[0]["memory"]["max_estimated_bytes"] / 2**20
    versus = f" {frame(runs) / frame(load('base', c)):.2f} |" if "base" in builds else ""
    alone = f"{n}x{n}"
    slicing = f"{frame(runs) / frame(load('this', alone)):.2f}" if alone in configs and alone != c else ""
    print(f"| {n} | {g} | {n // g} | {frame(runs):.3f} | {frame(runs) / base:.2f} |"
          f" {cpu(runs) / base_cpu:.2f} | {slicing} | {imbalance(runs, n):.2f} |{versus}"
          f" {fwd / frames:,.0f} | {fwd / paths:.2f} | {queries / paths:.2f} | {shares} | {mem:.0f} |")
print("\nevery image equals the 1-rank image")
PY
