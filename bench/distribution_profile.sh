#!/usr/bin/env bash
# Where the CPU time that distribution adds goes (issue 13): `perf record`
# of a 1-rank render and of N-rank renders of the same part directories, on
# the same cores, each run twice (with FRAMES frames and with 1 frame) so that
# the difference is the CPU time of FRAMES - 1 frames without set-up. Samples
# are grouped by what the code does (the proxy query, Embree, the alpha test
# and textures, shading, MPI, the kernel, copies and allocation, the rest of
# Ferry); the table gives CPU milliseconds per frame summed over ranks, and
# each group's share of what N ranks spend beyond the 1-rank frame.
#
#   bash bench/distribution_profile.sh [FERRY]       (default build/ferry; needs perf)
#   SCENE='builtin:island' PARTITION=best RANKS="4 8" SIZE=640x360 SPP=1 FRAMES=12 CORES=$(nproc) \
#     bash bench/distribution_profile.sh build/ferry
# The 1-rank run has --threads CORES, N ranks --threads max(1, CORES / N), as
# bench/distribution_cost.sh; Open MPI yields when idle (the same settings).
# Sample counts are statistics (999 Hz per thread): read differences of a
# few milliseconds per frame as noise.
set -euo pipefail
ferry=$(realpath "${1:-build/ferry}")
SCENE=${SCENE:-builtin:island}
PARTITION=${PARTITION:-best}
RANKS=${RANKS:-4 8}
SIZE=${SIZE:-640x360}
FRAMES=${FRAMES:-12}
CORES=${CORES:-$(nproc)}
SPP=${SPP:-1}
command -v perf > /dev/null || {
  echo "distribution_profile: needs perf (Debian: linux-perf)" >&2
  exit 1
}
[ "$FRAMES" -ge 2 ] || {
  echo "distribution_profile: FRAMES must be at least 2" >&2
  exit 1
}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none OMPI_MCA_mpi_yield_when_idle=1

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs);" \
  "load before: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "scene $SCENE, partition $PARTITION, $SIZE, $SPP spp, $FRAMES frames against 1, $CORES cores"

# profile N FRAMES: perf data of one render from N-rank parts.
profile() {
  local n=$1 frames=$2 threads=$((CORES / $1))
  [ "$threads" -ge 1 ] || threads=1
  perf record -q -F 999 -o "$work/perf-$n-$frames.data" -- \
    mpirun --oversubscribe --bind-to none -np "$n" "$ferry" render "$work/parts-$n" --size "$SIZE" \
    --spp "$SPP" --frames "$frames" --threads "$threads" -q -o "$work/out.pfm" > /dev/null 2>&1
}
for n in 1 $RANKS; do
  "$ferry" partition "$SCENE" --ranks "$n" --partitioner "$PARTITION" -o "$work/parts-$n" -q
  profile "$n" "$FRAMES"
  profile "$n" 1
done

python3 - "$work" "$FRAMES" $RANKS <<'EOF'
import collections, re, subprocess, sys
work, frames = sys.argv[1], int(sys.argv[2])
ranks = [int(r) for r in sys.argv[3:]]

# Groups, first match wins: (name, where the sample is: dso or symbol substring).
GROUPS = [
    ("proxy query", lambda dso, sym: "ProxyBvh::" in sym and "Builder" not in sym),
    ("Embree", lambda dso, sym: "embree" in dso),
    ("alpha test, textures", lambda dso, sym: any(s in sym for s in
        ("sampleAlpha", "alphaFilter", "Texture::", "bilinearTaps", "HdrImage::"))),
    ("kernel", lambda dso, sym: "kernel" in dso),
    ("MPI, sched_yield", lambda dso, sym: dso.startswith("mca_") or "libmpi" in dso
        or "open-pal" in dso or "open-rte" in dso or "sched_yield" in sym),
    ("copies, allocation", lambda dso, sym: "libc" in dso),
    ("forwarding decisions, queues", lambda dso, sym: any(s in sym for s in
        ("forwardBy", "pickOwner", "DistributedTraversal", "runSample", "decide", "keepToShade"))),
    ("shading, camera, lights", lambda dso, sym: any(s in sym for s in
        ("Shading", "reconstructSurface", "Light", "Bsdf", "bsdf", "Camera", "makeCameraPath",
         "WavefrontRenderer", "Distribution", "FrameBuffer", "Microfacet", "sample"))),
    ("other", lambda dso, sym: True),
]

def samples(path):
    out = subprocess.run(["perf", "report", "-i", path, "--no-children", "--sort", "dso,symbol",
                          "-g", "none", "-n", "--stdio"], capture_output=True, text=True).stdout
    groups = collections.Counter()
    for line in out.splitlines():
        m = re.match(r"\s+[\d.]+%\s+(\d+)\s+(\S+)\s+\[.\]\s+(.*)", line)
        if not m:
            continue
        count, dso, sym = int(m.group(1)), m.group(2), m.group(3).strip()
        groups[next(name for name, match in GROUPS if match(dso, sym))] += count
    return groups

def per_frame(n):  # CPU ms per frame (999 Hz sampling), frames 2..FRAMES
    a, b = samples(f"{work}/perf-{n}-{frames}.data"), samples(f"{work}/perf-{n}-1.data")
    return {name: (a[name] - b[name]) / (frames - 1) * 1000 / 999 for name, _ in GROUPS}

one = per_frame(1)
total1 = sum(one.values())
print(f"\nCPU ms per frame, summed over ranks (perf samples of {frames} frames minus 1 frame)")
header = f"  {'':30s} {'1 rank':>8s}"
rows = {n: per_frame(n) for n in ranks}
for n in ranks:
    header += f" {f'{n} ranks':>9s} {'extra':>7s} {'share':>6s}"
print(header)
for name, _ in GROUPS:
    line = f"  {name:30s} {one[name]:8.1f}"
    for n in ranks:
        extra = rows[n][name] - one[name]
        excess = sum(rows[n].values()) - total1
        line += f" {rows[n][name]:9.1f} {extra:+7.1f} {100 * extra / excess if excess else 0:5.0f}%"
    print(line)
line = f"  {'total':30s} {total1:8.1f}"
for n in ranks:
    total = sum(rows[n].values())
    line += f" {total:9.1f} {total - total1:+7.1f} {'':>6s}"
print(line)
for n in ranks:
    if total1 > 0:
        print(f"  {n} ranks: {sum(rows[n].values()) / total1:.2f}x the 1-rank CPU time per frame")
    else:  # a frame shorter than the sampling's noise (tiny SIZE or few FRAMES)
        print(f"  {n} ranks: no ratio: the 1-rank CPU time per frame measured {total1:.1f} ms"
              " (too few samples: more FRAMES or a larger SIZE)")
EOF
