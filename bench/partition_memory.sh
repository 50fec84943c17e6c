#!/usr/bin/env bash
# Out-of-core partitioning, measured (issue 17): the same partition made in
# memory and under --memory-budget, side by side in one run (peak resident
# set from /usr/bin/time, wall time, the ratio), the part files compared
# byte for byte; then, with RENDER=1, the parts rendered on RANKS ranks with
# each rank's estimated bytes, Embree bytes (retained and peak), peak
# resident set against the issue's bound (estimate x 1.15 + 200 MiB), the
# set-up seconds and the frame time.
#
#   SCENE='builtin:island?scale=30' RANKS=8 BUDGET=2GiB RENDER=1 bash bench/partition_memory.sh [FERRY]
#   SCALES='1 5 10 30:2GiB' RANKS=8 bash bench/partition_memory.sh [FERRY]
#
# Memory figures are counts and do not depend on the machine's load; the
# seconds do (every rank shares the machine's cores).
set -euo pipefail
ferry=$(realpath "${1:-build/ferry}")
scene=${SCENE:-builtin:island?scale=30}
ranks=${RANKS:-8}
budget=${BUDGET:-2GiB}
partitioner=${PARTITIONER:-best}
size=${SIZE:-640x360}
work=${WORK:-$(mktemp -d -p "${TMPDIR:-/tmp}")}
trap 'rm -rf "$work"' EXIT
mpirun_args=(--oversubscribe)
[ "$(id -u)" -eq 0 ] && mpirun_args+=(--allow-run-as-root)

peak() { awk '/Maximum resident set size/ {printf "%.0f", $NF * 1024}' "$1"; }
wall() { awk -F': ' '/Elapsed \(wall clock\)/ {n=split($2,a,":"); s=0; for(i=1;i<=n;i++) s=s*60+a[i]; print s}' "$1"; }

