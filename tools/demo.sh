#!/usr/bin/env bash
# The demo deployment, run by `./snapnav demo` inside the private bus namespace.
# For now: a publisher and a subscriber process on the private UDP multicast bus,
# recorded by lcm-logger into logs/, then replayed with lcm-logplayer to a second
# subscriber; a report is written beside the log. Later issues grow this into
# the simulated lab deployment.
set -euo pipefail
BIN="$1"; shift
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="$ROOT/logs/demo-$(date -u +%Y%m%d-%H%M%S)"
COUNT=150
while [ $# -gt 0 ]; do
  case "$1" in
    --out) OUT="$2"; shift 2 ;;
    --count) COUNT="$2"; shift 2 ;;
    *) echo "demo: unknown argument $1 (use --out DIR, --count N)" >&2; exit 2 ;;
  esac
done
SIZES=100,65536,1048576
mkdir -p "$OUT"
LOG="$OUT/run.lcmlog"
pids=()
cleanup() { for p in "${pids[@]:-}"; do kill "$p" 2>/dev/null || true; done; }
trap cleanup EXIT
step() { printf '\n[demo] %s\n' "$*"; }
wait_for_file() { for _ in $(seq 200); do [ -s "$1" ] && return 0; sleep 0.05; done; echo "demo: $1 did not appear" >&2; exit 1; }

SECONDS=0
step "private bus: $(ip -brief link show lo | tr -s ' '); route $(ip route show 224.0.0.0/4)"
step "starting lcm-logger -> $LOG"
lcm-logger -f -q "$LOG" &
pids+=($!)
logger_pid=$!
step "starting subscriber (bus-check verify, $COUNT probes)"
"$BIN/bus-check" verify --count "$COUNT" --sizes "$SIZES" --timeout-s 15 --ready-file "$OUT/.live.ready" >"$OUT/live.txt" 2>"$OUT/live.err" &
verify_pid=$!
pids+=($verify_pid)
wait_for_file "$OUT/.live.ready"
sleep 0.5
step "publisher: $COUNT omni frames of $SIZES bytes at 30 Hz"
"$BIN/bus-check" publish --count "$COUNT" --sizes "$SIZES" --rate-hz 30 2>&1 | sed 's/^/  /'
live_rc=0
wait "$verify_pid" || live_rc=$?
sed 's/^/  /' "$OUT/live.txt"
sleep 0.3
kill -INT "$logger_pid"; wait "$logger_pid" || true

step "replay with lcm-logplayer to a fresh subscriber"
"$BIN/bus-check" verify --count "$COUNT" --sizes "$SIZES" --timeout-s 15 --ready-file "$OUT/.replay.ready" >"$OUT/replay.txt" 2>"$OUT/replay.err" &
verify_pid=$!
pids+=($verify_pid)
wait_for_file "$OUT/.replay.ready"
lcm-logplayer "$LOG"
replay_rc=0
wait "$verify_pid" || replay_rc=$?
sed 's/^/  /' "$OUT/replay.txt"
rm -f "$OUT"/.*.ready

elapsed=$SECONDS
verdict() { [ "$1" = 0 ] && echo PASS || echo FAIL; }
cat >"$OUT/report.md" <<REPORT
# snapnav demo report

- Date (UTC): $(date -u +%Y-%m-%dT%H:%M:%SZ)
- Bus: UDP multicast on a private network namespace (loopback only, ttl=0)
- Log: \`$LOG\` ($(stat -c %s "$LOG") bytes)
- Run time: ${elapsed} s

| step | result | details |
|---|---|---|
| live: publisher -> subscriber | $(verdict $live_rc) | $(cat "$OUT/live.txt" | sed 's/^bus-check verify: //') |
| replay: lcm-logplayer -> subscriber | $(verdict $replay_rc) | $(cat "$OUT/replay.txt" | sed 's/^bus-check verify: //') |

Replay it yourself: \`./snapnav bus -- lcm-logplayer $LOG\` (real time), or inspect it with
\`./snapnav spy\` while it plays.
REPORT
step "report: $OUT/report.md"
cat "$OUT/report.md"
[ "$live_rc" = 0 ] && [ "$replay_rc" = 0 ]
