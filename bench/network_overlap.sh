#!/usr/bin/env bash
# Does the overlapped exchange hide the network? (issue 13, item 5)
#
# The island, partitioned once for 8 ranks with `best`, rendered on 8 ranks
# run as 4 hosts (network namespaces on this machine, Open MPI over TCP
# between them, bench/netns.sh) at 1280x720, 4 paths per pixel, with links
# unlimited and limited by tc to 1 Gbit/s, each with both exchanges
# (overlapped and the paper's bulk rounds), the configurations interleaved
# over ROUNDS rounds. Frame time is the median over all frames but each
# run's first (which also opens the TCP connections). Prints the frame time
# of each configuration and the 1 Gbit/s / unlimited ratio per exchange: a
# ratio near 1 means the network is hidden.
#
#   bench/network_overlap.sh [FERRY]        (as root: ip netns, tc)
#   SIZE=1280x720 SPP=4 FRAMES=3 ROUNDS=1 RATES="unlimited 1gbit" bench/network_overlap.sh
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
ferry=$(realpath "${1:-$here/build/ferry}")
SIZE=${SIZE:-1280x720}
SPP=${SPP:-4}
FRAMES=${FRAMES:-3}
ROUNDS=${ROUNDS:-1}
RATES=${RATES:-unlimited 1gbit}
EXCHANGES=${EXCHANGES:-overlapped bulk}
SCENE=${SCENE:-builtin:island}
[ "$(id -u)" -eq 0 ] || { echo "network_overlap: needs root (ip netns, tc)" >&2; exit 1; }
# shellcheck source=bench/netns.sh
NETNS_PREFIX=fno
source "$here/bench/netns.sh"
work=$(mktemp -d)
cleanup() { netns_down; rm -rf "$work"; }
trap cleanup EXIT
trap 'exit 130' INT TERM

echo "machine: $(nproc) cores, load before: $(cut -d' ' -f1-3 /proc/loadavg); $SCENE, $SIZE, $SPP spp," \
  "$FRAMES frames, 8 ranks on 4 hosts, best partition"
"$ferry" partition "$SCENE" --ranks 8 --partitioner best -o "$work/parts" -q
netns_up
declare -A throughput
for rate in $RATES; do
  netns_rate "$([ "$rate" = unlimited ] && echo "" || echo "$rate")"
  throughput[$rate]=$(netns_throughput)
done
for round in $(seq "$ROUNDS"); do
  for rate in $RATES; do
    netns_rate "$([ "$rate" = unlimited ] && echo "" || echo "$rate")"
    for exchange in $EXCHANGES; do
      tag="$rate-$exchange-$round"
      (netns_mpirun 8 "$ferry" render "$work/parts" --size "$SIZE" --spp "$SPP" --frames "$FRAMES" \
        --threads 1 --exchange "$exchange" -q -o "$work/$tag.pfm" --stats "$work/$tag.json") \
        > "$work/$tag.log" 2>&1 || { cat "$work/$tag.log"; exit 1; }
      echo "  $tag done"
    done
  done
done
for rate in $RATES; do echo "$rate ${throughput[$rate]}"; done > "$work/throughput.txt"

python3 - "$work" "$ROUNDS" "$RATES" "$EXCHANGES" <<'EOF'
import json, statistics, sys
work, rounds, rates, exchanges = sys.argv[1], int(sys.argv[2]), sys.argv[3].split(), sys.argv[4].split()
tput = dict(line.split() for line in open(f"{work}/throughput.txt"))
frame = {}
print("\nframe time, s (median over frames after the first; TCP throughput host 0 -> 1 measured at each rate)")
for rate in rates:
    for ex in exchanges:
        runs = [json.load(open(f"{work}/{rate}-{ex}-{r}.json")) for r in range(1, rounds + 1)]
        times = [f["seconds"] for s in runs for f in s["render"]["frames"][1:]] or \
                [f["seconds"] for s in runs for f in s["render"]["frames"]]
        frame[rate, ex] = statistics.median(times)
        t = runs[0]["render"]["total"]
        fr = len(runs[0]["render"]["frames"])
        st = t["stage_seconds"]
        print(f"  {rate:9} ({tput[rate]:>6} Mbit/s) {ex:10}: {frame[rate, ex]:7.2f} s/frame,"
              f" {t['exchange']['rays_forwarded'] / fr / 1e6:.2f} M rays forwarded/frame,"
              f" {t['exchange']['bytes_sent'] / fr / 2**20:.1f} MiB/frame;"
              f" stage s/frame summed over ranks: exchange {st['exchange'] / fr:.2f}, wait {st.get('wait', 0) / fr:.2f}")
print("\nslowest link against unlimited (1.00: the network is hidden)")
for ex in exchanges:
    print(f"  {ex:10}: " + ", ".join(f"{r} / {rates[0]} = {frame[r, ex] / frame[rates[0], ex]:.2f}"
                                     for r in rates[1:]))
if len(exchanges) > 1:
    print("\noverlapped against bulk at each rate (< 1: overlapped is faster)")
    for rate in rates:
        print(f"  {rate}: {frame[rate, exchanges[0]] / frame[rate, exchanges[1]]:.2f}")
EOF
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
