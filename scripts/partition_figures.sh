#!/usr/bin/env bash
# Regenerates the figures and numbers of docs/partitioning.md:
#   docs/images/max-part-{island,landscape}.{csv,png}   largest part, 1..128 ranks
#   docs/images/partition-{island,landscape}-NAME.png   each partitioner at 8 ranks
#   docs/images/partition-times.txt                     partitioning time and largest part at 8 ranks
#   docs/images/forwarding.txt                          rays forwarded per partitioner (8 ranks)
# Usage: scripts/partition_figures.sh [path/to/ferry]   (default: build/ferry)
set -euo pipefail
ferry=${1:-build/ferry}
here=$(cd "$(dirname "$0")/.." && pwd)
out="$here/docs/images"
mkdir -p "$out"
source "$here/tests/tools/mpi_env.sh"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
partitioners="spatial-simple spatial-sah object-naive object-proxies bvh-style best"

for scene in island landscape; do
  "$ferry" partition "builtin:$scene" --report "$out/max-part-$scene.csv" --ranks 1..128
done

declare -A view=([island]=overview [landscape]=top)
for scene in island landscape; do
  for p in $partitioners; do
    "$ferry" render "builtin:$scene" --partitioner "$p" --show-partition=8 --size 480x270 \
      --view "${view[$scene]}" -q -o "$out/partition-$scene-$p.png"
  done
done

{
  printf "%-10s %-15s %10s %12s %14s %8s\n" scene partitioner seconds "largest part" "% of scene" proxies
  for scene in island landscape; do
    for p in $partitioners; do
      "$ferry" partition "builtin:$scene" --ranks 8 --partitioner "$p" -o "$work/$scene-$p" > "$work/log"
      python3 - "$work/$scene-$p/manifest.json" "$scene" "$p" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))
largest = max(p["estimated_bytes"] for p in m["parts"])
print(f"{sys.argv[2]:<10} {sys.argv[3]:<15} {m['partition_seconds']:10.2f} {largest / 2**20:9.1f} MiB"
      f" {100 * largest / m['input_bytes']:13.1f}% {m['proxies']:8d}")
PY
    done
  done
} | tee "$out/partition-times.txt"

# Rays forwarded between ranks (the paper's Table 1), 8 ranks from part
# directories, a small image and one path per pixel. Scale 0.25 keeps eight
# ranks on a small machine.
{
  printf "%-10s %-15s %14s %10s %8s %14s\n" scene partitioner "rays forwarded" "per path" rounds "largest part"
  for scene in island landscape; do
    for p in $partitioners; do
      dir="$work/fwd-$scene-$p"
      "$ferry" partition "builtin:$scene?scale=0.25" --ranks 8 --partitioner "$p" -o "$dir" -q
      mpirun_n 8 "$ferry" render "$dir" --size 320x180 --spp 1 --max-depth 4 --threads 1 -q \
        -o "$work/fwd.pfm" --stats "$work/fwd.json"
      python3 - "$work/fwd.json" "$scene" "$p" "$dir/manifest.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))["render"]
m = json.load(open(sys.argv[4]))
fwd = s["total"]["exchange"]["rays_forwarded"]
paths = s["total"]["camera_paths"]
largest = max(p["estimated_bytes"] for p in m["parts"]) / m["input_bytes"]
print(f"{sys.argv[2]:<10} {sys.argv[3]:<15} {fwd:14d} {fwd / paths:10.2f} {s['total']['exchange']['rounds']:8d}"
      f" {100 * largest:13.1f}%")
PY
    done
  done
} | tee "$out/forwarding.txt"
