#!/usr/bin/env bash
# Whether --stats' stage times say where a frame goes (issue 73): for each
# rank count, one render of SCENE with --stats, binding off, and per frame
# the stage seconds (generate, trace, exchange, shade, wait; summed over
# ranks) over the rank count times the frame's seconds. 1.00: every second
# of every rank's frame is in a stage. The final composite is measured after
# the frame and left out. Fails when a frame is outside 1 +- TOLERANCE.
#
#   bash bench/stage_times.sh [FERRY]
#   RANKS="1 4 8" SCENE="builtin:island?scale=0.1" SIZE=480x270 SPP=1 FRAMES=4 TOLERANCE=0.05 \
#     bash bench/stage_times.sh
set -euo pipefail
ferry=$(realpath "${1:-build/ferry}")
ranks=${RANKS:-1 4 8}
scene=${SCENE:-builtin:island?scale=0.1}
size=${SIZE:-480x270}
spp=${SPP:-1}
frames=${FRAMES:-4}
tolerance=${TOLERANCE:-0.05}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "machine: $(nproc) cores, load before: $(cut -d' ' -f1-3 /proc/loadavg); $scene $size," \
  "$spp spp, $frames frames, ferry $(git -C "$(dirname "$0")" rev-parse --short HEAD 2> /dev/null || echo "(no git)")"
status=0
for n in $ranks; do
  mpirun --oversubscribe --bind-to none -np "$n" "$ferry" render "$scene" --size "$size" --spp "$spp" \
    --frames "$frames" --threads 1 --stats "$work/stats$n.json" -o "$work/image$n.exr" -q > "$work/log$n" 2>&1 ||
    {
      cat "$work/log$n" >&2
      exit 1
    }
  /usr/bin/python3 - "$work/stats$n.json" "$n" "$tolerance" << 'PY' || status=1
import json, sys
stats, n, tolerance = json.load(open(sys.argv[1])), int(sys.argv[2]), float(sys.argv[3])
ratios = []
for f in stats["render"]["frames"]:
    staged = sum(v for k, v in f["stage_seconds"].items() if k != "composite")
    ratios.append(staged / (n * f["seconds"]))
print(f"{n} ranks: stage seconds / (ranks x frame seconds), frame by frame:",
      " ".join(f"{r:.3f}" for r in ratios))
sys.exit(0 if all(abs(r - 1) <= tolerance for r in ratios) else 1)
PY
done
[ "$status" = 0 ] || echo "FAIL: a frame's stage times are more than $tolerance from its time" >&2
exit "$status"
