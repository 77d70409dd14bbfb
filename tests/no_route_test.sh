#!/usr/bin/env bash
# A process that cannot create LCM (network namespace without a multicast
# route) must say what is wrong and print the commands that fix it.
set -uo pipefail
BIN="$1"
ns=(-n)
[ "$(id -u)" = 0 ] || ns=(-r -n)
out="$(unshare "${ns[@]}" -- "$BIN/dead-reckoning" 2>&1)"
rc=$?
echo "$out"
[ "$rc" != 0 ] || { echo "FAIL: exit status 0 without a bus"; exit 1; }
for want in "cannot create LCM" "ip route add 224.0.0.0/4 dev lo" "./snapnav bus --"; do
  grep -qF -- "$want" <<<"$out" || { echo "FAIL: message lacks '$want'"; exit 1; }
done
echo "PASS"
