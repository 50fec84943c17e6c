#!/usr/bin/env bash
# A volume spread over ranks in bricks (docs/volumes.md, "Bricks across
# ranks"), measured in one run: a SIZE^3 float32 raw volume (two smooth
# blobs, written by numpy) in BRICK^3 bricks (default auto: no flag, the
# size Ferry chooses) on RANKS ranks against 1 rank
# on the same cores (binding off), and loaded natively distributed (each
# rank reads its own brick files, cut by scripts/cut_bricks.py) against
# partitioning the assembled volume and loading the parts.
#
#   bash bench/volume_bricks.sh                       # SIZE=1024 BRICK=auto RANKS=8
#   SIZE=256 bash bench/volume_bricks.sh              # a quick run
#
# Prints per rank estimated and resident bytes against total/RANKS, rays
# forwarded per camera path (paths: brick crossings; shadow rays), frame
# times, the partition step's time and peak memory, time to first pixel
# both ways, and `ferry info`'s total against the 1-rank render's resident
# memory; checks every image equals the 1-rank image. Needs about 3.2 x
# SIZE^3 x 4 bytes of memory (the partitioning process) and 4 x that of disk.
set -euo pipefail
cd "$(dirname "$0")/.."
ferry=${FERRY:-build/ferry}
size=${SIZE:-1024}
brick=${BRICK:-auto}
bricks_flag=""
if [ "$brick" = auto ]; then
  # Ferry's own choice (shapes/volume_brick.h, autoBrickVoxels), for the brick files.
  brick=$(( size / 16 / 8 * 8 )); [ $brick -lt 32 ] && brick=32; [ $brick -gt 128 ] && brick=128
  [ $((size * size * size)) -ge 16777216 ] \
    || { echo "SIZE=$size: auto keeps a grid under 2^24 samples whole; give BRICK"; exit 2; }
else
  bricks_flag="--volume-bricks $brick"
fi
ranks=${RANKS:-8}
image=${IMAGE:-480x270}
frames=${FRAMES:-2}
work=${WORK:-$(mktemp -d /tmp/ferry-volume-bricks.XXXX)}
python=/usr/bin/python3
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
mpi() { mpirun --oversubscribe --bind-to none -np "$@"; }
trap '[ -z "${KEEP:-}" ] && rm -rf "$work"' EXIT

echo "volume ${size}^3 float32 ($((size * size * size * 4 / 1048576)) MiB), bricks ${brick}^3 (${bricks_flag:-no flag}), $ranks ranks, $(nproc) cores, ferry $(git rev-parse --short HEAD 2> /dev/null || echo "(no git)")"
$python - "$work/vol.raw" "$size" << 'PY'
import sys, numpy as np
n = int(sys.argv[2])
c = np.arange(n, dtype=np.float32) / n
with open(sys.argv[1], "wb") as f:
    for z in range(n):  # a slice at a time
        y, x = np.meshgrid(c, c, indexing="ij")
        zz = np.float32(z / n)
        v = np.exp(-((x - .4) ** 2 + (y - .45) ** 2 + (zz - .45) ** 2) / .03) \
          + .7 * np.exp(-((x - .7) ** 2 + (y - .6) ** 2 + (zz - .5) ** 2) / .015)
        f.write(v.astype("<f4").tobytes())
PY
raw="raw:$work/vol.raw?dims=$size,$size,$size&format=float32&opacity=60"
render="--size $image --spp 1 --frames $frames --max-depth 4 --seed 1 -q"

# peak RSS (KiB) and wall seconds of a command, via /usr/bin/time
timed() { /usr/bin/time -f "%e %M" -o "$work/time" "$@"; cat "$work/time"; }

