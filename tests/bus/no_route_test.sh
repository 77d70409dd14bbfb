#!/usr/bin/env bash
# A process that cannot create LCM must say what is wrong and print the commands that fix it, from
# the facts of the network namespace it runs in (read from the kernel: /sys/class/net shows the
# host's loopback inside a namespace), and a malformed URL must be named as such, not blamed on
# the route (ctest bus_no_multicast_route_is_explained).
#   no_route_test.sh BIN_DIR
set -uo pipefail
BIN="$1"
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
ns=(-n)
[ "$(id -u)" = 0 ] || ns=(-r -n)
fail() { echo "FAIL: $*"; exit 1; }
check() {  # LABEL OUTPUT STATUS WANTED... -- UNWANTED...
  local label="$1" out="$2" rc="$3"; shift 3
  echo "--- $label (exit $rc):"; echo "$out"
  [ "$rc" != 0 ] || fail "$label: exit status 0 without a bus"
  local unwanted=0 s
  for s in "$@"; do
    if [ "$s" = -- ]; then unwanted=1; continue; fi
    if [ "$unwanted" = 0 ]; then
      grep -qF -- "$s" <<<"$out" || fail "$label: the message lacks '$s'"
    else
      ! grep -qF -- "$s" <<<"$out" || fail "$label: the message says '$s'"
    fi
  done
}

# A new namespace: loopback down, no route.
out="$(env -u LCM_DEFAULT_URL unshare "${ns[@]}" -- "$BIN/dead-reckoning" 2>&1)"; rc=$?
check "new namespace" "$out" "$rc" "cannot create LCM" "loopback is DOWN" "has NO route" \
  "ip route add 224.0.0.0/4 dev lo" "./snapnav bus --"

# Loopback up with multicast, still no route: the facts are this namespace's, not the host's.
out="$(env -u LCM_DEFAULT_URL unshare "${ns[@]}" -- bash -c \
  'ip link set lo up multicast on && exec "$1/dead-reckoning"' probe "$BIN" 2>&1)"; rc=$?
check "loopback up, no route" "$out" "$rc" "loopback is up with multicast" "has NO route" \
  "ip route add 224.0.0.0/4 dev lo" -- "WITHOUT multicast" "DOWN"

# On the private bus (route and multicast in place) a bad port is a bad port.
out="$("$ROOT/snapnav" bus -- "$BIN/dead-reckoning" --lcm-url 'udpm://239.255.76.67:notaport' 2>&1)"; rc=$?
check "bad port on the private bus" "$out" "$rc" "The URL is malformed: the port 'notaport' is not a port number" \
  -- "WITHOUT multicast" "NO route" "ip route add"

# A group that is not multicast, and an unknown provider.
out="$("$ROOT/snapnav" bus -- "$BIN/dead-reckoning" --lcm-url 'udpm://10.1.2.3:7667' 2>&1)"; rc=$?
check "unicast group" "$out" "$rc" "the group 10.1.2.3 is not a multicast address" -- "NO route"
out="$("$ROOT/snapnav" bus -- "$BIN/dead-reckoning" --lcm-url 'udmp://239.255.76.67:7667' 2>&1)"; rc=$?
check "unknown provider" "$out" "$rc" "unknown provider 'udmp' (did you mean 'udpm'?)"
echo "PASS"
