#!/usr/bin/env bash
# Run inside the private bus (./snapnav bus --). The launcher runs tests/launch/restart.deploy:
# lcm-logger, dead-reckoning, laser-slam and sim (real time, until stopped). dead-reckoning is
# killed with SIGKILL; the launcher must restart it while the others keep their pids, then SIGINT
# must stop everything within the grace time (5 s), exit 0, and the log must hold every message
# sim published.
set -euo pipefail
BIN="$1"; DEPLOY="$2"; OUT="$3"
rm -rf "$OUT"; mkdir -p "$OUT"
STATUS="$OUT/status"
fail() { echo "FAIL: $*" >&2; echo "--- launcher stderr:" >&2; tail -40 "$OUT/launch.err" >&2 || true; exit 1; }
field() { awk -F'\t' -v n="$1" -v c="$2" '$1==n { print $c }' "$STATUS" 2>/dev/null; }  # 2 state 3 pid 4 runs
wait_until() {  # SECONDS CONDITION...
  local deadline=$((SECONDS + $1)); shift
  until "$@"; do [ $SECONDS -lt $deadline ] || return 1; sleep 0.1; done
}
"$BIN/launch" "$DEPLOY" --out "$OUT" --status-file "$STATUS" --status-every-s 2 >"$OUT/launch.out" 2>"$OUT/launch.err" &
launcher=$!
trap 'kill -INT $launcher 2>/dev/null || true' EXIT
running() { [ "$(field "$1" 2)" = running ]; }
wait_until 60 running sim || fail "sim did not start"
sleep 3
declare -A before
for p in lcm-logger laser-slam sim; do before[$p]=$(field $p 3); done
victim=$(field dead-reckoning 3)
[ -n "$victim" ] && [ "$victim" != 0 ] || fail "no dead-reckoning pid"
echo "killing dead-reckoning (pid $victim) with SIGKILL"
kill -9 "$victim"
restarted() { [ "$(field dead-reckoning 4)" = 2 ] && running dead-reckoning; }
wait_until 15 restarted || fail "dead-reckoning was not restarted"
[ "$(field dead-reckoning 3)" != "$victim" ] || fail "dead-reckoning has its old pid"
for p in lcm-logger laser-slam sim; do
  [ "$(field $p 3)" = "${before[$p]}" ] && running $p || fail "$p was disturbed (pid ${before[$p]} -> $(field $p 3), $(field $p 2))"
  [ "$(field $p 4)" = 1 ] || fail "$p was restarted"
done
echo "dead-reckoning restarted (pid $(field dead-reckoning 3)); lcm-logger, laser-slam and sim kept their pids"
sleep 3
pids=$(awk -F'\t' '!/^#/ && $3 != 0 { print $3 }' "$STATUS")
echo "SIGINT to the launcher"
start=$(date +%s.%N)
kill -INT "$launcher"
rc=0; wait "$launcher" || rc=$?
trap - EXIT
took=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.2f", b - a }')
echo "launcher exited with $rc after $took s"
[ "$rc" = 0 ] || fail "the launcher exited with $rc"
awk -v t="$took" 'BEGIN { exit !(t < 5) }' || fail "stopping took $took s, more than the grace time of 5 s"
for p in $pids; do ! kill -0 "$p" 2>/dev/null || fail "pid $p still runs"; done
[ -z "$(awk -F'\t' '!/^#/ && $2 != "stopped"' "$STATUS")" ] || fail "not all stopped: $(cat "$STATUS")"
grep -q "launch: dead-reckoning: ended (killed by SIGKILL)" "$OUT/launch.err" || fail "no report of the kill"
# Nothing lost: every message sim published is in the log; the restarted dead-reckoning worked.
"$BIN/log-report" "$OUT/run.lcmlog" --out "$OUT/report" --process-logs "$OUT/processes" >/dev/null
python3 - "$OUT/report/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
bad = []
for ch in ("omni_frame", "laser_scan", "odometry", "pose_ground_truth"):
    p, r = s.get("delivery_%s_published" % ch), s.get("delivery_%s_recorded" % ch)
    print("sim %s: published %s, recorded %s" % (ch.upper(), p, r))
    if not p or p != r: bad.append(ch)
if s.get("process_dead-reckoning_runs") != 2: bad.append("dead-reckoning runs %s" % s.get("process_dead-reckoning_runs"))
if s.get("process_sim_runs") != 1 or s.get("process_laser-slam_runs") != 1: bad.append("others restarted")
if s.get("delivery_pose_laser_slam_published") != s.get("delivery_laser_scan_published"):
    bad.append("laser-slam missed scans: %s poses for %s scans" % (s.get("delivery_pose_laser_slam_published"), s.get("delivery_laser_scan_published")))
if bad: sys.exit("FAIL: " + ", ".join(bad))
PY
second=$(grep -E "^dead-reckoning: published [0-9]+ poses" "$OUT/processes/dead-reckoning.log" | tail -1 | awk '{ print $3 }')
[ "${second:-0}" -gt 0 ] || fail "the restarted dead-reckoning published nothing"
echo "the restarted dead-reckoning published $second poses"
rm -f "$OUT/run.lcmlog"
echo PASS
