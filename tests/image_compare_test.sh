#!/usr/bin/env bash
# bench/image_compare, the figures of bench/fidelity, on synthetic PFM images
# whose answers are known by hand: an image equal to the reference (at its
# size, and box-averaged to the comparison size) has bias 0 and block RMSE 0;
# the reference times 1.1 has bias +0.1 in every channel and the block RMSE
# worked out below; a missing file or a size that is no integer multiple of
# the comparison size fails with exit status 1 and a message naming the file.
#
#   bash tests/image_compare_test.sh IMAGE_COMPARE SOURCE_DIR
#
# (Registered by tests/CMakeLists.txt with the image_compare target, not with
# the ferry binary like the other *_test.sh.)
set -euo pipefail
compare=$(realpath "$1")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"

# The reference, 16x16: value v = 1 in the left half and 3 in the right, in
# the channels (v, 2v, v/2), plus a +-0.25 checkerboard that cancels in any
# 2x2 square, so the comparison size's box averages must undo it. At the
# default comparison size (a quarter: 4x4) with --block 2 there are 2x2
# blocks: two of value 1, two of value 3 (times the channel factors k).
python3 - <<'EOF'
import struct

def write_pfm(path, width, height, pixel):
    with open(path, "wb") as f:
        f.write(b"PF\n%d %d\n-1.0\n" % (width, height))
        for y in reversed(range(height)):  # PFM rows run bottom to top
            for x in range(width):
                f.write(struct.pack("<3f", *pixel(x, y)))

def reference(x, y, scale=1.0):
    v = (1.0 if x < 8 else 3.0) + 0.25 * (-1) ** (x + y)
    return (scale * v, scale * 2 * v, scale * 0.5 * v)

write_pfm("ref.pfm", 16, 16, reference)
write_pfm("same.pfm", 16, 16, reference)
write_pfm("scaled.pfm", 16, 16, lambda x, y: reference(x, y, 1.1))
# Already at the comparison size: the reference's 4x4 means, checkerboard gone.
write_pfm("small.pfm", 4, 4, lambda x, y: tuple(c * (1.0 if x < 2 else 3.0) for c in (1, 2, 0.5)))
write_pfm("odd.pfm", 6, 6, lambda x, y: (1, 1, 1))
# Twice the reference in the top-left 8x8 pixels only: one block of four differs.
write_pfm("local.pfm", 16, 16, lambda x, y: reference(x, y, 2.0 if x < 8 and y < 8 else 1.0))
# A crop of the right half, as ferry render --crop 0.5,1,0,1 renders it.
write_pfm("right.pfm", 8, 16, lambda x, y: reference(x + 8, y))
EOF

# Checks the JSON against the expected bias (every channel and luminance) and RMSE.
expect() {  # JSON BIAS RMSE
  python3 - "$@" <<'EOF'
import json, sys
path, bias, rmse = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
d = json.load(open(path))
for name, ch in d["channels"].items():
    assert abs(ch["bias"] - bias) < 1e-6, f"{path}: {name} bias {ch['bias']}, expected {bias}"
assert abs(d["block_relative_rmse"] - rmse) < 1e-6, \
    f"{path}: block relative RMSE {d['block_relative_rmse']}, expected {rmse}"
assert d["size"] == [4, 4] and d["blocks"] == [2, 2], f"{path}: size {d['size']} blocks {d['blocks']}"
print(f"  {path}: bias {bias:+g} in every channel, block relative RMSE {rmse:.6f}: as expected")
EOF
}

"$compare" ref.pfm same.pfm --block 2 --json same.json --side-by-side same.png > /dev/null
expect same.json 0 0
"$compare" ref.pfm small.pfm --block 2 --json small.json > /dev/null
expect small.json 0 0
# Scaled by 1.1: every block differs by 0.1 R_b, so the RMSE is
#   0.1 sqrt(mean R_b^2) / mean R_b, with R_b = k v over k in {1, 2, 1/2}, v in {1, 3}:
#   mean R_b^2 = mean k^2 mean v^2 = (5.25 / 3) (10 / 2) = 8.75, mean R_b = (3.5 / 3) 2 = 7/3,
#   RMSE = 0.1 sqrt(8.75) / (7/3) = 0.1267731...
# (1.1 stored as a float: the bias is 0.1 to within 1e-7.)
"$compare" ref.pfm scaled.pfm --block 2 --json scaled.json > /dev/null
expect scaled.json 0.1 "$(python3 -c 'print(0.1 * 8.75 ** 0.5 / (7 / 3))')"

