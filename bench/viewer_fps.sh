#!/usr/bin/env bash
# The viewer's speed (issue 15): frames per second of `ferry view` on the
# island at 640x360, 1 path per pixel per frame, on 1, 2 and 4 ranks of this
# machine (Ferry's default threads, --threads 0; --bind-to none), and the time from
# a camera change (POST /camera) to the first image of the new camera
# (/frame.png whose frame shows it), the median of several changes.
#
#   bash bench/viewer_fps.sh [FERRY]
#   SCENE=builtin:island SIZE=640x360 RANKS="1 2 4" SECONDS_EACH=10 CHANGES=8 bash bench/viewer_fps.sh
#   CONFIGS="4x1 4x2" bash bench/viewer_fps.sh     (ranks x data groups; overrides RANKS)
set -euo pipefail
ferry=$(realpath "${1:-build/ferry}")
SCENE=${SCENE:-builtin:island}
SIZE=${SIZE:-640x360}
RANKS=${RANKS:-1 2 4}
CONFIGS=${CONFIGS:-$(for n in $RANKS; do printf '%sx1 ' "$n"; done)}
SECONDS_EACH=${SECONDS_EACH:-10}
CHANGES=${CHANGES:-8}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none OMPI_MCA_mpi_yield_when_idle=1
work=$(mktemp -d)
pid=""
trap '[ -n "$pid" ] && kill -9 "$pid" 2> /dev/null; rm -rf "$work"' EXIT

echo "machine: $(nproc) cores, load before: $(cut -d' ' -f1-3 /proc/loadavg); $SCENE, $SIZE, 1 spp per frame"
for config in $CONFIGS; do
  n=${config%x*}
  groups=${config#*x}
  mpirun --oversubscribe --bind-to none -np "$n" "$ferry" view "$SCENE" --size "$SIZE" --port 0 -q \
    --data-groups "$groups" > "$work/view-$n.log" 2>&1 &
  pid=$!
  url=""
  for _ in $(seq 600); do
    url=$(grep -o 'http://[^ ]*/' "$work/view-$n.log" | head -1 || true)
    [ -n "$url" ] && break
    sleep 0.1
  done
  [ -n "$url" ] || { cat "$work/view-$n.log"; exit 1; }
  python3 - "$url" "$n" "$SECONDS_EACH" "$CHANGES" "$groups" <<'EOF'
import json, statistics, sys, time, urllib.request
base, ranks, seconds, changes = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4])
groups = int(sys.argv[5])
def get(path, timeout=30):
    with urllib.request.urlopen(base + path, timeout=timeout) as r:
        return r.read(), dict(r.headers)
def stats():
    return json.loads(get("stats")[0])
def post(path, body):
    req = urllib.request.Request(base + path, data=json.dumps(body).encode(), method="POST")
    urllib.request.urlopen(req, timeout=30).read()
# Warm up: the first frames (and the scene's set-up) are not counted.
while stats()["frame_id"] < 3:
    time.sleep(0.05)
s0, t0 = stats(), time.time()
time.sleep(seconds)
s1, t1 = stats(), time.time()
fps = (s1["frame_id"] - s0["frame_id"]) / (t1 - t0)
frame_s = s1["frame"]["seconds"]
# Camera changes: orbit a little each time; time until a frame of the new camera is served.
latencies = []
camera = s1["camera"]
for k in range(changes):
    offset = [f - a for f, a in zip(camera["from"], camera["at"])]
    angle = 0.05 * (1 if k % 2 == 0 else -1)
    import math
    c, s = math.cos(angle), math.sin(angle)
    moved = dict(camera, **{"from": [camera["at"][0] + c * offset[0] - s * offset[2], camera["from"][1],
                                     camera["at"][2] + s * offset[0] + c * offset[2]]})
    start = time.time()
    post("camera", moved)
    while True:
        st = stats()
        if st["camera"]["from"] == [float(x) for x in moved["from"]] or \
           all(abs(a - b) < 1e-3 * max(1, abs(b)) for a, b in zip(st["camera"]["from"], moved["from"])):
            break
        time.sleep(0.005)
    latencies.append(time.time() - start)
    camera = st["camera"]
    time.sleep(0.3)
print(f"  {ranks} rank(s) in {groups} group(s): {fps:5.2f} frames/s (last frame {frame_s:.3f} s, slowest rank);"
      f" camera change to first new image: median {statistics.median(latencies):.3f} s"
      f" (min {min(latencies):.3f}, max {max(latencies):.3f}, {len(latencies)} changes)")
post("quit", {})
EOF
  wait "$pid" || true
  pid=""
done
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
