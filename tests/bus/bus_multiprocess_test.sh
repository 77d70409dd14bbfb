#!/usr/bin/env bash
# Multi-process bus test, run inside `./snapnav bus --` (a private network namespace):
#  1. bus-check publish sends N probes of mixed sizes up to 1 MB over UDP multicast;
#     bus-check verify (another process) and lcm-logger receive them;
#  2. lcm-logplayer replays the log to a fresh verifier;
#  3. a verifier reads the log directly through file://LOG?speed=0.
# Each verifier exits 0 only if all N arrived byte-identical and in order.
set -euo pipefail
BIN="$1"
N=90
SIZES=100,1048576,65536,4096,524288,1000
TMP="$(mktemp -d)"
pids=()
cleanup() {
  for p in "${pids[@]:-}"; do kill "$p" 2>/dev/null || true; done
  rm -rf "$TMP"
}
trap cleanup EXIT

wait_for_file() {
  for _ in $(seq 200); do [ -s "$1" ] && return 0; sleep 0.05; done
  echo "FAIL: $1 did not appear" >&2
  exit 1
}

echo "== live: publisher -> verifier + lcm-logger (UDP multicast, private namespace)"
"$BIN/bus-check" verify --count $N --sizes $SIZES --timeout-s 15 --ready-file "$TMP/live.ready" >"$TMP/live.out" &
verify_pid=$!
pids+=("$verify_pid")
lcm-logger -f -c 'BUS_CHECK' --flush-interval=50 "$TMP/probes.lcmlog" >"$TMP/logger.out" 2>&1 &
logger_pid=$!
pids+=("$logger_pid")
wait_for_file "$TMP/live.ready"
sleep 0.5  # lcm-logger prints nothing when subscribed; give it a moment
"$BIN/bus-check" publish --count $N --sizes $SIZES --rate-hz 30
verify_rc=0
wait "$verify_pid" || verify_rc=$?
cat "$TMP/live.out"
sleep 0.3
kill -INT "$logger_pid"
wait "$logger_pid" || true
[ "$verify_rc" = 0 ] || { echo "FAIL: live verifier"; exit 1; }

echo "== the log itself, read with file://LOG?speed=0"
"$BIN/bus-check" verify --count $N --sizes $SIZES --timeout-s 5 \
  --lcm-url "file://$TMP/probes.lcmlog?speed=0" >"$TMP/file.out" || { cat "$TMP/file.out"; echo "FAIL: log content"; exit 1; }
cat "$TMP/file.out"

echo "== replay: lcm-logplayer -> verifier"
"$BIN/bus-check" verify --count $N --sizes $SIZES --timeout-s 15 --ready-file "$TMP/replay.ready" >"$TMP/replay.out" &
verify_pid=$!
pids+=("$verify_pid")
wait_for_file "$TMP/replay.ready"
lcm-logplayer -s 2 "$TMP/probes.lcmlog"
verify_rc=0
wait "$verify_pid" || verify_rc=$?
cat "$TMP/replay.out"
[ "$verify_rc" = 0 ] || { echo "FAIL: replay verifier"; exit 1; }
echo "PASS: $N probes ($SIZES bytes) live, in the log, and replayed: byte-identical and in order"
