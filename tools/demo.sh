#!/usr/bin/env bash
# The demo deployment, run by `./snapnav demo` inside the private bus namespace:
#  1. bus health: probe frames of 100 B..1 MB from a publisher to a subscriber process,
#     recorded by lcm-logger and replayed by lcm-logplayer, checked byte for byte;
#  2. the simulated lab: sim (robot, omni camera, laser, odometry, ground truth) and
#     dead-reckoning run as separate processes in real time, lcm-logger records the bus;
#  3. log-report turns the recording into report.md, summary.json and PNG plots.
# Later issues add the navigation processes to step 2.
set -euo pipefail
BIN="$1"; shift
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="$ROOT/logs/demo-$(date -u +%Y%m%d-%H%M%S)"
COUNT=90
DURATION=30
SCENE=indoor13
while [ $# -gt 0 ]; do
  case "$1" in
    --out) OUT="$2"; shift 2 ;;
    --duration-s) DURATION="$2"; shift 2 ;;
    --scene) SCENE="$2"; shift 2 ;;
    *) echo "demo: unknown argument $1 (use --out DIR, --duration-s S, --scene NAME)" >&2; exit 2 ;;
  esac
done
SIZES=100,65536,1048576
mkdir -p "$OUT"
pids=()
cleanup() { for p in "${pids[@]:-}"; do kill "$p" 2>/dev/null || true; done; }
trap cleanup EXIT
step() { printf '\n[demo] %s\n' "$*"; }
wait_for_file() { for _ in $(seq 200); do [ -s "$1" ] && return 0; sleep 0.05; done; echo "demo: $1 did not appear" >&2; exit 1; }
SECONDS=0

step "private bus: $(ip -brief link show lo | tr -s ' '); route $(ip route show 224.0.0.0/4)"
step "1/3 bus health: $COUNT probe frames ($SIZES bytes) at 30 Hz, recorded and replayed"
PROBES="$OUT/probes.lcmlog"
lcm-logger -f -q -c BUS_CHECK "$PROBES" &
logger_pid=$!; pids+=($logger_pid)
"$BIN/bus-check" verify --count "$COUNT" --sizes "$SIZES" --timeout-s 15 --ready-file "$OUT/.live.ready" >"$OUT/probes-live.txt" 2>/dev/null &
verify_pid=$!; pids+=($verify_pid)
wait_for_file "$OUT/.live.ready"; sleep 0.5
"$BIN/bus-check" publish --count "$COUNT" --sizes "$SIZES" --rate-hz 30 2>/dev/null
live_rc=0; wait "$verify_pid" || live_rc=$?
sleep 0.3; kill -INT "$logger_pid"; wait "$logger_pid" || true
"$BIN/bus-check" verify --count "$COUNT" --sizes "$SIZES" --timeout-s 15 --ready-file "$OUT/.replay.ready" >"$OUT/probes-replay.txt" 2>/dev/null &
verify_pid=$!; pids+=($verify_pid)
wait_for_file "$OUT/.replay.ready"
lcm-logplayer -s 2 "$PROBES" >/dev/null
replay_rc=0; wait "$verify_pid" || replay_rc=$?
rm -f "$OUT"/.*.ready "$PROBES"
sed 's/^/  live:   /' "$OUT/probes-live.txt"; sed 's/^/  replay: /' "$OUT/probes-replay.txt"

step "2/3 simulated lab '$SCENE' for $DURATION s in real time: sim + dead-reckoning + homing, lcm-logger recording"
LOG="$OUT/run.lcmlog"
lcm-logger -f -q "$LOG" &
logger_pid=$!; pids+=($logger_pid)
"$BIN/dead-reckoning" 2>"$OUT/dead-reckoning.log" &
dr_pid=$!; pids+=($dr_pid)
"$BIN/homing" --home-first 2>"$OUT/homing.log" &
homing_pid=$!; pids+=($homing_pid)
sleep 0.5
sim_rc=0
"$BIN/sim" --scene "$SCENE" --duration-s "$DURATION" --mode realtime 2>&1 | tee "$OUT/sim.log" | grep --line-buffered -E "^sim: (t=|done)" | sed 's/^/  /' || sim_rc=$?
sleep 0.5
kill -INT "$dr_pid" "$homing_pid" "$logger_pid"; wait "$dr_pid" || true; wait "$homing_pid" || true; wait "$logger_pid" || true
sed 's/^/  /' "$OUT/dead-reckoning.log" | grep -E "published|ODOMETRY|POSE" || true
sed 's/^/  /' "$OUT/homing.log" | grep -E "^homing: (published|frames|home)|HOMING_VECTOR" || true

step "3/3 report"
report_rc=0
"$BIN/log-report" "$LOG" --out "$OUT" >/dev/null || report_rc=$?
verdict() { [ "$1" = 0 ] && echo PASS || echo FAIL; }
{
  echo "# snapnav demo report"
  echo
  echo "- Date (UTC): $(date -u +%Y-%m-%dT%H:%M:%SZ); run time ${SECONDS} s"
  echo "- Bus: UDP multicast in a private network namespace (loopback only, ttl=0)"
  echo "- Log: \`$LOG\` ($(stat -c %s "$LOG") bytes); replay it with \`./snapnav bus -- lcm-logplayer $LOG\`"
  echo
  echo "## 1. Bus health"
  echo
  echo "| step | result | details |"
  echo "|---|---|---|"
  echo "| live: publisher -> subscriber | $(verdict $live_rc) | $(sed 's/^bus-check verify: //' "$OUT/probes-live.txt") |"
  echo "| replay: lcm-logplayer -> subscriber | $(verdict $replay_rc) | $(sed 's/^bus-check verify: //' "$OUT/probes-replay.txt") |"
  echo
  echo "## 2. Simulated lab: scene $SCENE, $DURATION s"
  echo
  grep -E "^sim: done" "$OUT/sim.log" | sed 's/^/    /'
  echo
  sed -n '/^## Messages/,$p' "$OUT/report.md" | sed 's/^## /### /'
} >"$OUT/demo-report.md"
step "report: $OUT/demo-report.md"
cat "$OUT/demo-report.md"
[ "$live_rc" = 0 ] && [ "$replay_rc" = 0 ] && [ "$sim_rc" = 0 ] && [ "$report_rc" = 0 ]
