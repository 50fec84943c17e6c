#!/usr/bin/env bash
# Smoke test of bench/paper-eval (issue 7), so the evaluation command cannot
# silently rot: a tiny island, one view, two partitioners, all three
# forwarding modes, 8 ranks on this host (NET=local: the network namespaces
# need root and take minutes; the real run exercises them). Checks that it
# writes the write-up and its images, that the counts repeat exactly (every
# proxies run is rendered twice), and that a failing run is named, exits
# non-zero and leaves no write-up behind.
#   tests/paper_eval_test.sh FERRY SOURCE_DIR
set -euo pipefail
ferry=$(realpath "$1")
src=$(realpath "$2")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

if ! /usr/bin/python3 -c "import matplotlib" 2>/dev/null && ! python3 -c "import matplotlib" 2>/dev/null; then
  fail "python3-matplotlib is missing (bash scripts/install-deps.sh)"
fi

export NET=local RATES_LOCAL="local again" SIZE=48x20 SCALE=0.05 FRAMES=1 SCENES=island
export VIEWS_island=default PARTITIONERS="spatial-sah best ray-guided" PICTURES=0

mkdir -p "$work/ok"
OUT="$work/ok" bash "$src/bench/paper-eval" "$ferry" > "$work/ok.log" 2>&1 || { cat "$work/ok.log"; fail "paper-eval failed"; }
md="$work/ok/evaluation.md"
[ -s "$md" ] || fail "no evaluation.md"
[ ! -e "$md.tmp" ] || fail "evaluation.md.tmp left behind"
for f in forwarded.png frame-times.png view-island-default.png; do
  [ -s "$work/ok/images/eval/$f" ] || fail "no images/eval/$f"
done
grep -q "^| island | default | .*(1.0×)" "$md" || fail "Table 1 row missing: $(grep -n island "$md" | head -3)"
grep -q "identical counts" "$md" || fail "determinism note missing"
grep -q "| island | default | best | broadcast |" "$md" || fail "forwarding-mode row missing"
grep -q "^## Against the paper" "$md" || fail "comparison missing"
grep -q "^## The bandwidth predictor" "$md" || fail "prediction table missing"
grep -q "^| island | default | ray-guided | " "$md" || grep -q "^## The ray-guided partitioner against the six" "$md" \
  || fail "ray-guided section missing"
echo "ok: $(grep -c '' "$md") lines; $(grep -m1 '^  island ' "$work/ok.log" | xargs)"

# A failing run: named, non-zero, nothing written.
mkdir -p "$work/bad"
if OUT="$work/bad" VIEWS_island=no-such-view bash "$src/bench/paper-eval" "$ferry" > "$work/bad.log" 2>&1; then
  fail "paper-eval succeeded with an unknown view"
fi
grep -q "FAILED.*island view no-such-view, partitioner spatial-sah" "$work/bad.log" || { cat "$work/bad.log"; fail "failing run not named"; }
[ -z "$(ls -A "$work/bad")" ] || fail "a failed run left files in OUT: $(ls -A "$work/bad")"
echo "ok: a failing run is named and leaves nothing"
