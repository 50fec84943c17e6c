#!/usr/bin/env bash
# Out-of-core partitioning (issue 17, item 1): under a --memory-budget smaller
# than the scene, the geometry goes to a spill file as it is made or read
# and is read back one mesh at a time, and the part files are byte for byte
# those of partitioning in memory: for a built-in (generated mesh by mesh)
# and for a pbrt scene of plymesh files (stored as parsed), with a mesh cut
# into pieces on the way. Bad budgets, a budget the records alone exceed
# and ray-guided out of core are clear errors that write nothing; the spill
# file never outlives the run. Peak memory is measured in a benchmark
# (bench/partition_memory.sh), not here.
set -uo pipefail
ferry=$1
source_dir=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

same_parts() {
  local a=$1 b=$2 what=$3
  for f in "$a"/*.fpart; do
    cmp -s "$f" "$b/$(basename "$f")" || fail "$what: $(basename "$f") differs"
  done
  [ "$(ls "$a"/*.fpart | wc -l)" -eq "$(ls "$b"/*.fpart | wc -l)" ] || fail "$what: file counts differ"
}

# A built-in: 76 MiB of geometry and records, 40 MiB of budget.
island="builtin:island?scale=0.5"
"$ferry" partition "$island" --ranks 3 --partitioner best -o "$work/in" -q || fail "in-memory partition"
"$ferry" partition "$island" --ranks 3 --partitioner best -o "$work/out" --memory-budget 40MiB \
  > "$work/log" || fail "out-of-core partition"
grep -q "geometry out of memory" "$work/log" || fail "the budget did not put the geometry out of memory"
same_parts "$work/in" "$work/out" "island, 3 ranks"
echo "  island: the same parts with the geometry out of memory"

# A pbrt scene of plymesh files, one big enough to be cut by best.
mkdir -p "$work/pbrt"
python3 - "$work/pbrt" <<'PY'
import sys, os
d = sys.argv[1]
def grid(path, n, x0):
    with open(path, "w") as f:
        f.write("ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\n"
                "property float z\nelement face %d\nproperty list uchar int vertex_indices\n"
                "end_header\n" % ((n + 1) * (n + 1), n * n))
        for j in range(n + 1):
            for i in range(n + 1):
                f.write("%g %g %g\n" % (x0 + i, 0.1 * ((i * 7 + j * 3) % 5), j))
        for j in range(n):
            for i in range(n):
                a = j * (n + 1) + i
                f.write("4 %d %d %d %d\n" % (a, a + 1, a + n + 2, a + n + 1))
shapes = []
for k in range(6):
    grid(os.path.join(d, "g%d.ply" % k), 60 if k == 0 else 8, 70 * k)
    shapes.append('AttributeBegin\n  Material "matte" "rgb Kd" [0.5 0.5 0.5]\n'
                  '  Shape "plymesh" "string filename" "g%d.ply"\nAttributeEnd\n' % k)
with open(os.path.join(d, "scene.pbrt"), "w") as f:
    f.write('LookAt 200 80 -150  200 0 30  0 1 0\nCamera "perspective" "float fov" 45\n'
            'WorldBegin\nLightSource "infinite" "rgb L" [1 1 1]\n' + "".join(shapes) +
            'AttributeBegin\n  Translate 0 5 0\n  Shape "plymesh" "string filename" "g1.ply"\nAttributeEnd\n'
            'WorldEnd\n')
PY
"$ferry" partition "$work/pbrt/scene.pbrt" --ranks 3 --partitioner best -o "$work/pin" -q \
  || fail "pbrt in memory"
"$ferry" partition "$work/pbrt/scene.pbrt" --ranks 3 --partitioner best -o "$work/pout" \
  --memory-budget 64MiB > "$work/log" || fail "pbrt out of core"
grep -q "geometry out of memory" "$work/log" || fail "pbrt: a given budget did not store the meshes"
grep -q "meshes or shapes cut into" "$work/log" || fail "pbrt: no mesh was cut (the test wants one)"
same_parts "$work/pin" "$work/pout" "pbrt plymesh scene, 3 ranks"
echo "  pbrt plymesh scene: the same parts with the meshes stored as parsed"

# --max-proxies: best's one proxy per instance merged down to the budget,
# said in the summary and kept in the manifest's options.
"$ferry" partition "$island" --ranks 3 --partitioner best -o "$work/merged" --max-proxies 100 \
  > "$work/log" || fail "partition with --max-proxies"
grep -q "100 proxies (merged from" "$work/log" || { fail "no merge in the summary"; cat "$work/log"; }
grep -q '"max_proxies": 100' "$work/merged/manifest.json" || fail "max_proxies not in the manifest"
echo "  --max-proxies: merged and recorded"

# Errors: one message, exit non-zero, nothing written.
expect_error() {
  local pattern=$1
  shift
  if "$ferry" partition "$@" > "$work/stdout" 2> "$work/stderr"; then
    fail "exit 0 for: $*"
  fi
  grep -q -- "$pattern" "$work/stderr" || { fail "no '$pattern' for: $*"; cat "$work/stderr"; }
}
expect_error "expected a size" "$island" --ranks 2 -o "$work/bad" --memory-budget lots
expect_error "expected a size" "$island" --ranks 2 -o "$work/bad" --memory-budget 0
expect_error "more than --memory-budget" "builtin:island?scale=30" --ranks 8 -o "$work/bad" \
  --memory-budget 100MiB
expect_error "ray-guided" "$island" --ranks 2 -o "$work/bad" --partitioner ray-guided \
  --memory-budget 40MiB
expect_error "twice that" "$work/pbrt/scene.pbrt" --ranks 2 -o "$work/bad" --memory-budget 100KiB
[ ! -e "$work/bad" ] || fail "a refused partition wrote its directory"
echo "  bad budgets: clear errors, nothing written"

# The spill file is unlinked while in use: nothing named after it remains.
[ "$(find "$work" -name '.*.geometry.*' | wc -l)" -eq 0 ] || fail "a spill file was left behind"

if [ "$failures" -gt 0 ]; then
  echo "$failures failures"
  exit 1
fi
echo "partition budget: all passed"
