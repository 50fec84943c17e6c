#!/usr/bin/env bash
# The distributed layer's central property: the N-rank image equals the
# 1-rank image with the same seed, for every rank count (odd ones too), every
# forwarding mode and every partition (including random replication and
# overlapping proxies), both exchanges (overlapped, the default, and bulk)
# and any chunk size. Exact: the ranks trace bit-identical rays and find the
# same hits, and the frame buffers sum in fixed point, so neither the order
# in which rays are shaded nor how the partial buffers are split over ranks
# changes a bit. One exception, allowed in at most 0.2% of the pixels: a ray that meets two
# surfaces at exactly the same distance (seams where instances touch, as in
# the Cornell box's corners) gets whichever the traversal order finds first,
# and that order depends on how the content is split over ranks.
# Also: no ray ever visits a rank twice, and rays forwarded (counted by the
# senders) equal rays received (counted by the receivers). Rank counts 2, 3,
# 5 and 8 here; 4 ranks in replay_test.sh (every forwarding mode, both path layouts).
set -euo pipefail
ferry=$1
source_dir=$2
source "$source_dir/tests/tools/multirank_test_env.sh"


run_scene() {
  local scene=$1 args=$2
  echo "== $scene"
  "$ferry" render "$scene" $args --seed 3 -q -o "$work/ref.pfm"
  for ranks in 2 3 8; do
    forwardings="proxies ring broadcast"
    [ "$ranks" = 8 ] && forwardings=proxies  # ring and broadcast visit every rank alike
    for forwarding in $forwardings; do
      for partition in round-robin random; do
        out="$work/r${ranks}-${forwarding}-${partition}.pfm"
        mpirun_n "$ranks" "$ferry" render "$scene" $args --seed 3 -q --threads 1 \
          --forwarding "$forwarding" --partition "$partition" -o "$out" --stats "$out.json"
        echo "ranks $ranks, $forwarding, $partition:"
        $compare "$work/ref.pfm" "$out" --rel 0 --abs 0 --outliers 0.002
        check_stats "$out.json"
      done
    done
  done
}

