#!/usr/bin/env bash
# Runs a command inside a private network namespace with only loopback and a multicast route, so
# that LCM's udpm traffic never leaves this machine and parallel runs do not collide.
# Usage: tests/integration/netns_run.sh COMMAND [ARGS...]
# Needs root (or CAP_SYS_ADMIN + CAP_NET_ADMIN); the namespace is removed on exit.
set -euo pipefail
if [ $# -eq 0 ]; then echo "usage: $0 COMMAND [ARGS...]" >&2; exit 2; fi
ns="overstep-test-$$-${RANDOM}"
if ! ip netns add "$ns" 2>/tmp/"$ns".err; then
  echo "netns_run: cannot create network namespace ($(head -1 /tmp/"$ns".err)); run as root" >&2
  rm -f /tmp/"$ns".err
  exit 1
fi
rm -f /tmp/"$ns".err
trap 'ip netns del "$ns" 2>/dev/null || true' EXIT
ip netns exec "$ns" ip link set lo up
ip netns exec "$ns" ip route add 224.0.0.0/4 dev lo
export OVERSTEP_NETNS="$ns"
export LCM_DEFAULT_URL="udpm://239.255.76.67:7667?ttl=0"
ip netns exec "$ns" "$@"
