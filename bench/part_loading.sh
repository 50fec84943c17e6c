#!/usr/bin/env bash
# Loading parts, measured against a baseline build in one run (issue 17,
# items 2 and 3): the same part directory rendered by BASELINE and by FERRY,
# alternately, ROUNDS times each. Per binary, the median over rounds of:
# the slowest rank's load, build and time to first pixel (the stats'
# "seconds"), the frame time, and per rank the peak resident set against its
# estimated part bytes and the part file's size. The images must be equal
# bit for bit (PFM), which the script checks.
#
#   BASELINE=/tmp/base/build/ferry SCENE='builtin:island?scale=4' RANKS=8 \
#     bash bench/part_loading.sh [FERRY]
#
# BASELINE is another build of Ferry (e.g. `git worktree add /tmp/base <commit>`
# built there); without it only FERRY is measured. The seconds depend on the
# machine's load (every rank shares its cores); the bytes do not.
set -euo pipefail
ferry=$(realpath "${1:-build/ferry}")
baseline=${BASELINE:-}
scene=${SCENE:-builtin:island?scale=4}
ranks=${RANKS:-8}
rounds=${ROUNDS:-3}
partitioner=${PARTITIONER:-best}
size=${SIZE:-640x360}
threads=${THREADS:-0}
work=${WORK:-$(mktemp -d -p "${TMPDIR:-/tmp}")}
trap 'rm -rf "$work"' EXIT
mpirun_args=(--oversubscribe --bind-to none)
[ "$(id -u)" -eq 0 ] && mpirun_args+=(--allow-run-as-root)

echo "scene $scene, $ranks ranks, $partitioner, $size, $rounds rounds" \
  "($(nproc) cores, $(free -g | awk '/Mem:/ {print $2}') GiB, $(uname -r))"
"$ferry" partition "$scene" --ranks "$ranks" --partitioner "$partitioner" -o "$work/parts" -q
du -sh "$work/parts" | awk '{print "  part directory: " $1}'

binaries=("new:$ferry")
[ -n "$baseline" ] && binaries=("base:$(realpath "$baseline")" "${binaries[@]}")
for round in $(seq 1 "$rounds"); do
  for entry in "${binaries[@]}"; do
    name=${entry%%:*} bin=${entry#*:}
    # Drop nothing from the page cache: both read parts the partitioner just
    # wrote, as a render after `ferry partition` on the same node does.
    mpirun "${mpirun_args[@]}" -np "$ranks" "$bin" render "$work/parts" --size "$size" \
      --spp 1 --threads "$threads" -q -o "$work/$name-$round.pfm" \
      --stats "$work/$name-$round.json" > /dev/null
  done
done

python3 - "$work" "$rounds" "$ranks" "${binaries[@]}" <<'PY'
import filecmp, json, os, statistics, sys
work, rounds, ranks = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
names = [e.split(":", 1)[0] for e in sys.argv[4:]]
mib = 2.0 ** 20
parts = sorted(f for f in os.listdir(f"{work}/parts") if f.startswith("part-"))
part_bytes = [os.path.getsize(f"{work}/parts/{f}") for f in parts]
runs = {n: [json.load(open(f"{work}/{n}-{r}.json")) for r in range(1, rounds + 1)] for n in names}
med = lambda xs: statistics.median(xs)
rows = {}
for n in names:
    sec = lambda k: med([s["seconds"]["slowest"][k] for s in runs[n]])
    rows[n] = {
        "load s (slowest rank)": sec("load"),
        "build s (slowest rank)": sec("build"),
        "first pixel s (slowest rank)": sec("first_pixel"),
        "frame s": med([s["render"]["total"]["seconds"] for s in runs[n]]),
        "largest peak resident MiB": med([max(r["peak_resident_bytes"] for r in s["memory"]["per_rank"]) / mib for s in runs[n]]),
        "summed peak resident MiB": med([sum(r["peak_resident_bytes"] for r in s["memory"]["per_rank"]) / mib for s in runs[n]]),
    }
keys = list(rows[names[0]].keys())
print(f"{'median over ' + str(rounds) + ' rounds':32}" + "".join(f"{n:>12}" for n in names) +
      ("   new/base" if len(names) == 2 else ""))
for k in keys:
    line = f"{k:32}" + "".join(f"{rows[n][k]:12.2f}" for n in names)
    if len(names) == 2 and rows["base"][k]:
        line += f"   {rows['new'][k] / rows['base'][k]:8.3f}"
    print(line)
intervals = ["start", "load", "lights", "build", "agree", "proxies", "renderer"]
print("\nslowest rank's set-up, median seconds: " + ", ".join(intervals))
for n in names:
    print(f"  {n:5} " + " ".join(f"{med([s['seconds']['slowest'][k] for s in runs[n]]):6.2f}" for k in intervals))
print("\nper rank (last round), MiB: part file | estimated | Embree retained | peak resident" +
      "".join(f" {n}" for n in names))
last = {n: runs[n][-1]["memory"]["per_rank"] for n in names}
for r in range(ranks):
    est = last[names[-1]][r]["estimated_bytes"] / mib
    emb = last[names[-1]][r]["embree_bytes"] / mib
    peaks = " ".join(f"{last[n][r]['peak_resident_bytes'] / mib:8.0f}" for n in names)
    print(f"  rank {r}: {part_bytes[r] / mib:8.0f} {est:9.0f} {emb:9.0f}   {peaks}")
same = all(filecmp.cmp(f"{work}/{names[0]}-1.pfm", f"{work}/{n}-{r}.pfm", shallow=False)
           for n in names for r in range(1, rounds + 1))
print(f"\nimages: {'bit-identical' if same else 'DIFFER'} across binaries and rounds")
fw = [s["render"]["total"]["exchange"]["rays_forwarded"] for n in names for s in runs[n]]
print(f"rays forwarded per frame: {sorted(set(fw))}")
PY