run_scene "builtin:cornell" "--size 40x40 --spp 2 --max-depth 4"
run_scene "builtin:island?scale=0.05" "--size 48x32 --spp 1 --max-depth 3"
# same_on_ranks LABEL SCENE ARGS: a pbrt scene on 2 and 3 ranks (the
# overlapped exchange on both, the bulk one, the replay layout and a random
# partition on one each) against its 1-rank image (no tie pixels: every pixel
# equal). Leaves the 1-rank image in $work/LABEL-ref.pfm.
same_on_ranks() {
  local label=$1 scene=$2 args=$3
  # shellcheck disable=SC2086
  "$ferry" render "$scene" $args -q -o "$work/$label-ref.pfm" 2>/dev/null
  for run in "2 --threads 1" "2 --partition random --threads 1" "3 --threads 1" \
    "3 --exchange bulk --threads 1" "3 --path-layout replay --threads 1"; do
    local ranks=${run%% *} variant=${run#* }
    # shellcheck disable=SC2086
    mpirun_n "$ranks" "$ferry" render "$scene" $args -q $variant -o "$work/$label.pfm" 2>/dev/null
    echo "$label, ranks $ranks, $variant:"
    $compare "$work/$label-ref.pfm" "$work/$label.pfm" --rel 0 --abs 0 --outliers 0
  done
}
# Subsurface walks (a pbrt scene: two spheres enclosing media): each step of
# a walk is a ray like any other, forwarded to whichever ranks hold the
# sphere's pieces, and a piece keeps the media its mesh bounds.
same_on_ranks subsurface "$source_dir/tests/oracle/cases/v3-subsurface.pbrt" "--size 24x24 --spp 2 --seed 3"
# Subsurface probes cross ranks that may not hold the material; a part
# directory keeps the materials' coefficients (and drops the walks' media).
shared="$source_dir/tests/oracle/cases/v3-subsurface-shared.pbrt"
same_on_ranks subsurface-shared "$shared" "--size 24x24 --spp 2 --seed 3"
"$ferry" partition "$shared" --ranks 3 --partitioner random -o "$work/shared-parts" -q 2>/dev/null
mpirun_n 3 "$ferry" render "$work/shared-parts" --size 24x24 --spp 2 --seed 3 -q --threads 1 \
  -o "$work/shared.pfm"
echo "subsurface-shared, a part directory on 3 ranks:"
$compare "$work/subsurface-shared-ref.pfm" "$work/shared.pfm" --rel 0 --abs 0 --outliers 0
if mpirun_n 3 "$ferry" render "$work/shared-parts" --size 24x24 --spp 2 --subsurface walk -q \
  --threads 1 -o "$work/walked.pfm" 2>"$work/walked.err"; then
  echo "walking a part directory should fail" >&2
  exit 1
fi
grep -q "part files do not keep" "$work/walked.err"
# Motion blur (a pbrt scene with moving instances): every rank finds a ray's
# time from its pixel and sample, and proxies bound the swept boxes, so
# forwarding finds moving content wherever it is when the ray passes; a part
# directory keeps both transforms.
motion="$source_dir/tests/oracle/cases/v3-motion.pbrt"
motion_args="--size 32x24 --spp 2 --seed 3"
same_on_ranks motion "$motion" "$motion_args"
same_on_ranks motion-camera "$source_dir/tests/oracle/cases/v3-motion-camera.pbrt" "$motion_args"
same_on_ranks motion-object "$source_dir/tests/oracle/cases/v3-motion-object.pbrt" "$motion_args"
same_on_ranks motion-object-v4 "$source_dir/tests/oracle/cases/v4-motion-object.pbrt" "$motion_args"
same_on_ranks motion-curves-object "$source_dir/tests/oracle/cases/v3-motion-curves-object.pbrt" "$motion_args"
"$ferry" partition "$motion" --ranks 3 -o "$work/motion-parts" -q 2>/dev/null
# shellcheck disable=SC2086
mpirun_n 3 "$ferry" render "$work/motion-parts" $motion_args -q --threads 1 -o "$work/motion.pfm"
echo "motion, a part directory on 3 ranks:"
$compare "$work/motion-ref.pfm" "$work/motion.pfm" --rel 0 --abs 0 --outliers 0
# The bulk exchange (the paper's rounds), and the overlapped one at small
# chunks (many chunks and bounces in flight at once) and with two threads a
# rank, and best's proxies merged to a few union boxes (more forwarding):
# the same image, bit for bit (tie pixels aside).
island="builtin:island?scale=0.05"
island_args="--size 48x32 --spp 1 --max-depth 3 --seed 3"
"$ferry" render "$island" $island_args -q -o "$work/island-ref.pfm"
for run in "3 --exchange bulk --threads 1" "5 --exchange bulk --threads 1" "5 --chunk 50 --threads 1" \
  "3 --chunk 7 --path-layout replay --threads 1" "5 --chunk 7 --path-layout replay --threads 1" \
  "3 --chunk 300 --threads 2" "5 --forwarding ring --chunk 100 --threads 1" \
  "3 --partition best --max-proxies 24 --threads 1"; do
  ranks=${run%% *} variant=${run#* }
  out="$work/variant.pfm"
  # shellcheck disable=SC2086
  mpirun_n "$ranks" "$ferry" render "$island" $island_args -q $variant \
    -o "$out" --stats "$out.json"
  echo "ranks $ranks, $variant:"
  $compare "$work/island-ref.pfm" "$out" --rel 0 --abs 0 --outliers 0.002
  check_stats "$out.json"
done
# One rank under mpirun equals the plain run, which does not start MPI
# (mpi/launcher.h).
mpirun_n 1 "$ferry" render "builtin:cornell" --size 40x40 --spp 2 --max-depth 4 --seed 3 -q -o "$work/one.pfm" \
  --stats "$work/one.json"
"$ferry" render "builtin:cornell" --size 40x40 --spp 2 --max-depth 4 --seed 3 -q -o "$work/plain.pfm" \
  --stats "$work/plain.json"
$compare "$work/plain.pfm" "$work/one.pfm" --rel 0 --abs 0
python3 -c "
import json, sys
one, plain = (json.load(open(f))['settings']['transport'] for f in sys.argv[1:])
assert (one, plain) == ('mpi', 'in-process'), (one, plain)" "$work/one.json" "$work/plain.json"
# Keeping the hits a rank found (default, --retrace remote) or re-tracing every
# shaded path (--retrace all) gives the same image on many ranks, bit for bit.
for forwarding in proxies broadcast; do
  for retrace in remote all; do
    mpirun_n 3 "$ferry" render "builtin:cornell" --size 40x40 --spp 2 --max-depth 4 --seed 3 -q --threads 1 \
      --forwarding "$forwarding" --partition random --retrace "$retrace" -o "$work/retrace-$retrace.pfm" \
      --stats "$work/retrace-$retrace.json"
    check_stats "$work/retrace-$retrace.json"
  done
  echo "3 ranks, $forwarding, --retrace remote against all:"
  $compare "$work/retrace-all.pfm" "$work/retrace-remote.pfm" --rel 0 --abs 0
done
# The instance level is a speed choice: objects placed once at the top level
# (default, --instancing shared) or under instances (always), same image on
# 3 ranks (the island mixes both kinds: terrain placed once, plants instanced).
for instancing in shared always; do
  mpirun_n 3 "$ferry" render "builtin:island?scale=0.05" --size 48x32 --spp 1 --max-depth 3 -q --threads 1 \
    --partition spatial-sah --instancing "$instancing" -o "$work/instancing-$instancing.pfm"
done
echo "3 ranks, --instancing shared against always:"
$compare "$work/instancing-always.pfm" "$work/instancing-shared.pfm" --rel 0 --abs 0
# Light paths: rays that start at the emitter, on whichever rank generates
# the pixel's paths, and shadow rays to the camera that add to any pixel on
# any rank: the same image at 3 and 5 ranks, both exchanges, the replay
# layout, and two threads a rank.
cornell_light="--size 40x40 --spp 2 --max-depth 4 --seed 3 --light-paths on"
"$ferry" render "builtin:cornell" $cornell_light -q -o "$work/light-ref.pfm" --stats "$work/light-ref.json"
python3 -c "import json,sys; t=json.load(open(sys.argv[1]))['render']['total']; assert t['light_paths'] > 0, t" \
  "$work/light-ref.json"
for run in "3 --threads 1" "5 --threads 1" "5 --exchange bulk --threads 1" \
  "3 --path-layout replay --chunk 60 --threads 1" "3 --partition random --forwarding broadcast --threads 2"; do
  ranks=${run%% *} variant=${run#* }
  out="$work/light.pfm"
  # shellcheck disable=SC2086
  mpirun_n "$ranks" "$ferry" render "builtin:cornell" $cornell_light -q $variant -o "$out" \
    --stats "$out.json"
  echo "light paths, ranks $ranks, $variant:"
  $compare "$work/light-ref.pfm" "$out" --rel 0 --abs 0 --outliers 0.002
  check_stats "$out.json"
done
# A crop window (--crop) with light paths: the same part of the image on 1
# and 3 ranks (camera paths keyed by the film's pixel, light paths splat
# into the window only).
"$ferry" render "builtin:cornell" $cornell_light --crop 0.2,0.7,0.1,0.55 -q -o "$work/crop-ref.pfm"
mpirun_n 3 "$ferry" render "builtin:cornell" $cornell_light --crop 0.2,0.7,0.1,0.55 -q --threads 1 \
  -o "$work/crop.pfm"
echo "crop window with light paths, 3 ranks:"
$compare "$work/crop-ref.pfm" "$work/crop.pfm" --rel 0 --abs 0 --outliers 0.002
echo "distributed_test: all passed"
