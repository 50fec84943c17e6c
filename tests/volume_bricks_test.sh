#!/usr/bin/env bash
# Volumes in bricks across ranks (docs/volumes.md, "Bricks across ranks"): a
# raw volume split into bricks renders the same image bit for bit on one
# rank, on 3 and 4 ranks partitioned on the fly, from a part directory, and
# loaded natively distributed (each rank reading only its own brick files,
# cut by scripts/cut_bricks.py); a missing or wrong-sized brick on one rank
# ends every rank within seconds with a message naming the rank and the file.
set -uo pipefail
ferry=$1
source_dir=$2
source "$source_dir/tests/tools/multirank_test_env.sh"
python=/usr/bin/python3  # Debian's, with numpy
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

# A float32 volume of 36x30x26 samples: two blobs.
$python - "$work/vol.raw" << 'PY'
import sys, numpy as np
z, y, x = np.mgrid[0:26, 0:30, 0:36].astype(np.float32)
v = np.exp(-((x - 12) ** 2 + (y - 14) ** 2 + (z - 12) ** 2) / 40) \
  + 0.7 * np.exp(-((x - 26) ** 2 + (y - 18) ** 2 + (z - 15) ** 2) / 25)
(v * 3 - 0.5).astype('<f4').tofile(sys.argv[1])
PY
raw="raw:$work/vol.raw?dims=36,30,26&format=float32&spacing=0.1,0.1,0.1&opacity=40"
args="--size 48x40 --spp 2 --max-depth 4 --seed 5 -q --threads 1"

"$ferry" render "$raw" $args --volume-bricks 8 -o "$work/one.pfm" || fail "one rank"
"$ferry" render "$raw" $args -o "$work/whole.pfm" || fail "one rank, whole"
cmp -s "$work/one.pfm" "$work/whole.pfm" && fail "bricks and the whole medium gave the very same bytes"
for n in 3 4; do
  mpirun_n $n "$ferry" render "$raw" $args --volume-bricks 8 -o "$work/on$n.pfm" || fail "$n ranks"
  cmp -s "$work/one.pfm" "$work/on$n.pfm" || fail "$n ranks on the fly: not the 1-rank image"
done
"$ferry" partition "$raw" --volume-bricks 8 --ranks 3 -o "$work/parts" -q || fail "partition"
mpirun_n 3 "$ferry" render "$work/parts" $args -o "$work/parts.pfm" --stats "$work/parts.json" \
  || fail "part directory"
cmp -s "$work/one.pfm" "$work/parts.pfm" || fail "part directory: not the 1-rank image"
echo "  bricks: 1 rank = 3 and 4 ranks on the fly = a 3-rank part directory"

$python "$source_dir/scripts/cut_bricks.py" "$work/vol.raw" 36,30,26 float32 8 "$work/bricks" > /dev/null \
  || fail "cut_bricks.py"
$python - "$work/bricks/volume.json" << 'PY'
import json, sys
m = json.load(open(sys.argv[1]))
m["spacing"] = [0.1, 0.1, 0.1]
m["opacity"] = 40
json.dump(m, open(sys.argv[1], "w"))
PY
for n in 1 3; do
  mpirun_n $n "$ferry" render "bricks:$work/bricks/volume.json" $args -o "$work/native$n.pfm" \
    --stats "$work/native$n.json" || fail "natively distributed on $n ranks"
  cmp -s "$work/one.pfm" "$work/native$n.pfm" || fail "natively distributed on $n ranks: not the image of the assembled volume"
done
for stats in parts native3; do
  $python - "$work/$stats.json" << 'PY' || fail "$stats: a rank holds more than 1.3 x a third"
import json, sys
s = json.load(open(sys.argv[1]))["memory"]
per = [r["estimated_bytes"] for r in s["per_rank"]]
assert max(per) <= 1.3 * sum(per) / 3, per
PY
done
echo "  natively distributed bricks: the same image on 1 and 3 ranks, each rank a third"

# Without the flag: a grid of 2^24 samples or more is bricked on any rank
# count (auto, 32^3 bricks for 256^3), the same image on 1 and 3 ranks, no
# rank above 1.3 x its share; --volume-bricks 0 keeps it whole.
$python - "$work/big.raw" << 'PY'
import sys, numpy as np
n = 256
c = (np.arange(n, dtype=np.float32) - n / 2) / n
z, y, x = np.meshgrid(c, c, c, indexing="ij")
(255 * np.exp(-(x * x + y * y + z * z) / 0.02)).astype(np.uint8).tofile(sys.argv[1])
PY
big="raw:$work/big.raw?dims=256,256,256&format=uint8&opacity=20"
"$ferry" render "$big" $args -o "$work/big1.pfm" --stats "$work/big1.json" || fail "auto bricks, 1 rank"
mpirun_n 3 "$ferry" render "$big" $args -o "$work/big3.pfm" --stats "$work/big3.json" || fail "auto bricks, 3 ranks"
cmp -s "$work/big1.pfm" "$work/big3.pfm" || fail "auto bricks: the 3-rank image is not the 1-rank image"
"$ferry" render "$big" $args --volume-bricks 0 -o "$work/big0.pfm" --stats "$work/big0.json" || fail "--volume-bricks 0"
$python - "$work/big1.json" "$work/big3.json" "$work/big0.json" << 'PY' || fail "auto bricks: not bricked, or a rank above 1.3 x a third"
import json, sys
one, three, whole = (json.load(open(p)) for p in sys.argv[1:])
assert one["scene"]["volume_bricks"] > 8, one["scene"]["volume_bricks"]
assert whole["scene"]["volume_bricks"] == 0, whole["scene"]["volume_bricks"]
per = [r["estimated_bytes"] for r in three["memory"]["per_rank"]]
assert max(per) <= 1.3 * sum(per) / 3, per
PY
echo "  auto: a 256^3 grid in $($python -c "import json,sys; print(json.load(open(sys.argv[1]))['scene']['volume_bricks'])" "$work/big1.json") bricks, the same image on 1 and 3 ranks"

