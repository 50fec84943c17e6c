#!/usr/bin/env bash
# Nothing hangs: a failure on one rank (exception or signal) at loading, at
# the first ray exchange or at compositing ends every rank within seconds with
# a message naming the rank, a non-zero exit, and the previous output file
# untouched. Input errors every rank meets are reported once.
set -uo pipefail
ferry=$1
source_dir=$2
source "$source_dir/tests/tools/mpi_env.sh"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

scene="builtin:cornell"
args=(--size 32x32 --spp 1 --max-depth 2 -q --threads 1)
echo "good image" > "$work/out.png"

expect_failure() {  # name, expected message fragment, command...
  local name=$1 fragment=$2
  shift 2
  local start=$SECONDS
  timeout 60 "$@" > "$work/stdout" 2> "$work/stderr"
  local code=$?
  local took=$((SECONDS - start))
  if [ $code -eq 124 ]; then fail "$name: hung (killed after 60 s)"; return; fi
  if [ $code -eq 0 ]; then fail "$name: exited 0"; fi
  if ! grep -q -- "$fragment" "$work/stderr"; then fail "$name: stderr lacks '$fragment'"; cat "$work/stderr"; fi
  if [ "$(cat "$work/out.png")" != "good image" ]; then fail "$name: replaced the previous output"; fi
  if ls "$work"/.out.png.tmp* > /dev/null 2>&1; then fail "$name: left a temporary file"; fi
  echo "$name: exit $code after ${took}s: $(grep -m1 'ferry: error' "$work/stderr")"
  if [ $took -gt 30 ]; then fail "$name: took ${took}s to end"; fi
}

for point in load exchange composite; do
  FERRY_FAIL_RANK=1 FERRY_FAIL_AT=$point expect_failure "exception at $point on rank 1" \
    "rank 1: injected failure at $point" mpirun --oversubscribe -np 3 "$ferry" render "$scene" "${args[@]}" -o "$work/out.png"
done
# The same in the bulk exchange (the default is the overlapped one, whose
# other ranks are then polling for messages, not waiting in a collective).
FERRY_FAIL_RANK=1 FERRY_FAIL_AT=exchange expect_failure "exception at exchange on rank 1, bulk" \
  "rank 1: injected failure at exchange" mpirun --oversubscribe -np 3 "$ferry" render "$scene" "${args[@]}" --exchange bulk -o "$work/out.png"
FERRY_FAIL_RANK=2 FERRY_FAIL_AT=signal-exchange expect_failure "signal at first exchange on rank 2" \
  "ferry: rank 2 died of SIGSEGV" mpirun --oversubscribe -np 3 "$ferry" render "$scene" "${args[@]}" -o "$work/out.png"

# Errors every rank meets: one message, not one per rank.
one_message() {  # name, fragment, command...
  local name=$1 fragment=$2
  shift 2
  expect_failure "$name" "$fragment" "$@"
  local n
  n=$(grep -c "ferry: error\|Error:\|ERROR:" "$work/stderr")
  if [ "$n" -ne 1 ]; then fail "$name: $n error messages instead of 1"; cat "$work/stderr"; fi
}
one_message "missing scene" "no such file" mpirun --oversubscribe -np 3 "$ferry" render "$work/missing.obj" "${args[@]}" -o "$work/out.png"
one_message "unknown builtin" "builtin" mpirun --oversubscribe -np 3 "$ferry" render "builtin:nowhere" "${args[@]}" -o "$work/out.png"
one_message "unknown view" "view" mpirun --oversubscribe -np 3 "$ferry" render "$scene" --view nowhere "${args[@]}" -o "$work/out.png"
one_message "bad size" "--size" mpirun --oversubscribe -np 3 "$ferry" render "$scene" --size 12by3 -q -o "$work/out.png"
one_message "bad flag" "--no-such-flag" mpirun --oversubscribe -np 3 "$ferry" render "$scene" --no-such-flag -o "$work/out.png"
one_message "bad exchange" "--exchange" mpirun --oversubscribe -np 3 "$ferry" render "$scene" "${args[@]}" --exchange sometimes -o "$work/out.png"
one_message "overlapped broadcast" "broadcast" mpirun --oversubscribe -np 3 "$ferry" render "$scene" "${args[@]}" --exchange overlapped --forwarding broadcast -o "$work/out.png"
one_message "bad light paths" "--light-paths" mpirun --oversubscribe -np 3 "$ferry" render "$scene" "${args[@]}" --light-paths sometimes -o "$work/out.png"
one_message "light paths without MIS" "--mis on" mpirun --oversubscribe -np 3 "$ferry" render "$scene" "${args[@]}" --light-paths on --mis off -o "$work/out.png"
one_message "bad max part" "--max-part" mpirun --oversubscribe -np 3 "$ferry" render "$scene" "${args[@]}" --partitioner ray-guided --max-part 0.5 -o "$work/out.png"
one_message "bad mesh proxies" "--mesh-proxies 0" mpirun --oversubscribe -np 3 "$ferry" render "$scene" "${args[@]}" --mesh-proxies 0 -o "$work/out.png"
one_message "bad crop" "--crop" mpirun --oversubscribe -np 3 "$ferry" render "$scene" "${args[@]}" --crop 0.5,0.2,0,1 -o "$work/out.png"
one_message "empty crop" "holds no pixel" mpirun --oversubscribe -np 3 "$ferry" render "$scene" --size 8x8 -q --crop 0.51,0.52,0,1 -o "$work/out.png"
one_message "bad output format" "unknown image format" mpirun --oversubscribe -np 2 "$ferry" render "$scene" "${args[@]}" -o "$work/out.gif"

if [ $failures -ne 0 ]; then echo "failure_test: $failures failures"; exit 1; fi
echo "failure_test: all passed"
