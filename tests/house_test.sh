#!/usr/bin/env bash
# The house rules docs/architecture.md states, checked on the tree (the
# include arrows themselves are checked at every build by
# scripts/check_layering.py):
#   - no partitioner's name is compared in src/ outside the registry
#     (partition/partitioners.cpp): code asks a Partitioner what it does;
#   - no layer below app/ spells a command-line flag in its messages: it
#     names settings, and app/ names flags;
#   - trace/ holds trace backends only; io/ has a folder per format;
#   - comments state contracts: no issue numbers in src/, no header comment
#     block over 15 lines (history and measurements live in docs/).
set -euo pipefail
source_dir=$2
cd "$source_dir"
failures=0
fail() {
  echo "house_test: $1" >&2
  failures=$((failures + 1))
}

mapfile -t names < <(grep -oE 'name\(\) const override \{ return "[a-z-]+"' src/partition/partitioners.cpp |
  sed -E 's/.*"([a-z-]+)"/\1/')
((${#names[@]} >= 9)) || fail "found ${#names[@]} partitioners in src/partition/partitioners.cpp, expected 9"
pattern=$(IFS='|'; echo "${names[*]}")
if hits=$(grep -rnE "(==|!=) *\"($pattern)\"|\"($pattern)\" *(==|!=)" src --include='*.cpp' --include='*.h' |
  grep -v '_test\.cpp:' | grep -v '^src/partition/partitioners\.cpp:'); then
  fail "a partitioner's name is compared outside the registry:"$'\n'"$hits"
fi

if hits=$(grep -rnE '"[^"]*--[a-z][a-z-]+' src --include='*.cpp' --include='*.h' |
  grep -vE '^src/(app|flags)/|_test\.cpp:|_test_util\.h:' | grep -vE '^[^:]+:[0-9]+: *//'); then
  fail "a layer below app/ and flags/ spells a flag in a message (name the setting):"$'\n'"$hits"
fi

for f in src/trace/*; do
  case "$(basename "$f")" in
    trace_backend* | embree_backend* | reference_backend* | queue_trace.h | alpha_cutout*) ;;
    *) fail "src/trace/ holds $(basename "$f"), which is not a trace backend" ;;
  esac
done
for format in pbrt gltf obj ply parts images; do
  [[ -d src/io/$format ]] || fail "src/io/$format/ is missing (io/ has a folder per format)"
done

if hits=$(grep -rniE 'issues? #?[0-9]' src); then
  fail "issue numbers in src/ (they belong in commit messages and docs/):"$'\n'"$hits"
fi
if hits=$(find src -name '*.h' -print0 | xargs -0 awk '
    FNR == 1 { run = 0 }
    /^[[:space:]]*\/\// { if (run == 0) start = FNR; run++; next }
    { if (run > 15) print FILENAME ":" start ": " run " comment lines"; run = 0 }'); [[ -n "$hits" ]]; then
  fail "header comment blocks over 15 lines (move the why and the history to docs/):"$'\n'"$hits"
fi

echo "house_test: ${#names[@]} partitioners, $failures rule(s) broken"
((failures == 0))