# An unstructured volume (builtin:tets, clusters of cells cut over ranks):
# the 1-rank image on 3 ranks on the fly and from a 3-rank part directory.
tets="builtin:tets?count=100000"
"$ferry" render "$tets" $args -o "$work/tets1.pfm" || fail "tets, 1 rank"
mpirun_n 3 "$ferry" render "$tets" $args -o "$work/tets3.pfm" --stats "$work/tets3.json" || fail "tets, 3 ranks"
cmp -s "$work/tets1.pfm" "$work/tets3.pfm" || fail "tets on 3 ranks: not the 1-rank image"
"$ferry" partition "$tets" --ranks 3 -o "$work/tetparts" -q || fail "tets, partition"
mpirun_n 3 "$ferry" render "$work/tetparts" $args -o "$work/tetparts.pfm" || fail "tets, part directory"
cmp -s "$work/tets1.pfm" "$work/tetparts.pfm" || fail "tets from a part directory: not the 1-rank image"
$python - "$work/tets3.json" << 'PY' || fail "tets: a rank holds more than 1.3 x a third"
import json, sys
per = [r["estimated_bytes"] for r in json.load(open(sys.argv[1]))["memory"]["per_rank"]]
assert max(per) <= 1.3 * sum(per) / 3, per
PY
echo "  unstructured (100 000 tetrahedra): 1 rank = 3 ranks on the fly = a 3-rank part directory"

# The bench runs (a small volume): its own checks are the same images and
# no rank above 1.3 x its share.
FERRY=$(realpath "$ferry") SIZE=40 BRICK=16 RANKS=3 IMAGE=40x30 FRAMES=1 \
  bash "$source_dir/bench/volume_bricks.sh" > "$work/bench.log" 2>&1 \
  || { cat "$work/bench.log"; fail "bench/volume_bricks.sh"; }
echo "  bench/volume_bricks.sh at 40^3 on 3 ranks: $(grep -c '= 1-rank image' "$work/bench.log") images equal"

# Failures: every rank ends within seconds, the message names rank and file.
run_failing() {
  local name=$1
  shift
  local start=$SECONDS
  timeout 60 "$@" > "$work/stdout" 2> "$work/stderr"
  local code=$?
  if [ $code -eq 124 ]; then fail "$name: hung"; return; fi
  [ $code -ne 0 ] || fail "$name: exited 0"
  echo "  $name: exit $code after $((SECONDS - start)) s: $(head -c 300 "$work/stderr" | tr '\n' ' ')"
}
cp -r "$work/bricks" "$work/missing"
rm "$work/missing/brick_4.raw"
run_failing "a missing brick" mpirun --oversubscribe -np 3 "$ferry" render "bricks:$work/missing/volume.json" $args -o "$work/x.pfm"
grep -q "rank 1" "$work/stderr" && grep -q "brick_4.raw" "$work/stderr" || fail "the message names neither rank 1 nor brick_4.raw"
cp -r "$work/bricks" "$work/short"
head -c 100 "$work/bricks/brick_2.raw" > "$work/short/brick_2.raw"
run_failing "a brick of the wrong size" mpirun --oversubscribe -np 3 "$ferry" render "bricks:$work/short/volume.json" $args -o "$work/x.pfm"
grep -q "brick_2.raw" "$work/stderr" && grep -q "100 bytes" "$work/stderr" || fail "the message does not say the brick's size"
cp -r "$work/bricks" "$work/nan"
$python -c "import numpy as np, sys; a = np.fromfile(sys.argv[1], '<f4'); a[7] = np.nan; a.tofile(sys.argv[1])" \
  "$work/nan/brick_5.raw"
run_failing "a NaN in a brick" mpirun --oversubscribe -np 3 "$ferry" render "bricks:$work/nan/volume.json" $args -o "$work/x.pfm"
grep -q "brick_5.raw.*sample 7 is nan" "$work/stderr" || fail "the message does not name the brick and the sample"
[ -e "$work/x.pfm" ] && fail "a failed render wrote an image"

if [ $failures -ne 0 ]; then
  echo "volume_bricks_test: $failures failure(s)"
  exit 1
fi
echo "volume_bricks_test: passed"
