#!/usr/bin/env bash
# The differential suite: every case in tests/oracle/cases, rendered by Ferry
# and compared with pbrt's own render of it (tests/oracle/references, made by
# tests/oracle/render_references.sh). Per channel, the mean over the image
# (bias = Ferry / pbrt - 1) and the relative RMSE of 4x4 block means
# (bench/image_compare) must stay within the case's limits in
# tests/oracle/expectations.tsv: +-2 % and 0.05 for an exact case; for an
# approximated one its measured difference, so that it cannot drift further.
#
#   bash tests/oracle_test.sh FERRY IMAGE_COMPARE SOURCE_DIR [NAME ...]
#
# Settings (environment): SPP (default 256, the cases' Ferry renders),
# KEEP=DIR (keep renders and side-by-side pictures there; failing cases'
# pictures are always written to $TMPDIR/ferry-oracle-failures).
set -euo pipefail
ferry=$(realpath "$1")
compare=$(realpath "$2")
src=$(realpath "$3")
shift 3
here="$src/tests/oracle"
SPP=${SPP:-256}
work=${KEEP:-$(mktemp -d)}
mkdir -p "$work"
[ -n "${KEEP:-}" ] || trap 'rm -rf "$work"' EXIT
failures_dir="${TMPDIR:-/tmp}/ferry-oracle-failures"

names=("$@")
if ((${#names[@]} == 0)); then
  for f in "$here"/references/*.exr; do names+=("$(basename "$f" .exr)"); done
fi

# expectations.tsv: case, status, max |bias| per channel, max block RMSE, note.
limits() {
  awk -F'\t' -v n="$1" '$1 == n { print $2, $3, $4; found = 1 } END { if (!found) print "exact 0.02 0.05" }' \
    "$here/expectations.tsv"
}

failed=0
printf '%-36s %-12s %8s %8s %8s %8s %6s\n' case status biasR biasG biasB rmse result
for name in "${names[@]}"; do
  scene="$here/cases/$name.pbrt"
  ref="$here/references/$name.exr"
  [ -f "$scene" ] && [ -f "$ref" ] || { echo "oracle_test: $name: no case or no reference" >&2; exit 2; }
  read -r status maxBias maxRmse < <(limits "$name")
  out="$work/$name.exr"
  if ! "$ferry" render "$scene" -o "$out" --spp "$SPP" --quiet >"$work/$name.log" 2>&1; then
    echo "oracle_test: $name: ferry failed:" >&2
    cat "$work/$name.log" >&2
    failed=1
    continue
  fi
  w=$(/usr/bin/python3 -c "import OpenImageIO as o; s=o.ImageInput.open('$ref').spec(); print(f'{s.width}x{s.height}')")
  "$compare" "$ref" "$out" --size "$w" --block 4 --json "$work/$name.json" \
    --side-by-side "$work/$name.png" >/dev/null
  read -r bR bG bB rmse ok < <(python3 - "$work/$name.json" "$maxBias" "$maxRmse" <<'EOF'
import json, sys
j = json.load(open(sys.argv[1]))
bias = [j["channels"][c]["bias"] for c in ("R", "G", "B")]
bias = [0.0 if b is None else b for b in bias]
rmse = 0.0 if j["block_relative_rmse"] is None else j["block_relative_rmse"]
ok = all(abs(b) <= float(sys.argv[2]) for b in bias) and rmse <= float(sys.argv[3])
print(f"{bias[0]:+.4f} {bias[1]:+.4f} {bias[2]:+.4f} {rmse:.4f} {'ok' if ok else 'FAIL'}")
EOF
)
  printf '%-36s %-12s %8s %8s %8s %8s %6s\n' "$name" "$status" "$bR" "$bG" "$bB" "$rmse" "$ok"
  if [ "$ok" != ok ]; then
    failed=1
    mkdir -p "$failures_dir"
    cp "$work/$name.png" "$work/$name.exr" "$failures_dir/"
    echo "  limits: |bias| <= $maxBias, block RMSE <= $maxRmse; pictures in $failures_dir/$name.png" >&2
  fi
done
exit $failed
