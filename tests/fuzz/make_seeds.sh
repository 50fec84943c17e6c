#!/usr/bin/env bash
# Regenerates the seed corpora of the fuzz targets that have no corpus of
# their own (tests/fuzz/corpus/<kind>) from the malformed-input corpora in
# tests/corpus and from files Ferry writes itself (part files, a manifest, a
# checkpoint of a tiny render). pbrt and ply keep their minimised corpora.
#   bash tests/fuzz/make_seeds.sh build/ferry
set -euo pipefail
ferry=$(realpath "${1:-build/ferry}")
cd "$(dirname "$0")/../.."
corpus=tests/fuzz/corpus
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

fresh() { rm -rf "${corpus:?}/$1"; mkdir -p "$corpus/$1"; }
fresh obj && cp tests/corpus/obj/*.obj "$corpus/obj/"
# Valid ones too (the corpus's good files name material libraries, which a
# fuzzed input has not got beside it).
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n' > "$corpus/obj/valid-triangle.obj"
printf 'o quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\ng top\ns 1\nf 1/1/1 2/2/1 3/3/1 4/4/1\n' \
  > "$corpus/obj/valid-quad.obj"
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 0 0 1\nf 1 2 4\nf 2 3 4\n' > "$corpus/obj/valid-relative.obj"
fresh gltf && cp tests/corpus/gltf/*.gltf "$corpus/gltf/"
fresh glb && cp tests/corpus/gltf/*.glb "$corpus/glb/"
fresh bsdf && cp tests/corpus/bsdf/*.bsdf "$corpus/bsdf/"

"$ferry" partition builtin:cornell --ranks 2 --partitioner best -o "$work/parts" -q
fresh part
cp "$work"/parts/part-0000.fpart "$corpus/part/cornell-0.fpart"
cp "$work"/parts/part-0001.fpart "$corpus/part/cornell-1.fpart"
cp "$work"/parts/shared.fpart "$corpus/part/cornell-shared.fpart"
for f in tests/corpus/parts-v1/*.fpart; do cp "$f" "$corpus/part/v1-$(basename "$f")"; done
fresh manifest
cp "$work/parts/manifest.json" "$corpus/manifest/cornell.json"
cp tests/corpus/parts-v1/manifest.json "$corpus/manifest/v1.json"
printf '{}' > "$corpus/manifest/empty-object.json"

fresh checkpoint
"$ferry" render builtin:cornell --size 4x3 --spp 1 --frames 2 -q -o "$work/c.pfm" \
  --checkpoint "$corpus/checkpoint/cornell-4x3.ckpt"
"$ferry" render builtin:cornell --size 1x1 --spp 1 -q -o "$work/d.pfm" \
  --checkpoint "$corpus/checkpoint/cornell-1x1.ckpt"
printf 'FERRYCKP' > "$corpus/checkpoint/magic-only.ckpt"

fresh camera
printf '{"from":[0,1,5],"at":[0,1,0]}' > "$corpus/camera/minimal.json"
printf '{"from":[1,2,3],"at":[0,0,0],"up":[0,0,1],"fov":60}' > "$corpus/camera/full.json"
printf '{"from":[0,1,5],"at":[0,1,5]}' > "$corpus/camera/degenerate.json"
printf '[1,2,3]' > "$corpus/camera/array.json"
fresh settings
printf '{"width":32,"height":24}' > "$corpus/settings/size.json"
printf '{"spp":4,"max_depth":8,"exposure":-1.5}' > "$corpus/settings/samples.json"
printf '{"view":"top"}' > "$corpus/settings/view.json"
printf '{"view":"nowhere","width":-1}' > "$corpus/settings/bad.json"
printf '{"volume_opacity":4,"color_map":"viridis"}' > "$corpus/settings/volume.json"

fresh raw
python3 -c "import sys; sys.stdout.buffer.write(b'dims=2,2,2&format=uint8\\n' + bytes(range(0, 256, 32)))" \
  > "$corpus/raw/ball-uint8.raw"
python3 -c "import struct, sys; sys.stdout.buffer.write(b'dims=2,1,1&format=float32&spacing=0.5,1,1&origin=1,2,3&opacity=5\\n' + struct.pack('<2f', 0.5, 2))" \
  > "$corpus/raw/float32.raw"
python3 -c "import sys; sys.stdout.buffer.write(b'dims=2,1,1&format=uint16\\n' + bytes([0, 0, 255, 255]))" \
  > "$corpus/raw/uint16.raw"
fresh bricks
printf '{"dims":[2,2,2],"format":"uint8","bricks":[{"file":"b.raw","lo":[0,0,0],"hi":[2,2,2]}]}' \
  > "$corpus/bricks/one-brick.json"
printf '{"dims":[4,2,2],"format":"uint8","bricks":[{"file":"b.raw","lo":[0,0,0],"hi":[2,2,2],"rank":0},{"file":"c.raw","lo":[2,0,0],"hi":[4,2,2]}]}' \
  > "$corpus/bricks/two-bricks-one-missing.json"
printf '{"dims":[2,2,2],"format":"float32","range":[0,1],"spacing":[1,2,3],"origin":[-1,0,1],"opacity":3,"bricks":[{"file":"b.raw","lo":[0,0,0],"hi":[1,2,2]}]}' \
  > "$corpus/bricks/uncovered.json"
printf '{"dims":[2,2,2],"format":"uint8","bricks":[{"file":"b.raw","lo":[0,0,0],"hi":[2,2,2]},{"file":"b.raw","lo":[1,1,1],"hi":[2,2,2]}]}' \
  > "$corpus/bricks/overlapping.json"
python3 -c "import sys; sys.stdout.buffer.write(bytes(range(0, 27 * 9, 9)))" > "$work/vol.raw"
"$ferry" partition "raw:$work/vol.raw?dims=3,3,3&format=uint8" --volume-bricks 2 --ranks 2 -o "$work/bricked" -q
cp "$work"/bricked/part-0000.fpart "$corpus/part/bricks-0.fpart"
# A combined texture (format 11): a mix of constants by an fbm, scaled by wrinkled.
cat > "$work/combined.pbrt" << 'PBRT'
WorldBegin
Texture "n" "float" "fbm" "integer octaves" 2
Texture "w" "float" "wrinkled" "integer octaves" 2
Texture "m" "spectrum" "mix" "texture amount" "n" "rgb tex1" [1 0 0] "rgb tex2" [0 0 1]
Texture "s" "spectrum" "scale" "texture tex1" "m" "texture tex2" "w"
Material "matte" "texture Kd" "s"
Shape "trianglemesh" "point3 P" [0 0 0 1 0 0 0 1 0] "integer indices" [0 1 2]
WorldEnd
PBRT
"$ferry" partition "$work/combined.pbrt" --ranks 1 -o "$work/combined" -q
cp "$work"/combined/part-0000.fpart "$corpus/part/combined-texture-0.fpart"
"$ferry" partition tests/corpus/pbrt/cutouts_v4.pbrt --ranks 1 -o "$work/cutouts" -q
cp "$work"/cutouts/part-0000.fpart "$corpus/part/cutouts-0.fpart"
fresh tf && cp tests/corpus/volumes/*.tf.json "$corpus/tf/"
fresh vdb && cp tests/corpus/volumes/*.vdb "$corpus/vdb/"
# Grid descriptions (tests/fuzz/fuzz_inputs.cpp, vdbgrids): a count byte, then
# per grid name, type, scale, rotation, translation, background, voxels.
fresh vdbgrids
python3 - "$corpus/vdbgrids" << 'PY'
import os, struct, sys
def grid(name, typ, scale=(16, 16, 16), rot=0, trans=(0, 0, 0), bg=0.0, voxels=()):
    b = bytes([name, typ, *[s & 0xFF for s in scale], rot]) + struct.pack("<hhhf", *trans, bg)
    return b + bytes([len(voxels)]) + b"".join(struct.pack("<hhhf", *v) for v in voxels)
cube = [(x, y, z, 0.25 * (1 + x + y + z)) for x in range(2) for y in range(2) for z in range(2)]
seeds = {
    "density-cube": bytes([0]) + grid(0, 0, voxels=cube),
    "density-and-temperature": bytes([1]) + grid(0, 0, scale=(8, 16, 32), trans=(-8, 0, 16), voxels=cube)
    + grid(1, 0, voxels=[(0, 0, 0, 1500.0), (1, 1, 1, 800.0)]),
    "rotated": bytes([0]) + grid(0, 0, rot=1, voxels=cube),
    "double-only": bytes([0]) + grid(0, 1, voxels=cube),
    "negative-value": bytes([0]) + grid(0, 0, voxels=[(0, 0, 0, 1.0), (1, 0, 0, -1.0)]),
    "far-apart": bytes([0]) + grid(0, 0, voxels=[(-30000, 0, 0, 1.0), (30000, 30000, 30000, 1.0)]),
    "mirrored": bytes([0]) + grid(0, 0, scale=(-16, 16, 16), voxels=cube),
    "first-float-grid-unnamed": bytes([0]) + grid(3, 0, voxels=cube),
}
for name, b in seeds.items():
    open(os.path.join(sys.argv[1], name), "wb").write(b)
PY
echo "seeds in $corpus: $(ls "$corpus" | tr '\n' ' ')"