# Where the error is: all of it in the top-left block, the worst (the worst
# 1 % and 5 % of 4 blocks are that one block).
"$compare" ref.pfm local.pfm --block 2 --json local.json > /dev/null
python3 - <<'EOF'
import json
d = json.load(open("local.json"))
shares = d["squared_error_share_of_worst_blocks"]
assert abs(shares["1%"] - 1) < 1e-9 and abs(shares["5%"] - 1) < 1e-9, shares
w = d["worst_blocks"]
assert (w[0]["x"], w[0]["y"]) == (0, 0) and abs(w[0]["share"] - 1) < 1e-9, w[0]
assert abs(w[0]["image_luminance"] - 2 * w[0]["reference_luminance"]) < 1e-6, w[0]
assert all(b["share"] == 0 for b in w[1:]), w
print("  local.pfm: the one differing block holds all the squared error")
EOF

# The 99th-percentile pixel: of the 16 pixels at the comparison size, the
# 16th smallest (index int(0.99 * 16) = 15), the brightest: the right half's
# luminance; local.pfm doubles only the left half, so the ratio is 1, and
# scaled.pfm's is 1.1.
python3 - <<'EOF'
import json
for path, ratio in (("local.json", 1.0), ("scaled.json", 1.1)):
    p = json.load(open(path))["p99_luminance"]
    assert abs(p["ratio"] - ratio) < 1e-6, (path, p)
print("  p99 pixel luminance ratios: 1 (local.pfm), 1.1 (scaled.pfm)")
EOF

# --reference-crop compares with that part of the reference: its right half
# equals right.pfm.
"$compare" ref.pfm right.pfm --reference-crop 0.5,1,0,1 --size 2x4 --block 1 --json right.json > /dev/null
python3 - <<'EOF'
import json
d = json.load(open("right.json"))
assert d["size"] == [2, 4], d["size"]
for name, ch in d["channels"].items():
    assert abs(ch["bias"]) < 1e-6, (name, ch)
assert abs(d["block_relative_rmse"]) < 1e-6, d["block_relative_rmse"]
print("  right.pfm against the reference cropped to its right half: equal")
EOF

# --exclude leaves the blocks whose centre lies in a window out of the block
# figures: without the top-left block, local.pfm equals the reference there;
# the bias still covers the whole image (the top-left block's four pixels of
# value 1 doubled: R mean 2.25 from 2; bias 0.125). The excluded block is grey
# in the difference picture.
"$compare" ref.pfm local.pfm --block 2 --exclude 0,0.5,0,0.5 --json excluded.json \
  --side-by-side excluded.png > excluded.txt
grep -q "excluded   1 of 4 blocks" excluded.txt
python3 - <<'EOF2'
import json
d = json.load(open("excluded.json"))
assert d["excluded_blocks"] == 1 and d["exclude"] == ["0,0.5,0,0.5"], d
assert abs(d["block_relative_rmse"]) < 1e-9, d["block_relative_rmse"]
assert abs(d["channels"]["R"]["bias"] - 0.125) < 1e-6, d["channels"]["R"]
assert all((b["x"], b["y"]) != (0, 0) for b in d["worst_blocks"]), d["worst_blocks"]
print("  local.pfm with its differing block excluded: RMSE 0, bias over the whole image")
EOF2

# The side-by-side picture: three 4x4 panels and two 4-pixel gaps.
python3 - <<'EOF'
import struct
with open("same.png", "rb") as f:
    head = f.read(24)
assert head[:8] == b"\x89PNG\r\n\x1a\n", "same.png is not a PNG"
width, height = struct.unpack(">II", head[16:24])
assert (width, height) == (20, 4), f"same.png is {width}x{height}, expected 20x4"
print("  same.png: 20x4 (reference | image | difference)")
EOF

# Failures: exit status 1 and one message naming the file.
fails() {  # WHAT EXPECTED-TEXT ARGS...
  local what=$1 text=$2
  shift 2
  local status=0
  "$compare" "$@" > out.txt 2> err.txt || status=$?
  if [ "$status" -ne 1 ] || ! grep -qF -- "$text" err.txt; then
    echo "image_compare_test: $what: exit status $status (expected 1), stderr:" >&2
    cat err.txt >&2
    exit 1
  fi
  echo "  $what: exit 1, '$(head -1 err.txt)'"
}
fails "missing image" "missing.exr: no such file" ref.pfm missing.exr
fails "missing reference" "nothing.pfm: no such file" nothing.pfm ref.pfm
fails "no integer ratio" "odd.pfm: 6x6 is not an integer multiple" ref.pfm odd.pfm
fails "block does not divide" "--block 3" ref.pfm same.pfm --block 3
fails "bad reference crop" "--reference-crop" ref.pfm right.pfm --reference-crop 0.5,0.4,0,1
fails "bad exclude window" "--exclude" ref.pfm same.pfm --exclude 0,1,0
fails "everything excluded" "cover every block" ref.pfm same.pfm --exclude 0,1,0,1

"$compare" --help | grep "block relative RMSE   = sqrt" > /dev/null || {
  echo "image_compare_test: --help does not define the block relative RMSE" >&2
  exit 1
}
echo "image_compare_test: passed"
