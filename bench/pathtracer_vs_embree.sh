#!/usr/bin/env bash
# Ferry against Embree's own tutorial path tracer (/usr/bin/pathtracer from
# Debian's embree-tools), same scenes, camera, lights, image size, samples and
# maximum path length, both on all cores, in one run. Prints paths/s and rays/s
# of each and the ratio Ferry/Embree (> 1: Ferry is faster).
#
#   bash bench/pathtracer_vs_embree.sh [FERRY]          (default build/ferry)
#   SIZE=512x512 SPP=2 DEPTH=5 FRAMES=8 WARMUP=2 ROUNDS=3 bash bench/pathtracer_vs_embree.sh
#   THREADS=1 ...        both renderers on one thread (default 0: all cores)
#   RETRACE="remote all" ...   Ferry's --retrace modes to run, each against the
#                        same Embree runs (default: remote, Ferry's default)
#   BASELINE=old/ferry ...     also run another Ferry build (without --retrace,
#                        which older builds lack) in the same rounds: before/after
#                        figures under the same load
#   FERRY_ARGS="--instancing always" ...  more arguments for Ferry (this build)
#   EMBREE_INSTANCING=geometry ...  Embree's --instancing (default: its own
#                        default, none: the whole OBJ flattened into one BVH;
#                        geometry: each mesh its own instanced scene, the
#                        structure of Ferry's --instancing always)
#
# Scenes:
#   cornell  /usr/share/doc/embree3/models/cornell_box.obj, turned 180 degrees
#            about y (x, z -> -x, -z) so that Ferry's default OBJ camera (on +z,
#            looking -z, framing the bounds) looks into the open side of the box.
#            The file has no emitter (its light quad is commented out), so both
#            renderers get Ferry's default OBJ lights: a sun from
#            normalize(0.4, 1, 0.6) with irradiance 3 and a constant sky of 0.5.
#   bunny    ../shared/scenes/stanford-bunny/bun_zipper.ply (69,451 triangles)
#            converted to OBJ by bench/ply_to_obj.py, same camera rule and lights.
# Embree gets the same camera (--vp/--vi/--vu/--fov 45 --righthanded) and the
# lights as --directionallight (direction of travel) and --ambientlight.
#
# Ferry's rays/path counts its re-traces (none on one rank with the default
# --retrace remote; one per shaded hit with --retrace all, the paper's way).
#
# Timing: frames after WARMUP, excluding scene load and BVH build for both
# (Embree: its --benchmark mode; Ferry: per-frame seconds from --stats). Both
# statistics are Embree's own: mean frames/s over the fastest 75 % of frames
# (its FilteredStatistics(0.5, 0)). ROUNDS alternate Ferry and Embree runs so
# a busy machine slows both alike; the figures are medians over rounds.
#
# What differs (so compare paths/s, and read rays/s with care): Embree samples
# every light at every vertex (2 shadow rays with sun + sky), Ferry picks one
# (1 shadow ray) and, with --retrace all only, re-traces each hit it shades
# (Ferry's compact paths carry no hit record); Embree ends a path when its throughput falls below 0.01,
# Ferry plays Russian roulette from the third bounce. The walls are white
# (Kd 1), so neither ends a path early there.
set -euo pipefail
ferry=$(realpath "${1:-build/ferry}")
here=$(cd "$(dirname "$0")" && pwd)
shared=${SHARED_SCENES:-$here/../../shared/scenes}
SIZE=${SIZE:-512x512}
SPP=${SPP:-2}
DEPTH=${DEPTH:-5}
FRAMES=${FRAMES:-8}
WARMUP=${WARMUP:-2}
ROUNDS=${ROUNDS:-3}
THREADS=${THREADS:-0}
RETRACE=${RETRACE:-remote}
BASELINE=${BASELINE:-}
FERRY_ARGS=${FERRY_ARGS:-}
EMBREE_INSTANCING=${EMBREE_INSTANCING:-}
modes=$RETRACE
if [ -n "$BASELINE" ]; then BASELINE=$(realpath "$BASELINE"); modes="baseline $RETRACE"; fi
width=${SIZE%x*}
height=${SIZE#*x}

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp /usr/share/doc/embree3/models/cornell_box.mtl "$work/"
awk '$1 == "v" { printf "v %s %s %s\n", -$2, $3, -$4; next } { print }' \
  /usr/share/doc/embree3/models/cornell_box.obj > "$work/cornell.obj"
python3 "$here/ply_to_obj.py" "$shared/stanford-bunny/bun_zipper.ply" "$work/bunny.obj" 2> /dev/null

echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)," \
  "$(free -g | awk '/Mem:/ {print $2}') GiB; load before: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "settings: ${width}x${height}, $SPP spp, max path length $DEPTH, $FRAMES frames after $WARMUP warm-up, $ROUNDS rounds," \
  "threads $THREADS (0: all), Ferry --retrace $RETRACE"
