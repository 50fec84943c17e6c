#!/usr/bin/env bash
# Data groups (docs/data-parallel.md, "Data groups") measured in one run:
# frame time against 1 rank on the same cores (binding off; N ranks get
# max(1, CORES / N) threads each), rays forwarded per camera path and the
# largest rank's estimated memory, for 4 ranks and for 8 ranks as 1 group
# of 8, 2 of 4 and 4 of 2. Configurations alternate over ROUNDS; a frame's
# time is the slowest rank's, the median over frames and rounds. SPP is at
# least the largest group count, so that every group has samples to render.
#
#   bash bench/data_groups.sh [FERRY]
#   SCENE=builtin:island SIZE=480x270 SPP=4 FRAMES=2 ROUNDS=2 bash bench/data_groups.sh
set -euo pipefail
ferry=$(realpath "${1:-build/ferry}")
SCENE=${SCENE:-builtin:island}
SIZE=${SIZE:-480x270}
SPP=${SPP:-4}
FRAMES=${FRAMES:-2}
ROUNDS=${ROUNDS:-2}
CORES=${CORES:-$(nproc)}
CONFIGS=${CONFIGS:-"1x1 4x1 8x1 8x2 8x4"}  # ranks x groups
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none OMPI_MCA_mpi_yield_when_idle=1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs);" \
  "scene $SCENE, $SIZE, $SPP spp, $FRAMES frames, $ROUNDS rounds, best, ferry $(git -C "$(dirname "$0")" rev-parse --short HEAD 2> /dev/null || echo '(no git)')"
for round in $(seq "$ROUNDS"); do
  for config in $CONFIGS; do
    n=${config%x*} g=${config#*x}
    threads=$((CORES / n))
    [ "$threads" -ge 1 ] || threads=1
    mpirun --oversubscribe --bind-to none -np "$n" "$ferry" render "$SCENE" --size "$SIZE" --spp "$SPP" \
      --frames "$FRAMES" --threads "$threads" --partition best --data-groups "$g" -q \
      -o "$work/$config.pfm" --stats "$work/$config.$round.json"
  done
done
for config in $CONFIGS; do
  cmp -s "$work/1x1.pfm" "$work/$config.pfm" || { echo "FAIL: $config: not the 1-rank image"; exit 1; }
done
/usr/bin/python3 - "$work" "$ROUNDS" $CONFIGS << 'PY'
import json, statistics, sys
work, rounds, configs = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
def load(c):
    return [json.load(open(f"{work}/{c}.{r}.json")) for r in range(1, rounds + 1)]
def frame(runs):
    return statistics.median(f["seconds"] for s in runs for f in s["render"]["frames"])
base = frame(load("1x1"))
print("\n| ranks | groups | ranks a group | frame (s) | x 1 rank | forwards / camera path | largest rank (MiB, estimated) |")
print("|---:|---:|---:|---:|---:|---:|---:|")
for c in configs:
    runs = load(c)
    n, g = (int(v) for v in c.split("x"))
    t = runs[0]["render"]["total"]
    fwd = t["exchange"]["rays_forwarded"] / max(1, t["camera_paths"])
    mem = runs[0]["memory"]["max_estimated_bytes"] / 2**20
    print(f"| {n} | {g} | {n // g} | {frame(runs):.3f} | {frame(runs) / base:.2f} | {fwd:.2f} | {mem:.0f} |")
print("\nevery image equals the 1-rank image")
PY
