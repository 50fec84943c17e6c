#!/usr/bin/env bash
# What finer instanced proxies cost and save (docs/partitioning.md,
# "Instanced proxies"): for each scene and each --instance-proxies value
# (boxes per mesh of an instanced object's shape; 0: the default, one per 4
# triangles of each mesh, at most 1024), one partition is made and
# rendered on RANKS ranks by this build and, with BASELINE=old/ferry, by
# another build, interleaved in the same rounds so that a busy machine slows
# both alike. The part files do not depend on the build that renders them
# (ProxyBvh is built when a rank loads), so both render the same parts and
# must forward the same rays and write the same image (checked).
#
# Per configuration: rays forwarded per frame (and of them, found nothing
# where they were sent), frame time (the median over every frame but each
# run's first, over all rounds; a frame's time is its slowest rank's), CPU
# seconds per frame summed over ranks, and the proxy tree's bytes per rank
# (largest), from --stats. Counters are exact; times are this machine's.
#
#   BASELINE=/tmp/old/build/ferry bash bench/instanced_shapes.sh [FERRY]
#   SCENES="builtin:island builtin:landscape" SHAPES="4 16 64" PARTITION=ray-guided \
#     RANKS=8 SIZE=640x270 FRAMES=4 ROUNDS=2 OUT=dir bash bench/instanced_shapes.sh
set -euo pipefail
ferry=$(realpath "${1:-build/ferry}")
BASELINE=${BASELINE:+$(realpath "$BASELINE")}
SCENES=${SCENES:-builtin:island builtin:landscape}
SHAPES=${SHAPES:-4 16 64}
PARTITION=${PARTITION:-ray-guided}
RANKS=${RANKS:-8}
SIZE=${SIZE:-640x270}
FRAMES=${FRAMES:-4}
ROUNDS=${ROUNDS:-2}
if ((FRAMES < 2)); then
  echo "instanced_shapes: FRAMES must be 2 or more (the first frame, with set-up, is left out)" >&2
  exit 2
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
OUT=${OUT:-$work/out}
mkdir -p "$OUT"
export OMPI_MCA_mpi_yield_when_idle=1
root=()
[ "$(id -u)" = 0 ] && root=(--allow-run-as-root)

builds=(candidate)
[ -n "$BASELINE" ] && builds=(baseline candidate)
binary() { [ "$1" = baseline ] && echo "$BASELINE" || echo "$ferry"; }

for scene in $SCENES; do
  for k in $SHAPES; do
    name="${scene#builtin:}-$k"
    "$ferry" partition "$scene" --ranks "$RANKS" --partitioner "$PARTITION" \
      --instance-proxies "$k" -o "$work/$name" >/dev/null
  done
done

for round in $(seq 1 "$ROUNDS"); do
  for scene in $SCENES; do
    for k in $SHAPES; do
      name="${scene#builtin:}-$k"
      for build in "${builds[@]}"; do
        echo "round $round: $name, $build" >&2
        mpirun "${root[@]}" --oversubscribe --bind-to none -np "$RANKS" "$(binary "$build")" \
          render "$work/$name" --size "$SIZE" --spp 1 --frames "$FRAMES" --threads 1 \
          -o "$work/$name-$build.pfm" --stats "$OUT/$name-$build-$round.json" >/dev/null
      done
    done
  done
done

python3 - "$OUT" "$work" "$SCENES" "$SHAPES" "$ROUNDS" "${builds[*]}" <<'EOF'
import json, statistics, sys, os, filecmp
out, work, scenes, shapes, rounds, builds = sys.argv[1:7]
scenes, shapes, builds = scenes.split(), shapes.split(), builds.split()
rows = []
print(f"{'parts':<16} {'build':<10} {'forwards/frame':>15} {'found nothing':>14} {'frame s':>8} "
      f"{'CPU s/frame':>12} {'proxy MiB':>10}")
for scene in scenes:
    for k in shapes:
        name = f"{scene.replace('builtin:', '')}-{k}"
        if len(builds) == 2 and not filecmp.cmp(f"{work}/{name}-baseline.pfm",
                                                f"{work}/{name}-candidate.pfm", shallow=False):
            sys.exit(f"{name}: the two builds wrote different images")
        base = None
        for build in builds:
            frames, cpu, fwd, none, proxy = [], [], [], [], 0
            for r in range(1, int(rounds) + 1):
                d = json.load(open(f"{out}/{name}-{build}-{r}.json"))
                f = d["render"]["frames"]
                frames += [x["seconds"] for x in f[1:]]
                cpu += [x["cpu_seconds"] for x in f[1:]]
                e = d["render"]["total"]["exchange"]
                fwd.append(e["rays_forwarded"] / len(f))
                none.append(e["visits_without_hit"] / len(f))
                proxy = d["memory"]["max_proxy_bytes"] / 2**20
            if len(set(fwd)) != 1:
                sys.exit(f"{name} {build}: forwards differ between rounds: {fwd}")
            row = dict(parts=name, build=build, forwards=fwd[0], nothing=none[0],
                       frame=statistics.median(frames), cpu=statistics.median(cpu), proxy=proxy)
            rows.append(row)
            ratio = f"  (x{row['frame'] / base['frame']:.3f} frame time)" if base else ""
            print(f"{name:<16} {build:<10} {row['forwards']:>15,.0f} {row['nothing']:>14,.0f} "
                  f"{row['frame']:>8.3f} {row['cpu']:>12.3f} {row['proxy']:>10.2f}{ratio}")
            base = base or row
with open(f"{out}/instanced_shapes.csv", "w") as f:
    f.write("parts,build,forwards_per_frame,found_nothing_per_frame,frame_seconds,cpu_seconds_per_frame,proxy_mib\n")
    for r in rows:
        f.write(f"{r['parts']},{r['build']},{r['forwards']:.0f},{r['nothing']:.0f},{r['frame']:.4f},{r['cpu']:.4f},{r['proxy']:.2f}\n")
print(f"\nwrote {out}/instanced_shapes.csv")
EOF