# SCALES="1 5 10 30:2GiB": the island at each scale (after a colon, under
# that budget), one row each: instances, wall and CPU seconds, peak
# resident, and both per million instances, with each scale's time and peak
# per instance against the first scale's (issue 48: linear means near 1).
if [ -n "${SCALES:-}" ]; then
  echo "island, $ranks ranks, $partitioner ($(nproc) cores, $(free -g | awk '/Mem:/ {print $2}') GiB)"
  printf '%-14s %10s %8s %8s %10s %12s %12s %8s %8s\n' scale instances wall cpu "peak GiB" \
    "cpu s/M" "peak MiB/M" "time x" "peak x"
  first=""
  for entry in $SCALES; do
    s=${entry%%:*}
    args=()
    [ "$entry" != "$s" ] && args=(--memory-budget "${entry#*:}")
    sc="builtin:island?scale=$s"
    instances=$("$ferry" info --json "$sc" | python3 -c "import json, sys; print(json.load(sys.stdin)['instances'])")
    /usr/bin/time -f "%e %U %S %M" -o "$work/scale.time" "$ferry" partition "$sc" --ranks "$ranks" \
      --partitioner "$partitioner" -o "$work/scale" -q "${args[@]}"
    rm -rf "$work/scale"
    read -r w u sy kb < "$work/scale.time"
    row=$(python3 -c "
import sys
w, u, sy, kb, n = map(float, sys.argv[1:6])
cpu = u + sy; peak = kb * 1024
print(f'{n:.0f} {w:.1f} {cpu:.1f} {peak / 2**30:.2f} {cpu / n * 1e6:.2f} {peak / 2**20 / n * 1e6:.0f}')" \
      "$w" "$u" "$sy" "$kb" "$instances")
    read -r n wall cpu gib cpum peakm <<< "$row"
    [ -z "$first" ] && first="$cpum $peakm"
    ratios=$(python3 -c "import sys; a, b, c, d = map(float, sys.argv[1:]); print(f'{c / a:.2f} {d / b:.2f}')" $first "$cpum" "$peakm")
    printf '%-14s %10s %8s %8s %10s %12s %12s %8s %8s\n' "$entry" "$n" "$wall" "$cpu" "$gib" "$cpum" "$peakm" $ratios
  done
  exit 0
fi

echo "scene $scene, $ranks ranks, $partitioner, budget $budget ($(nproc) cores, $(free -g | awk '/Mem:/ {print $2}') GiB)"
"$ferry" info "$scene" | sed -n '2,9p'
if [ "${SKIP_IN_MEMORY:-0}" != 1 ]; then
  /usr/bin/time -v "$ferry" partition "$scene" --ranks "$ranks" --partitioner "$partitioner" \
    -o "$work/in" -q 2> "$work/in.time"
fi
/usr/bin/time -v "$ferry" partition "$scene" --ranks "$ranks" --partitioner "$partitioner" \
  -o "$work/out" --memory-budget "$budget" > "$work/out.log" 2> "$work/out.time"
grep "geometry out of memory" "$work/out.log" || echo "  (the scene fits the budget: partitioned in memory)"
gib() { python3 -c "import sys; print(f'{int(sys.argv[1]) / 2**30:.2f}')" "$1"; }
printf '%-26s %14s %10s\n' partition "peak (GiB)" seconds
if [ "${SKIP_IN_MEMORY:-0}" != 1 ]; then
  printf '%-26s %14s %10.1f\n' "in memory" "$(gib "$(peak "$work/in.time")")" "$(wall "$work/in.time")"
fi
printf '%-26s %14s %10.1f\n' "--memory-budget $budget" "$(gib "$(peak "$work/out.time")")" "$(wall "$work/out.time")"
python3 -c "import sys; print(f'  peak / budget: {int(sys.argv[1]) / float(sys.argv[2]):.3f}')" \
  "$(peak "$work/out.time")" "$(python3 -c "
import re,sys; t='$budget'; m=re.match(r'([0-9.]+)\s*([A-Za-z]*)', t); u={'':1,'B':1,'K':2**10,'KiB':2**10,'M':2**20,'MiB':2**20,'G':2**30,'GiB':2**30,'KB':1e3,'MB':1e6,'GB':1e9}[m.group(2)]; print(float(m.group(1))*u)")"
if [ "${SKIP_IN_MEMORY:-0}" != 1 ]; then
  same=1
  for f in "$work"/in/*.fpart; do cmp -s "$f" "$work/out/$(basename "$f")" || same=0; done
  [ "$same" = 1 ] && echo "  part files: byte-identical" || echo "  part files: DIFFER"
  rm -rf "$work/in"
fi
[ "${RENDER:-0}" = 1 ] || exit 0

/usr/bin/time -v mpirun "${mpirun_args[@]}" -np "$ranks" "$ferry" render "$work/out" --size "$size" \
  -q -o "$work/image.png" --stats "$work/stats.json" 2> "$work/render.time"
python3 - "$work/stats.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
mib = 2.0 ** 20
print(f"{'rank':>4} {'estimated':>10} {'embree':>8} {'embree pk':>9} {'peak res':>9} {'bound':>8}  (MiB)")
worst = 0.0
for r in s["memory"]["per_rank"]:
    bound = r["estimated_bytes"] * 1.15 + 200 * mib
    worst = max(worst, r["peak_resident_bytes"] / bound)
    print(f"{r['rank']:>4} {r['estimated_bytes'] / mib:10.0f} {r['embree_bytes'] / mib:8.0f} "
          f"{r['embree_peak_bytes'] / mib:9.0f} {r['peak_resident_bytes'] / mib:9.0f} {bound / mib:8.0f}")
print(f"  largest peak resident / bound: {worst:.3f} (goal <= 1)")
sec = s["seconds"]
print("  seconds: " + ", ".join(f"{k} {v:.2f}" for k, v in sec.items() if isinstance(v, (int, float))))
print(f"  frame seconds: {s['render']['total']['seconds']:.2f}")
ex = s["render"]["total"]["exchange"]
print(f"  rays forwarded {ex['rays_forwarded']}, camera paths {s['render']['total']['camera_paths']}")
PY
echo "  render wall seconds (mpirun): $(wall "$work/render.time")"
