# Sourced by the benches against Embree's tutorial path tracer
# (pathtracer_vs_embree.sh, instructions_per_path.sh): the scenes both
# renderers get, and the camera Embree needs to see what Ferry sees.
#
#   embree_scenes WORK SHARED   writes WORK/cornell.obj (+ .mtl) and, when
#                               SHARED/stanford-bunny holds the bunny,
#                               WORK/bunny.obj; sets $scenes to those it wrote
#   embree_view FERRY OBJ       sets $embree_view_args to Ferry's default OBJ
#                               view (src/io/obj/obj_loader.cpp: at the bounds'
#                               centre, from +z, fovY 45) as Embree's arguments
#
# cornell: /usr/share/doc/embree3/models/cornell_box.obj turned 180 degrees
# about y (x, z -> -x, -z) so that Ferry's default view looks into the open
# side of the box; bunny: ../shared/scenes/stanford-bunny/bun_zipper.ply
# (69,451 triangles) as OBJ (bench/ply_to_obj.py). Neither has an emitter:
# both renderers get Ferry's default OBJ lights, a sun from
# normalize(0.4, 1, 0.6) with irradiance 3 and a constant sky of 0.5
# (embree_light_args).

embree_light_args=(--directionallight -0.4 -1 -0.6 3 3 3 --ambientlight 0.5 0.5 0.5)

embree_scenes() {
  local work=$1 shared=$2 here
  here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
  cp /usr/share/doc/embree3/models/cornell_box.mtl "$work/"
  awk '$1 == "v" { printf "v %s %s %s\n", -$2, $3, -$4; next } { print }' \
    /usr/share/doc/embree3/models/cornell_box.obj > "$work/cornell.obj"
  scenes="cornell bunny"
  if [ -f "$shared/stanford-bunny/bun_zipper.ply" ]; then
    python3 "$here/ply_to_obj.py" "$shared/stanford-bunny/bun_zipper.ply" "$work/bunny.obj" 2> /dev/null
  else
    echo "bunny: skipped (no $shared/stanford-bunny/bun_zipper.ply; SHARED_SCENES names another folder)"
    scenes=cornell
    : > "$work/bunny.obj"
  fi
}

embree_view() {
  local v
  read -r -a v <<< "$("$1" info "$2" --json | python3 -c '
import json, math, sys
lo, hi = json.load(sys.stdin)["bounds"]
c = [(a + b) / 2 for a, b in zip(lo, hi)]
d = 0.5 * math.dist(lo, hi) / math.sin(math.radians(22.5))
print(" ".join(f"{x:.9g}" for x in (c[0], c[1], c[2] + d, *c)))')"
  embree_view_args=(--vp "${v[@]:0:3}" --vi "${v[@]:3:3}" --vu 0 1 0 --fov 45 --righthanded)
}
