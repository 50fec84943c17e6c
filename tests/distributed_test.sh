#!/usr/bin/env bash
# The distributed layer's central property: the N-rank image equals the
# 1-rank image with the same seed, for every rank count (odd ones too), every
# forwarding mode and every partition (including random replication and
# overlapping proxies). Tolerance: relative 1e-4 per channel (plus 1e-6
# absolute): the ranks trace bit-identical rays and find the same hits, so
# only the order in which partial frame buffers are summed differs; with at
# most a few hundred float additions per pixel that is far below 1e-4.
# One exception, allowed in at most 0.2% of the pixels: a ray that meets two
# surfaces at exactly the same distance (seams where instances touch, as in
# the Cornell box's corners) gets whichever the traversal order finds first,
# and that order depends on how the content is split over ranks.
# Also: no ray ever visits a rank twice, and rays forwarded (counted by the
# senders) equal rays received (counted by the receivers).
set -euo pipefail
ferry=$1
source_dir=$2
source "$source_dir/tests/tools/multirank_test_env.sh"


run_scene() {
  local scene=$1 args=$2
  echo "== $scene"
  "$ferry" render "$scene" $args --seed 3 -q -o "$work/ref.pfm"
  for ranks in 2 3 4 8; do
    for forwarding in proxies ring broadcast; do
      for partition in round-robin random; do
        out="$work/r${ranks}-${forwarding}-${partition}.pfm"
        mpirun_n "$ranks" "$ferry" render "$scene" $args --seed 3 -q --threads 1 \
          --forwarding "$forwarding" --partition "$partition" -o "$out" --stats "$out.json"
        echo "ranks $ranks, $forwarding, $partition:"
        $compare "$work/ref.pfm" "$out" --outliers 0.002
        check_stats "$out.json"
      done
    done
  done
}

run_scene "builtin:cornell" "--size 40x40 --spp 2 --max-depth 4"
run_scene "builtin:island?scale=0.05" "--size 48x32 --spp 1 --max-depth 3"
# One rank under mpirun equals the plain run.
mpirun_n 1 "$ferry" render "builtin:cornell" --size 40x40 --spp 2 --max-depth 4 --seed 3 -q -o "$work/one.pfm"
"$ferry" render "builtin:cornell" --size 40x40 --spp 2 --max-depth 4 --seed 3 -q -o "$work/plain.pfm"
$compare "$work/plain.pfm" "$work/one.pfm" --rel 0 --abs 0
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
echo "distributed_test: all passed"
