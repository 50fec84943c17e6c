#!/usr/bin/env bash
# Instructions a path costs in Ferry and in Embree's tutorial path tracer
# (/usr/bin/pathtracer), counted by callgrind on the scenes of
# bench/pathtracer_vs_embree.sh: one frame, one thread, Ferry with
# --sampler independent (Embree's kind of random numbers). Counts repeat to
# the instruction whatever the load: they say where paths/s goes.
#
#   bash bench/instructions_per_path.sh [FERRY]        (default build/ferry)
#   SIZE=256x256 SPP=1 DEPTH=5 bash bench/instructions_per_path.sh
#   bash bench/instructions_per_path.sh /tmp/build-g/ferry
#        a build with line tables (-DCMAKE_CXX_FLAGS_RELEASE="-O3 -DNDEBUG -g":
#        the same code) also splits Ferry's own instructions by source file
#   MAX_OWN_RATIO=1.85 ...   a gate: exit 1 when Ferry's own instructions a
#        path (outside Embree) exceed this many times the tutorial's own on a
#        scene (bench_smoke_test runs it)
#
# Per path: all instructions, those in Embree (libembree3), the renderer's
# own (the rest), and the closest and shadow rays it traced. Ferry: its
# frame loop only (--toggle-collect on WavefrontRenderer::renderPixels);
# rays from --stats. Embree: one frame is half the difference between its
# --benchmark runs of 3 frames and of 1 (scene load and BVH build cancel);
# rays are its calls of rtcIntersect1 and rtcOccluded1. A shaded vertex
# costs Embree's tutorial two shadow rays (sun and sky), Ferry one.
set -euo pipefail
ferry=$(realpath "${1:-build/ferry}")
here=$(cd "$(dirname "$0")" && pwd)
shared=${SHARED_SCENES:-$here/../../shared/scenes}
SIZE=${SIZE:-256x256}
SPP=${SPP:-1}
DEPTH=${DEPTH:-5}
width=${SIZE%x*}
height=${SIZE#*x}
for tool in valgrind pathtracer; do
  command -v "$tool" > /dev/null || {
    echo "instructions_per_path.sh: $tool is missing (bash scripts/install-deps.sh installs it)" >&2
    exit 2
  }
done

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
source "$here/embree_scenes.sh"
embree_scenes "$work" "$shared"
echo "settings: ${width}x${height}, $SPP spp, max path length $DEPTH, 1 thread; Ferry $ferry"

for scene in $scenes; do
  obj="$work/$scene.obj"
  embree_view "$ferry" "$obj"
  valgrind --tool=callgrind --toggle-collect='ferry::WavefrontRenderer<*>::renderPixels*' \
    --callgrind-out-file="$work/ferry.cg" "$ferry" render "$obj" --size "$SIZE" --spp "$SPP" \
    --max-depth "$DEPTH" --threads 1 --sampler independent -q -o "$work/ferry.pfm" \
    --stats "$work/ferry.json" > "$work/ferry.log" 2>&1 ||
    { cat "$work/ferry.log" >&2; exit 1; }
  for frames in 1 3; do
    valgrind --tool=callgrind --callgrind-out-file="$work/embree$frames.cg" pathtracer -i "$obj" \
      "${embree_view_args[@]}" --size "$width" "$height" \
      --spp "$SPP" --max-path-length "$DEPTH" "${embree_light_args[@]}" --threads 1 \
      --benchmark 0 "$frames" > "$work/embree$frames.log" 2>&1 ||
      { cat "$work/embree$frames.log" >&2; exit 1; }
  done
  python3 - "$scene" "$work" "$((width * height * SPP))" <<'EOF'
import collections, json, os, re, sys

scene, work, paths = sys.argv[1], sys.argv[2], int(sys.argv[3])

def costs(path):
    """Exclusive instructions by (object, source file), and calls by callee."""
    names = {"ob": {}, "fl": {}, "fn": {}}
    table = {"ob": "ob", "cob": "ob", "fl": "fl", "fi": "fl", "fe": "fl", "cfi": "fl", "cfl": "fl",
             "fn": "fn", "cfn": "fn"}
    cost, calls = collections.Counter(), collections.Counter()
    ob = fl = callee = None
    skip = False
    for line in open(path):
        m = re.match(r"(c?ob|c?fl|c?fi|fe|c?fn)=\((\d+)\)(?: (.*))?", line)
        if m:
            kind, ident, name = m.groups()
            names[table[kind]].setdefault(ident, name)
            value = names[table[kind]][ident]
            if kind == "ob": ob = value
            elif kind in ("fl", "fi", "fe"): fl = value
            elif kind == "cfn": callee = value
            continue
        m = re.match(r"calls=(\d+)", line)
        if m:
            calls[callee] += int(m.group(1))
            skip = True  # the next cost line is the call's inclusive cost
            continue
        m = re.match(r"[-+*]?\d*\s+(\d+)", line)
        if m and line[0] in "0123456789+-*":
            if not skip: cost[(ob, fl)] += int(m.group(1))
            skip = False
    return cost, calls

def split(cost):
    embree = sum(v for (ob, _), v in cost.items() if ob and "libembree3" in ob)
    return sum(cost.values()), embree

ferry_cost, _ = costs(f"{work}/ferry.cg")
ferry_all, ferry_embree = split(ferry_cost)
frames = json.load(open(f"{work}/ferry.json"))["render"]["frames"]
traces = frames[0]["traces"]
one, one_calls = costs(f"{work}/embree1.cg")
three, three_calls = costs(f"{work}/embree3.cg")
e1, e3 = split(one), split(three)
embree_all, embree_embree = (e3[0] - e1[0]) / 2, (e3[1] - e1[1]) / 2
def per_frame(name):
    return (three_calls[name] - one_calls[name]) / 2

rows = [("Ferry", ferry_all, ferry_embree, traces["closest"], traces["occlusion"]),
        ("Embree's tutorial", embree_all, embree_embree, per_frame("rtcIntersect1"), per_frame("rtcOccluded1"))]
for name, total, embree, closest, shadow in rows:
    print(f"{scene:8} {name:18} {total / paths:7.0f} instructions/path: Embree {embree / paths:6.0f} "
          f"({100 * embree / total:4.1f} %), own {(total - embree) / paths:6.0f}; "
          f"rays/path: {closest / paths:.2f} closest, {shadow / paths:.2f} shadow")
ratio = (ferry_all - ferry_embree) / (embree_all - embree_embree)
print(f"{scene:8} Ferry / tutorial: all {ferry_all / embree_all:.3f}, own {ratio:.3f}, "
      f"in Embree {ferry_embree / embree_embree:.3f}")
by_file = collections.Counter()
for (ob, fl), v in ferry_cost.items():
    if ob and "libembree3" in ob: continue
    by_file[fl if fl and fl != "???" else f"(no line table: {os.path.basename(ob or '?')})"] += v
if not any(f.startswith("/") for f in by_file):
    print(f"{scene:8} Ferry's own by source file: needs a build with line tables (-g)")
else:
    top = by_file.most_common(12)
    print(f"{scene:8} Ferry's own by source file (instructions/path): "
          + ", ".join(f"{re.sub(r'^.*/(src|include)/', '', f)} {v / paths:.0f}" for f, v in top))
gate = os.environ.get("MAX_OWN_RATIO")
if gate and ratio > float(gate):
    sys.exit(f"FAIL: {scene}: Ferry's own instructions a path are {ratio:.3f}x the tutorial's "
             f"(MAX_OWN_RATIO={gate})")
EOF
done
