#!/usr/bin/env bash
# A small cluster on this machine: NETNS_HOSTS network namespaces ("hosts"),
# each with one veth into a bridge in the root namespace, Open MPI over TCP
# between them, and the link rate set by tc. Sourced by bench/paper-eval;
# also usable by hand:
#
#   source bench/netns.sh
#   netns_up                   # namespaces, veths, bridge, addresses (cleans leftovers first)
#   netns_rate 1gbit           # every host's link limited to 1 Gbit/s, both directions ("" = no limit)
#   (netns_mpirun 8 build/ferry render ...)  # 8 ranks on NETNS_HOSTS hosts (it execs: run it in a subshell)
#   netns_throughput           # TCP throughput host 0 -> host 1, Mbit/s (checks the limit bites)
#   netns_down                 # removes everything; safe to call twice
#
# Everything this creates carries the prefix $NETNS_PREFIX, so a run that was
# killed (even with SIGKILL, where no trap runs) is cleaned up by the next
# netns_up. Needs root (ip netns, tc). Nothing leaves this machine: the bridge
# has no uplink, and the addresses are in a private /24.
NETNS_PREFIX=${NETNS_PREFIX:-fev}
NETNS_HOSTS=${NETNS_HOSTS:-4}
NETNS_SUBNET=${NETNS_SUBNET:-10.213.77}
_netns_dir=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)

netns_name() { echo "$NETNS_PREFIX-h$1"; }
netns_ip() { echo "$NETNS_SUBNET.$(($1 + 1))"; }

# Removes every namespace, veth and bridge with our prefix (also leftovers of a killed run).
netns_down() {
  local ns link
  for ns in $(ip netns list 2>/dev/null | awk '{print $1}' | grep "^$NETNS_PREFIX-h" || true); do
    ip netns pids "$ns" 2>/dev/null | xargs -r kill -TERM 2>/dev/null || true
    ip netns del "$ns" 2>/dev/null || true
  done
  for link in $(ip -o link show 2>/dev/null | awk -F': ' '{print $2}' | cut -d@ -f1 | grep "^$NETNS_PREFIX-" || true); do
    ip link del "$link" 2>/dev/null || true
  done
  rm -f "/tmp/$NETNS_PREFIX-hosts-"* "/tmp/$NETNS_PREFIX-tput."*
}

netns_up() {
  netns_down
  local br="$NETNS_PREFIX-br" i ns
  ip link add "$br" type bridge
  ip addr add "$NETNS_SUBNET.254/24" dev "$br"
  ip link set "$br" up
  for ((i = 0; i < NETNS_HOSTS; i++)); do
    ns=$(netns_name "$i")
    ip netns add "$ns"
    ip link add "$NETNS_PREFIX-v$i" type veth peer name "$NETNS_PREFIX-p$i"
    ip link set "$NETNS_PREFIX-p$i" netns "$ns"
    ip -n "$ns" link set "$NETNS_PREFIX-p$i" name eth0
    ip -n "$ns" addr add "$(netns_ip "$i")/24" dev eth0
    ip -n "$ns" link set eth0 up
    ip -n "$ns" link set lo up
    ip link set "$NETNS_PREFIX-v$i" master "$br"
    ip link set "$NETNS_PREFIX-v$i" up
  done
}

# netns_rate RATE: each host's link carries at most RATE (tc rate syntax,
# e.g. 10gbit) in each direction: a token bucket on both ends of its veth
# (the namespace end shapes what the host sends, the bridge end what it
# receives). An empty RATE removes the limits.
netns_rate() {
  local rate=$1 i ns burst
  case "$rate" in
    *gbit) burst=$(( ${rate%gbit} * 256 ))kb ;;  # about 2 ms at the rate, at least 64 KiB (one GSO segment)
    *) burst=256kb ;;
  esac
  for ((i = 0; i < NETNS_HOSTS; i++)); do
    ns=$(netns_name "$i")
    tc -n "$ns" qdisc del dev eth0 root 2>/dev/null || true
    tc qdisc del dev "$NETNS_PREFIX-v$i" root 2>/dev/null || true
    [ -n "$rate" ] || continue
    tc -n "$ns" qdisc add dev eth0 root tbf rate "$rate" burst "$burst" latency 50ms
    tc qdisc add dev "$NETNS_PREFIX-v$i" root tbf rate "$rate" burst "$burst" latency 50ms
  done
}

# netns_mpirun NP COMMAND...: Open MPI with the ranks on the namespaces, NP /
# NETNS_HOSTS per host (filled in order): a hostfile of their addresses,
# daemons started by bench/netns-agent (ip netns exec, no ssh, each host with
# a host name of its own), TCP between hosts, shared memory within one.
# mpirun gives up if the daemons have not all reported within
# NETNS_STARTUP_TIMEOUT (30) seconds. Ends in `exec mpirun`, so run in the
# background its process id is mpirun's.
netns_mpirun() {
  local np=$1 i hostfile="/tmp/$NETNS_PREFIX-hosts-$1"
  shift
  for ((i = 0; i < NETNS_HOSTS; i++)); do
    echo "$(netns_ip "$i") slots=$(((np + NETNS_HOSTS - 1) / NETNS_HOSTS))"
  done > "$hostfile"
  NETNS_PREFIX=$NETNS_PREFIX NETNS_SUBNET=$NETNS_SUBNET \
  OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 \
    exec mpirun --hostfile "$hostfile" -np "$np" --map-by slot \
    --mca plm rsh --mca plm_rsh_agent "$_netns_dir/netns-agent" --mca plm_rsh_no_tree_spawn 1 \
    --mca btl "${NETNS_BTL:-tcp,vader,self}" --mca btl_vader_single_copy_mechanism none \
    --mca btl_tcp_if_include "$NETNS_SUBNET.0/24" \
    --mca oob_tcp_if_include "$NETNS_SUBNET.0/24" --mca mpi_yield_when_idle 1 \
    --mca orte_startup_timeout "${NETNS_STARTUP_TIMEOUT:-30}" \
    "$@"
}

# TCP throughput from host 0 to host 1 in Mbit/s: BYTES (default 64 MiB)
# through one connection, timed by the receiver.
netns_throughput() {
  local bytes=${1:-67108864} port=5301 out
  out=$(mktemp "/tmp/$NETNS_PREFIX-tput.XXXXXX")
  ip netns exec "$(netns_name 1)" python3 - "$port" > "$out" <<'PY' &
import socket, sys, time
s = socket.socket(); s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
s.bind(("0.0.0.0", int(sys.argv[1]))); s.listen(1); s.settimeout(60)
c, _ = s.accept(); t0 = None; n = 0
while True:
    b = c.recv(1 << 20)
    if t0 is None: t0 = time.perf_counter()
    if not b: break
    n += len(b)
print(f"{n * 8 / (time.perf_counter() - t0) / 1e6:.0f}")
PY
  local listener=$!
  sleep 0.5
  ip netns exec "$(netns_name 0)" python3 - "$(netns_ip 1)" "$port" "$bytes" <<'PY'
import socket, sys, time
for _ in range(50):
    try:
        s = socket.create_connection((sys.argv[1], int(sys.argv[2]))); break
    except OSError: time.sleep(0.1)
buf = b"\0" * (1 << 20); left = int(sys.argv[3])
while left > 0:
    s.sendall(buf[:min(left, len(buf))]); left -= len(buf)
s.close()
PY
  wait "$listener"
  cat "$out"
  rm -f "$out"
}
