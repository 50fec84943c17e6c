#!/usr/bin/env bash
# Restyling a bricked volume in the viewer (docs/volumes.md, "Restyling"):
# `ferry view` of a SIZE^3 raw volume on RANKS ranks (bricked without a
# flag: 2^24 samples or more), binding off; the time from POST /settings
# with another colour map and opacity to the first served frame drawn with
# it, against the time from a camera change to its first frame (the same
# restart without a restyle), medians of CHANGES changes each, one run.
# Fails when the restyle median passes a second (issue 72's goal).
#
#   bash bench/viewer_restyle.sh [FERRY]
#   SIZE=512 RANKS=4 IMAGE=320x180 CHANGES=8 bash bench/viewer_restyle.sh
set -euo pipefail
ferry=$(realpath "${1:-build/ferry}")
size=${SIZE:-512}
ranks=${RANKS:-4}
image=${IMAGE:-320x180}
changes=${CHANGES:-8}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none OMPI_MCA_mpi_yield_when_idle=1
work=$(mktemp -d)
pid=""
trap '[ -n "$pid" ] && kill -9 "$pid" 2> /dev/null; rm -rf "$work"' EXIT

/usr/bin/python3 - "$work/vol.raw" "$size" << 'PY'
import sys, numpy as np
n = int(sys.argv[2])
c = (np.arange(n, dtype=np.float32) - n / 2) / n
with open(sys.argv[1], "wb") as f:
    for z in range(n):  # a slice at a time: a ball of noise-free shells
        y, x = np.meshgrid(c, c, indexing="ij")
        r = np.sqrt(x * x + y * y + c[z] * c[z])
        f.write((255 * np.clip(1 - 2 * r, 0, 1) * (0.6 + 0.4 * np.cos(40 * r))).astype(np.uint8).tobytes())
PY
echo "machine: $(nproc) cores, load before: $(cut -d' ' -f1-3 /proc/loadavg); ${size}^3 uint8 raw volume," \
  "$ranks ranks, $image, ferry $(git -C "$(dirname "$0")" rev-parse --short HEAD 2> /dev/null || echo "(no git)")"
mpirun --oversubscribe --bind-to none -np "$ranks" "$ferry" view \
  "raw:$work/vol.raw?dims=$size,$size,$size&format=uint8" --size "$image" --port 0 -q > "$work/view.log" 2>&1 &
pid=$!
url=""
for _ in $(seq 1200); do
  url=$(grep -o 'http://[^ ]*/' "$work/view.log" | head -1 || true)
  [ -n "$url" ] && break
  kill -0 "$pid" 2> /dev/null || { cat "$work/view.log"; exit 1; }
  sleep 0.1
done
[ -n "$url" ] || { cat "$work/view.log"; exit 1; }
/usr/bin/python3 - "$url" "$changes" << 'PY'
import json, math, statistics, sys, time, urllib.request
base, changes = sys.argv[1], int(sys.argv[2])
def stats():
    with urllib.request.urlopen(base + "stats", timeout=60) as r:
        return json.loads(r.read())
def post(path, body):
    req = urllib.request.Request(base + path, data=json.dumps(body).encode(), method="POST")
    urllib.request.urlopen(req, timeout=60).read()
def until(done):
    while True:
        s = stats()
        if done(s):
            return s
        time.sleep(0.005)
s = until(lambda s: s["frame_id"] >= 3)
if "color_maps" not in s:
    sys.exit("FAIL: the viewer offers no colour maps for the bricked volume")
maps = s["color_maps"]
restyles, moves = [], []
camera = s["camera"]
for k in range(changes):
    # A restyle: the next colour map and an opacity scale.
    wanted = {"color_map": maps[(k + 1) % len(maps)], "volume_opacity": [0.5, 2.0][k % 2]}
    before = stats()["frame_id"]
    start = time.time()
    post("settings", wanted)
    until(lambda s: s["settings"]["color_map"] == wanted["color_map"] and
          s["settings"]["volume_opacity"] == wanted["volume_opacity"] and s["frame_id"] > before)
    restyles.append(time.time() - start)
    time.sleep(0.3)
    # A camera change: the same restart, no restyle.
    offset = [f - a for f, a in zip(camera["from"], camera["at"])]
    angle = 0.05 * (1 if k % 2 == 0 else -1)
    c, s_ = math.cos(angle), math.sin(angle)
    moved = dict(camera, **{"from": [camera["at"][0] + c * offset[0] - s_ * offset[2], camera["from"][1],
                                     camera["at"][2] + s_ * offset[0] + c * offset[2]]})
    start = time.time()
    post("camera", moved)
    st = until(lambda s: all(abs(a - b) < 1e-3 * max(1, abs(b)) for a, b in zip(s["camera"]["from"], moved["from"])))
    moves.append(time.time() - start)
    camera = st["camera"]
    time.sleep(0.3)
frame = stats()["frame"]["seconds"]
print(f"restyle (colour map and opacity) to its first frame: median {statistics.median(restyles):.3f} s "
      f"(min {min(restyles):.3f}, max {max(restyles):.3f}); camera change to its first frame: median "
      f"{statistics.median(moves):.3f} s (min {min(moves):.3f}, max {max(moves):.3f}); "
      f"{changes} of each; a frame {frame:.3f} s")
post("quit", {})
if statistics.median(restyles) > 1.0:
    sys.exit("FAIL: a restyle took more than a second to reach a frame (the goal)")
PY
wait "$pid" || true
pid=""
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
