#!/usr/bin/env bash
# `ferry view` on 2 ranks: the API (frames grow, PNGs of the set size, a
# camera change restarts the accumulation and changes the image, a corpus of
# bad requests each gets a 4xx and the server stays up), the page in headless
# Chromium (the image is not blank, dragging orbits the camera and restarts
# the accumulation; the screenshot is kept), a raw volume's colour map and
# opacity changed from the page (held whole, and in bricks over the ranks),
# another array of a .vti chosen on the page, POST /quit and Ctrl-C end every
# rank within 5 s, a long session keeps resident memory flat, a rank's
# failure ends the viewer with its message, and a port in use is a clear
# error.
set -uo pipefail
ferry=$1
source_dir=$2
source "$source_dir/tests/tools/mpi_env.sh"
work=$(mktemp -d)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -9 "$p" 2> /dev/null; done
  rm -rf "$work"
}
trap cleanup EXIT
check="python3 $source_dir/tests/tools/viewer_check.py"
fail() { echo "FAIL: $*"; for f in "$work"/*.log; do echo "== $f"; tail -20 "$f"; done; exit 1; }
screenshot=${FERRY_VIEWER_SCREENSHOT:-$work/viewer.png}

# start NAME ARGS...: mpirun -np 2 ferry view ARGS in the background; sets
# $url and $pid once the URL is printed (30 s at most).
start() {
  local name=$1
  shift
  mpirun --oversubscribe -np 2 "$ferry" view "$@" > "$work/$name.log" 2>&1 &
  pid=$!
  pids+=("$pid")
  for _ in $(seq 300); do
    url=$(grep -o 'http://[^ ]*/' "$work/$name.log" | head -1)
    [ -n "$url" ] && return 0
    kill -0 "$pid" 2> /dev/null || fail "$name: ferry view exited before printing its URL"
    sleep 0.1
  done
  fail "$name: no URL after 30 s"
}

# ends_within PID SECONDS: waits for it; sets $code.
ends_within() {
  local p=$1 seconds=$2
  for _ in $(seq $((seconds * 10))); do
    if ! kill -0 "$p" 2> /dev/null; then
      wait "$p"
      code=$?
      return 0
    fi
    sleep 0.1
  done
  fail "pid $p still running after ${seconds} s"
}

echo "== API and browser"
start main builtin:cornell --port 0 --size 320x240 --threads 1
case "$url" in http://127.0.0.1:*) ;; *) fail "binds $url, not 127.0.0.1 by default" ;; esac
$check "$url" api || fail "API"
$check "$url" browser "$screenshot" || fail "browser"
t0=$SECONDS
$check "$url" quit || fail "POST /quit"
ends_within "$pid" 5
[ "$code" -eq 0 ] || fail "after POST /quit, exit code $code"
grep -q "ferry view: stopped" "$work/main.log" || fail "no 'stopped' line"
echo "  POST /quit: every rank ended, exit 0, $((SECONDS - t0)) s"

echo "== a volume's transfer function"
python3 -c "
import sys
n = 32
out = bytearray()
for z in range(n):
    for y in range(n):
        for x in range(n):
            r = ((x - n / 2) ** 2 + (y - n / 2) ** 2 + (z - n / 2) ** 2) ** 0.5 / (n / 2)
            out.append(max(0, min(255, int(255 * (1 - r)))))
open(sys.argv[1], 'wb').write(out)" "$work/ball.raw"
start volume "raw:$work/ball.raw?dims=32,32,32&format=uint8" --port 0 --size 96x64 --threads 1
$check "$url" volume "${FERRY_VIEWER_VOLUME_SCREENSHOT:-$work/volume.png}" || fail "volume"
$check "$url" quit
ends_within "$pid" 5
echo "== a bricked volume's transfer function (bricks on both ranks)"
start bricks "raw:$work/ball.raw?dims=32,32,32&format=uint8" --volume-bricks 8 --port 0 --size 96x64 --threads 1
$check "$url" volume "$work/bricks.png" || fail "bricked volume"
$check "$url" quit
ends_within "$pid" 5

echo "== another field of VTK data, chosen on the page (the ranks read it again)"
python3 -c "
import sys
n = 16
ball, shell = [], []
for z in range(n):
    for y in range(n):
        for x in range(n):
            r = ((x - n / 2) ** 2 + (y - n / 2) ** 2 + (z - n / 2) ** 2) ** 0.5 / (n / 2)
            ball.append(max(0.0, 1 - r))
            shell.append(max(0.0, 1 - abs(r - 0.6) * 5))
array = lambda name, v: '<DataArray type=\"Float32\" Name=\"%s\" format=\"ascii\">%s</DataArray>' % (
    name, ' '.join('%.4f' % x for x in v))
e = '0 %d 0 %d 0 %d' % (n - 1, n - 1, n - 1)
open(sys.argv[1], 'w').write('<?xml version=\"1.0\"?><VTKFile type=\"ImageData\" version=\"0.1\">'
    '<ImageData WholeExtent=\"%s\" Origin=\"0 0 0\" Spacing=\"1 1 1\"><Piece Extent=\"%s\">'
    '<PointData Scalars=\"ball\">%s%s</PointData></Piece></ImageData></VTKFile>'
    % (e, e, array('ball', ball), array('shell', shell)))" "$work/two.vti"
start field "$work/two.vti" --port 0 --size 96x64 --threads 1
$check "$url" field shell || fail "field"
$check "$url" quit
ends_within "$pid" 5
grep -q "reading .*two.vti again for its field 'shell'" "$work/field.log" || fail "no reading-again line"

echo "== AOVs shown instead of the colour"
start display builtin:cornell --aov albedo,normal --port 0 --size 64x48 --threads 1
$check "$url" display || fail "display"
$check "$url" quit
ends_within "$pid" 5

echo "== a long session"
start memory builtin:cornell --port 0 --size 16x16 --max-depth 2 --threads 1
$check "$url" memory 1000 || fail "memory"
$check "$url" quit
ends_within "$pid" 5

echo "== Ctrl-C"
start interrupt builtin:cornell --port 0 --size 64x48 --threads 1
sleep 1
kill -INT "$pid"
ends_within "$pid" 5
echo "  SIGINT to mpirun: every rank ended within 5 s (exit $code)"

echo "== a rank fails"
export FERRY_FAIL_RANK=1 FERRY_FAIL_AT=exchange
start failing builtin:cornell --port 0 --size 64x48 --threads 1
unset FERRY_FAIL_RANK FERRY_FAIL_AT
ends_within "$pid" 15
[ "$code" -ne 0 ] || fail "a failed rank, yet exit 0"
grep -q "error on rank 1: injected failure at exchange" "$work/failing.log" || fail "the rank's message is missing"
echo "  rank 1 failed: the viewer ended, exit $code, with the rank's message"

echo "== a port in use"
start holder builtin:cornell --port 0 --size 32x32 --threads 1
port=${url##*:}
port=${port%/}
mpirun --oversubscribe -np 2 "$ferry" view builtin:cornell --port "$port" --size 32x32 > "$work/second.log" 2>&1
code=$?
[ "$code" -ne 0 ] || fail "a second viewer on port $port exited 0"
grep -q "cannot listen on 127.0.0.1:$port" "$work/second.log" || fail "no clear message for a port in use"
echo "  port $port in use: $(grep -m1 'error' "$work/second.log")"
$check "$url" quit
ends_within "$pid" 5
echo "viewer_test: all passed"
