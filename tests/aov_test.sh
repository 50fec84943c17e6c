#!/usr/bin/env bash
# AOVs (--aov): the Cornell box with albedo, normal and depth on 1 and 3
# ranks gives EXR files with the channels Albedo.R/G/B, Ns.X/Y/Z and Z, the
# same bit for bit at both rank counts, and the same colour as without
# --aov; a .pfm output gets the AOVs as files beside it (out.albedo.pfm ...),
# the same on both rank counts; the stats name them; an unknown name and a
# .png output are refused with a message.
set -uo pipefail
ferry=$1
source_dir=$2
source "$source_dir/tests/tools/multirank_test_env.sh"
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
mpirun_bound() { local n=$1; shift; mpirun --allow-run-as-root --oversubscribe --bind-to none -np "$n" "$@"; }

scene=builtin:cornell
args="--size 40x30 --spp 4 --max-depth 3 -q --threads 1"
aovs="--aov albedo,normal,depth"
mpirun_bound 1 "$ferry" render $scene $args $aovs -o "$work/one.exr" || fail "1 rank, EXR"
mpirun_bound 3 "$ferry" render $scene $args $aovs -o "$work/three.exr" --stats "$work/three.json" \
  || fail "3 ranks, EXR"
/usr/bin/python3 -c 'import json, sys; assert json.load(open(sys.argv[1]))["settings"]["aov"] == "albedo,normal,depth"' \
  "$work/three.json" || fail "the stats do not name the AOVs"
"$ferry" render $scene $args -o "$work/plain.exr" || fail "no AOVs, EXR"
/usr/bin/python3 - "$work/one.exr" "$work/three.exr" "$work/plain.exr" << 'PY' || fail "the EXR channels"
import sys
import numpy as np
import OpenImageIO as oiio
def read(path):
    image = oiio.ImageInput.open(path)
    assert image, oiio.geterror()
    spec = image.spec()
    pixels = image.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT)
    image.close()
    return list(spec.channelnames), pixels
one_names, one = read(sys.argv[1])
three_names, three = read(sys.argv[2])
plain_names, plain = read(sys.argv[3])
want = ["Albedo.R", "Albedo.G", "Albedo.B", "Ns.X", "Ns.Y", "Ns.Z", "Z"]
for name in ["R", "G", "B"] + want:
    assert name in one_names, f"no channel {name} in {one_names}"
assert one_names == three_names, (one_names, three_names)
assert np.array_equal(one, three), "1 and 3 ranks differ"
col = lambda names, px, c: px[:, :, names.index(c)]
for c in "RGB":
    assert np.array_equal(col(one_names, one, c), col(plain_names, plain, c)), f"{c} changed by --aov"
albedo = np.stack([col(one_names, one, f"Albedo.{c}") for c in "RGB"], -1)
normal = np.stack([col(one_names, one, f"Ns.{c}") for c in "XYZ"], -1)
depth = col(one_names, one, "Z")
assert albedo.min() >= 0 and albedo.max() <= 1, (albedo.min(), albedo.max())
assert albedo.mean() > 0.1, albedo.mean()
lengths = np.linalg.norm(normal, axis=-1)
assert np.median(lengths) > 0.99, np.median(lengths)
# A ray that misses (the sides of a 4:3 view of the square box) adds 0 to every AOV.
hit = depth > 0
assert hit.mean() > 0.5, hit.mean()
assert not albedo[~hit].any() and not normal[~hit].any(), "a pixel with no hit has AOVs"
assert (lengths[hit] > 0).all(), "a pixel with hits has no normal"
print(f"  channels {sorted(set(one_names))}; albedo mean {albedo.mean():.3f}, "
      f"depth {depth[hit].min():.0f}..{depth.max():.0f}, {hit.mean():.0%} of the pixels hit")
PY
echo "  EXR: 1 rank = 3 ranks, bit for bit; the colour as without --aov"

mpirun_bound 1 "$ferry" render $scene $args $aovs -o "$work/one.pfm" || fail "1 rank, PFM"
mpirun_bound 3 "$ferry" render $scene $args $aovs -o "$work/three.pfm" || fail "3 ranks, PFM"
"$ferry" render $scene $args -o "$work/plain.pfm" || fail "no AOVs, PFM"
cmp -s "$work/one.pfm" "$work/plain.pfm" || fail "the PFM colour changed by --aov"
for a in albedo normal depth; do
  [ -s "$work/one.$a.pfm" ] || fail "no $work/one.$a.pfm"
  cmp -s "$work/one.$a.pfm" "$work/three.$a.pfm" || fail "$a.pfm: 1 and 3 ranks differ"
done
head -c 2 "$work/one.depth.pfm" | grep -q Pf || fail "depth.pfm is not a grey PFM"
echo "  PFM: out.albedo.pfm, out.normal.pfm, out.depth.pfm, 1 rank = 3 ranks"

if "$ferry" render $scene $args --aov albedo,colour -o "$work/bad.exr" 2> "$work/stderr"; then
  fail "an unknown AOV was accepted"
fi
grep -q "unknown AOV 'colour'" "$work/stderr" || fail "no message naming the AOV: $(head -c 300 "$work/stderr")"
if "$ferry" render $scene $args $aovs -o "$work/bad.png" 2> "$work/stderr"; then
  fail "--aov with a PNG output was accepted"
fi
grep -q "PNG holds no AOVs" "$work/stderr" || fail "no message about the PNG: $(head -c 300 "$work/stderr")"
echo "  refused: an unknown AOV name, and --aov with a .png output"

if [ $failures -ne 0 ]; then
  echo "aov_test: $failures failure(s)"
  exit 1
fi
echo "aov_test: passed"