thread_args=()
if [ "$THREADS" -gt 0 ]; then thread_args=(--threads "$THREADS"); fi
read -r -a ferry_extra <<< "$FERRY_ARGS"
embree_extra=()
if [ -n "$EMBREE_INSTANCING" ]; then embree_extra=(--instancing "$EMBREE_INSTANCING"); fi
echo "extra: Ferry ${FERRY_ARGS:-(none)}; Embree ${embree_extra[*]:-(none)}"

# Embree's filter on frames/s: drop the slowest quarter, average the rest.
filtered_mean='
def filtered_mean(values):
    v = sorted(values)
    return sum(v[len(v) // 4:]) / len(v[len(v) // 4:])
'

for scene in cornell bunny; do
  obj="$work/$scene.obj"
  # Ferry's default OBJ view (src/io/obj/obj_loader.cpp): at the bounds centre, from +z, fovY 45.
  read -r vp vi <<< "$("$ferry" info "$obj" --json | python3 -c '
import json, math, sys
lo, hi = json.load(sys.stdin)["bounds"]
c = [(a + b) / 2 for a, b in zip(lo, hi)]
d = 0.5 * math.dist(lo, hi) / math.sin(math.radians(22.5))
print(",".join(f"{x:.9g}" for x in (c[0], c[1], c[2] + d)), ",".join(f"{x:.9g}" for x in c))')"
  embree_args=(-i "$obj" --vp ${vp//,/ } --vi ${vi//,/ } --vu 0 1 0 --fov 45 --righthanded
               --size "$width" "$height" --spp "$SPP" --max-path-length "$DEPTH"
               --directionallight -0.4 -1 -0.6 3 3 3 --ambientlight 0.5 0.5 0.5 "${thread_args[@]}"
               "${embree_extra[@]}")
  for retrace in $modes; do : > "$work/$scene.$retrace.rounds"; done
  for round in $(seq "$ROUNDS"); do
    for retrace in $modes; do
      if [ "$retrace" = baseline ]; then
        mode_args=(); binary=$BASELINE
      else
        mode_args=(--retrace "$retrace" "${ferry_extra[@]}"); binary=$ferry
      fi
      "$binary" render "$obj" --size "$SIZE" --spp "$SPP" --max-depth "$DEPTH" --frames $((WARMUP + FRAMES)) \
        "${mode_args[@]}" "${thread_args[@]}" -q -o "$work/ferry-$retrace.pfm" --stats "$work/ferry-$retrace.json"
    done
    pathtracer "${embree_args[@]}" --benchmark "$WARMUP" "$FRAMES" > "$work/embree.txt" 2>&1
    for retrace in $modes; do
    python3 - "$work/ferry-$retrace.json" "$work/embree.txt" "$WARMUP" "$((width * height * SPP))" \
      >> "$work/$scene.$retrace.rounds" <<EOF
import json, sys
$filtered_mean
stats, embree, warmup, paths = json.load(open(sys.argv[1])), open(sys.argv[2]).read(), int(sys.argv[3]), int(sys.argv[4])
frames = stats["render"]["frames"][warmup:]
ferry_fps = filtered_mean([1 / f["seconds"] for f in frames])
ferry_mrays = filtered_mean([f["traces"]["total"] / f["seconds"] / 1e6 for f in frames])
value = {l.split()[0]: float(l.split()[1]) for l in embree.splitlines() if l.startswith("BENCHMARK_RENDER_")}
print(ferry_fps * paths, ferry_mrays, value["BENCHMARK_RENDER_AVG"] * paths, value["BENCHMARK_RENDER_MRAYPS_AVG"],
      sum(f["traces"]["total"] for f in frames) / len(frames) / paths)
EOF
    done
  done
  for retrace in $modes; do
  python3 - "$scene" "$work/$scene.$retrace.rounds" "$retrace" <<'EOF'
import statistics, sys
rows = [list(map(float, l.split())) for l in open(sys.argv[2])]
med = [statistics.median(col) for col in zip(*rows)]
ratios = " ".join(f"{r[0] / r[2]:.2f}" for r in rows)
print(f"{sys.argv[1]:8} {sys.argv[3]:8} Ferry {med[0] / 1e6:7.3f} Mpaths/s {med[1]:7.2f} Mrays/s ({med[4]:.2f} rays/path) | "
      f"Embree {med[2] / 1e6:7.3f} Mpaths/s {med[3]:7.2f} Mrays/s | "
      f"Ferry/Embree paths/s {med[0] / med[2]:.3f} (per round: {ratios})")
EOF
  done
done
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