read -r part_s part_kib < <(timed "$ferry" partition "$raw" $bricks_flag --ranks "$ranks" -o "$work/parts" -q)
"$ferry" info "$raw" $bricks_flag --json > "$work/info.json"
mpi 1 "$ferry" render "$raw" $bricks_flag $render -o "$work/one.pfm" --stats "$work/one.json"
sync
mpi "$ranks" "$ferry" render "$work/parts" $render -o "$work/parts.pfm" --stats "$work/parts.json"
$python scripts/cut_bricks.py "$work/vol.raw" "$size,$size,$size" float32 "$brick" "$work/bricks" > /dev/null
$python - "$work/bricks/volume.json" << 'PY'
import json, sys
m = json.load(open(sys.argv[1])); m["opacity"] = 60; json.dump(m, open(sys.argv[1], "w"))
PY
rm -f "$work/vol.raw"
sync  # both ways read files already on disk: no write-back during the timed render
mpi "$ranks" "$ferry" render "bricks:$work/bricks/volume.json" $render -o "$work/native.pfm" --stats "$work/native.json"
for image_file in parts native; do
  cmp -s "$work/one.pfm" "$work/$image_file.pfm" && echo "image ($image_file, $ranks ranks) = 1-rank image" \
    || { echo "FAIL: the $image_file image differs from the 1-rank image"; exit 1; }
done
$python - "$work" "$ranks" "$part_s" "$part_kib" << 'PY'
import json, sys
work, ranks, part_s, part_kib = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4])
one, parts, native, info = (json.load(open(f"{work}/{n}.json")) for n in ("one", "parts", "native", "info"))
MiB = 1 << 20
def frame(s):
    fr = s["render"]["frames"]
    return min(f["seconds"] for f in fr) if fr else s["render"]["total"]["seconds"]
total = one["memory"]["per_rank"][0]["estimated_bytes"]
print(f"\n1 rank holds {total / MiB:.0f} MiB (estimated); total/{ranks} = {total / ranks / MiB:.0f} MiB")
print("\n| rank | estimated MiB | x total/N | resident MiB | peak resident MiB |")
print("|---:|---:|---:|---:|---:|")
for r in parts["memory"]["per_rank"]:
    print(f"| {r['rank']} | {r['estimated_bytes'] / MiB:.0f} | {r['estimated_bytes'] * ranks / total:.2f} | "
          f"{r['resident_bytes'] / MiB:.0f} | {r['peak_resident_bytes'] / MiB:.0f} |")
t = parts["render"]["total"]
paths = t["camera_paths"]
ex = t["exchange"]
print(f"\nrays forwarded per camera path: {(ex['rays_forwarded'] - ex['shadow_rays_forwarded']) / paths:.2f} paths (brick crossings), "
      f"{ex['shadow_rays_forwarded'] / paths:.2f} shadow rays")
f1, fn = frame(one), frame(parts)
print(f"frame: 1 rank {f1:.3f} s, {ranks} ranks {fn:.3f} s ({fn / f1:.2f}x, same cores, binding off)")
fp = lambda s: max(r["first_pixel"] for r in s["seconds"]["per_rank"])
peak = lambda s: max(r["peak_resident_bytes"] for r in s["memory"]["per_rank"]) / MiB
largest = max(r["estimated_bytes"] for r in parts["memory"]["per_rank"]) * ranks / total
print(f"largest rank: {largest:.2f} x total/{ranks} (the goal: at most 1.3)")
print(f"\npartitioning the assembled volume: {part_s:.1f} s, peak {part_kib / 1024:.0f} MiB (one process holds it all)")
print(f"time to first pixel: parts {fp(parts):.2f} s (largest rank peak {peak(parts):.0f} MiB); "
      f"natively distributed {fp(native):.2f} s (largest rank peak {peak(native):.0f} MiB)")
told = info["memory_bytes"]["total"]
held = one["memory"]["per_rank"][0]["resident_bytes"]
print(f"ferry info's total {told / MiB:.0f} MiB against the 1-rank render's resident {held / MiB:.0f} MiB "
      f"({told / held:.3f}; the process's own libraries are not the scene's)")
if largest > 1.3:
    sys.exit("FAIL: the largest rank holds more than 1.3 x its share")
PY
