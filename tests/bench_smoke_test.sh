#!/usr/bin/env bash
# Every bench the docs name still runs: each one once, at the smallest
# settings it takes, must exit 0 and print its result line. The figures are
# not checked (they mean nothing at these sizes), but for two that hold at
# any size and load: the direct light against Embree's tutorial's, and
# Ferry's own instructions a path against the tutorial's (callgrind
# counts). Run elsewhere: the benches
# with gates of their own (data_groups_test, partition_budget_test,
# partition_scale_test, volume_bricks_test, paper_eval_test with
# netns.sh, transmittance_gate, image_compare_test). Left out: same_images.sh
# (minutes at any size; it is run on every refactor), network_overlap.sh
# (network namespaces and tc for 8 ranks, as paper-eval's) and
# proxy_query_bench (its set-up builds a 2 M-proxy tree: minutes).
set -uo pipefail
ferry=$(realpath "$1")
source_dir=$2
source "$source_dir/tests/tools/mpi_env.sh"
cd "$source_dir"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failures=0
export FERRY="$ferry"

# bench NAME EXPECTED COMMAND...: runs it, its output in $work/NAME.log; fails
# unless it exits 0 and its output has EXPECTED (a regular expression).
bench() {
  local name=$1 expected=$2
  shift 2
  local start=$SECONDS
  if ! "$@" > "$work/$name.log" 2>&1; then
    echo "FAIL: $name exited non-zero; its output ends:"
    tail -20 "$work/$name.log"
    failures=$((failures + 1))
  elif ! grep -Eq "$expected" "$work/$name.log"; then
    echo "FAIL: $name printed no line matching '$expected'; its output ends:"
    tail -20 "$work/$name.log"
    failures=$((failures + 1))
  else
    echo "  $name: ran in $((SECONDS - start)) s"
  fi
}

tiny="builtin:island?scale=0.05"
bench distribution_cost 'memory per rank' env SCENE="$tiny" SIZE=48x32 RANKS="1 2" FRAMES=1 ROUNDS=1 \
  EXCHANGES=overlapped bash bench/distribution_cost.sh "$ferry"
bench stage_times 'stage seconds' env SCENE="$tiny" SIZE=96x54 RANKS="1 2" FRAMES=2 TOLERANCE=0.25 \
  bash bench/stage_times.sh "$ferry"
bench viewer_fps 'frames/s' env SCENE="$tiny" SIZE=48x32 RANKS=1 SECONDS_EACH=2 \
  CHANGES=1 bash bench/viewer_fps.sh "$ferry"
bench viewer_restyle 'restyle .* to its first frame' env SIZE=256 RANKS=2 IMAGE=48x32 CHANGES=1 \
  bash bench/viewer_restyle.sh "$ferry"
bench memory_vs_embree 'est/ret' bash bench/memory_vs_embree.sh "$ferry" "$tiny"
bench part_loading 'images: bit-identical' env BASELINE="$ferry" SCENE="$tiny" RANKS=2 ROUNDS=1 SIZE=48x32 \
  THREADS=1 bash bench/part_loading.sh "$ferry"
bench instanced_shapes 'instanced_shapes.csv' env SCENES="$tiny" RANKS=2 ROUNDS=1 FRAMES=2 SHAPES=4 SIZE=48x32 \
  OUT="$work/instanced" bash bench/instanced_shapes.sh "$ferry"
bench memory_bandwidth 'memory_bandwidth.csv' env SCENES=island SCALE=0.05 RANKS=2 CAPS=2 \
  OUT="$work/bandwidth" bash bench/memory_bandwidth.sh "$ferry"
bench trace_ceiling_bench 'render/trace-stream' "$(dirname "$ferry")/bench/trace_ceiling_bench" --benchmark_min_time=0.01
bench curves_bench 'rays gate' env STRANDS=20000 MAX_BYTES_RATIO=2 MIN_RAYS_RATIO=0.5 \
  "$(dirname "$ferry")/bench/curves_bench" --benchmark_min_time=0.05 --benchmark_repetitions=3 \
  --benchmark_enable_random_interleaving=true
bench distribution_profile 'the 1-rank CPU time per frame' env SCENE="$tiny" SIZE=48x32 RANKS=2 \
  FRAMES=2 bash bench/distribution_profile.sh "$ferry"
if command -v pathtracer > /dev/null; then
  bench pathtracer_vs_embree 'same scene: converged at depth 1' env SIZE=32x32 SPP=1 FRAMES=1 WARMUP=0 ROUNDS=1 \
    ERROR_SPP=1 REFERENCE_SPP=2 DIRECT_SPP=1024 MAX_DIRECT_DIFFERENCE=1 bash bench/pathtracer_vs_embree.sh "$ferry"
  bench instructions_per_path 'Ferry / tutorial' env SIZE=32x32 MAX_OWN_RATIO=1.85 \
    bash bench/instructions_per_path.sh "$ferry"
else
  echo "FAIL: pathtracer_vs_embree: Embree's tutorial (embree-tools) is missing"
  failures=$((failures + 1))
fi
if [ -d "$source_dir/../shared/scenes/bathroom" ]; then
  bench bathroom_mirror_check '^[|] B [|]' /usr/bin/python3 bench/bathroom_mirror_check.py \
    --ferry "$ferry" --step 24 --spp 4
  bench bathroom_experiments '^[|] hand mirror' /usr/bin/python3 bench/bathroom_experiments.py \
    --ferry "$ferry" --spp 1 --step 8
  bench time_to_pbrt_error '^[|] bathroom|nothing measured' env ONLY=bathroom PBRT_SPP=2 \
    REF_SPP=4 FERRY_SPP=1 FERRY_MAX_SPP=2 OUT="$work/time-to-pbrt-error" FERRY="$ferry" \
    IMAGE_COMPARE="$(dirname "$ferry")/bench/image_compare" bash bench/time_to_pbrt_error.sh
  bench fidelity 'against Ferry at' env ONLY=bathroom SPP=1 EQUAL_TIME=1 CONVERGED_SPP=2 \
    OUT="$work/fidelity" FERRY="$ferry" \
    IMAGE_COMPARE="$(dirname "$ferry")/bench/image_compare" bench/fidelity
else
  echo "  fidelity, bathroom_mirror_check, bathroom_experiments, time_to_pbrt_error: skipped (no ../shared/scenes beside the source tree)"
fi

if ((failures > 0)); then
  echo "bench_smoke_test: $failures failed"
  exit 1
fi
echo "bench_smoke_test: every bench ran"
