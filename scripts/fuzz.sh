#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, ASan + UBSan, from the same libraries
# as the command: tests/fuzz/CMakeLists.txt) and runs each for SECONDS over
# its seeds (tests/fuzz/corpus/<kind>) and past findings
# (tests/fuzz/regressions/<kind>), one target per core at a time. Fails on
# any crash, leak, timeout, out-of-memory or sanitizer report, and keeps the
# input that caused it in $FUZZ_OUT (default build-fuzz/findings).
#
#   bash scripts/fuzz.sh [SECONDS] [KIND ...]     # default: 60 s, every kind
#   MERGE=1 bash scripts/fuzz.sh 3600 pbrt        # keep what a long run found, minimised
#   FUZZ_OPT=-O0 bash scripts/fuzz.sh 10          # as CI: builds in half the time, runs slower
#   FUZZ_CORPUS=~/fuzz bash scripts/fuzz.sh 3600   # what a run finds stays there for the next
#   FUZZ_BUILD_ONLY=1 bash scripts/fuzz.sh          # only build the targets
#
# Prints a table: kind, executions, corpus size, coverage (libFuzzer's
# edges), features, and the outcome. docs/fuzzing.md has the long runs.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
shift || true
build=${FUZZ_BUILD:-build-fuzz}
out=${FUZZ_OUT:-$build/findings}
jobs=${FUZZ_JOBS:-$(nproc)}
opt=${FUZZ_OPT:--O1}

if ! command -v clang++ > /dev/null; then
  echo "fuzz.sh: clang++ is missing (bash scripts/install-deps.sh installs it)" >&2
  exit 1
fi
CC=clang CXX=clang++ cmake -S . -B "$build" -G Ninja -DFERRY_BUILD_FUZZERS=ON \
  -DFERRY_BUILD_TESTS=OFF -DFERRY_BUILD_BENCH=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="$opt -gline-tables-only" -DCMAKE_C_FLAGS_RELWITHDEBINFO="$opt -gline-tables-only" > /dev/null
cmake --build "$build" --target ferry_fuzzers
[ "${FUZZ_BUILD_ONLY:-0}" = 1 ] && exit 0

if (($# > 0)); then
  kinds=("$@")
else
  kinds=()
  for d in tests/fuzz/corpus/*/; do kinds+=("$(basename "$d")"); done
fi
mkdir -p "$out"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
corpora=${FUZZ_CORPUS:-$work}

# Kinds whose inputs go to a third-party reader that mutations make ask for
# absurd allocations, which AddressSanitizer ends the process for (the
# release build reports the reader's error instead): run over their seeds
# only, unless FUZZ_MUTATE_ALL=1. vdb: OpenVDB reads chunk sizes from the
# file (docs/fuzzing.md). Their regressions are OpenVDB's behaviours too,
# which under ASan depend on the build (a file that leaks at -O1 asks for
# 1 TiB at -O0): the suite replays them in its own build.
replay_only=" vdb "

# run KIND: one target for `seconds`; its log in $work/KIND.log, its exit
# status in $work/KIND.status.
run() {
  local kind=$1 fuzzer="$build/tests/fuzz/ferry_fuzz_$1"
  local dirs=("$corpora/$kind.corpus" "tests/fuzz/corpus/$kind")
  [[ -d "tests/fuzz/regressions/$kind" && $replay_only != *" $kind "* ]] && dirs+=("tests/fuzz/regressions/$kind")
  mkdir -p "$corpora/$kind.corpus"
  local status=0 limit=""
  [[ $replay_only == *" $kind "* && ${FUZZ_MUTATE_ALL:-0} != 1 ]] && limit="-runs=0"
  # Leaks in third-party libraries only are suppressed, each with its reason.
  LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/scripts/sanitizers/lsan.supp:print_suppressions=0} \
    ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1} UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1} \
    "$fuzzer" -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=10 -print_final_stats=1 $limit \
    -artifact_prefix="$out/$kind-" "${dirs[@]}" > "$work/$kind.log" 2>&1 || status=$?
  if [ "$status" = 0 ] && [ "${MERGE:-0}" = 1 ]; then
    "$fuzzer" -merge=1 "tests/fuzz/corpus/$kind" "$corpora/$kind.corpus" >> "$work/$kind.log" 2>&1 || status=$?
  fi
  echo "$status" > "$work/$kind.status"
}

running=0
for kind in "${kinds[@]}"; do
  [ -x "$build/tests/fuzz/ferry_fuzz_$kind" ] || { echo "fuzz.sh: no target for '$kind'" >&2; exit 1; }
  run "$kind" &
  running=$((running + 1))
  if ((running >= jobs)); then
    wait -n || true
    running=$((running - 1))
  fi
done
wait

failed=0
printf '%-11s %12s %8s %8s %8s  %s\n' kind executions corpus cov ft outcome
for kind in "${kinds[@]}"; do
  log="$work/$kind.log"
  status=$(cat "$work/$kind.status" 2> /dev/null || echo 1)
  # (A target that fails before its first status line leaves these empty.)
  execs=$(awk '/stat::number_of_executed_units/ {print $2}' "$log" 2> /dev/null | tail -1 || true)
  last=$(grep -E '^#[0-9]+' "$log" 2> /dev/null | tail -1 || true)
  cov=$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<< "$last")
  ft=$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<< "$last")
  corp=$(sed -n 's/.* corp: \([0-9]*\).*/\1/p' <<< "$last")
  outcome=clean
  if [ "$status" != 0 ] || grep -qE '^(==[0-9]+==ERROR|SUMMARY: (Address|Undefined|Leak)Sanitizer)|runtime error:' "$log"; then
    outcome="FAILED (exit $status; input in $out/$kind-*)"
    failed=$((failed + 1))
  fi
  printf '%-11s %12s %8s %8s %8s  %s\n' "$kind" "${execs:-?}" "${corp:-?}" "${cov:-?}" "${ft:-?}" "$outcome"
  if [[ $outcome != clean ]]; then
    grep -E -A25 '==ERROR|runtime error:|deadly signal|ALARM|out-of-memory' "$log" | head -60 || tail -40 "$log"
  fi
done
if ((failed > 0)); then
  echo "fuzz.sh: $failed of ${#kinds[@]} targets failed"
  echo "fuzz: $((${#kinds[@]} - failed)) passed, $failed failed"
  exit 1
fi
echo "fuzz.sh: ${#kinds[@]} targets, ${seconds} s each, no finding"
echo "fuzz: ${#kinds[@]} passed, 0 failed"
