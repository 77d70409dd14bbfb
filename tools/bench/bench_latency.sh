#!/usr/bin/env bash
# End-to-end latency, run by `./snapnav bench latency` inside the private bus namespace: sim in real
# time, homing (HOG, home = first frame), placecells (localizing in a memory explored first) and,
# when it is built, fused-slam run as separate processes with latency-probe beside them. The probe
# pairs every HOMING_VECTOR, POSE_PLACE_CELLS and POSE_EKF (the fused pose of a place-cell fix)
# with the omni frame of the same utime and times it by its own receive times. --runs runs of
# --duration-s each; summary.json holds the median over the runs of each figure, bench.md the table.
set -euo pipefail
BIN="$1"; shift
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
OUT="$ROOT/logs/bench-latency"
RUNS=3
DURATION=20
SCENE=indoor13
FRESH=0
while [ $# -gt 0 ]; do
  case "$1" in
    --out) OUT="$2"; shift 2 ;;
    --runs) RUNS="$2"; shift 2 ;;
    --duration-s) DURATION="$2"; shift 2 ;;
    --scene) SCENE="$2"; shift 2 ;;
    --fresh-memory) FRESH=1; shift ;;
    *) echo "bench latency: unknown argument $1 (--out DIR, --runs N, --duration-s S, --scene NAME, --fresh-memory)" >&2; exit 2 ;;
  esac
done
mkdir -p "$OUT"
rm -f "$OUT"/run-*.json "$OUT"/run-*.csv "$OUT/summary.json" "$OUT/bench.md"
pids=()
cleanup() { for p in "${pids[@]:-}"; do kill "$p" 2>/dev/null || true; done; rm -f "$OUT/.probe.ready"; }
trap cleanup EXIT
wait_for_file() { for _ in $(seq 200); do [ -s "$1" ] && return 0; sleep 0.05; done; echo "bench latency: $1 did not appear" >&2; exit 1; }

# The place-cell memory: explored once per scene from a lockstep simulator log (kept for later runs).
MEMORY="$OUT/$SCENE.placecells"
if [ "$FRESH" = 1 ] || [ ! -s "$MEMORY" ]; then
  echo "bench latency: exploring '$SCENE' for the place-cell memory (30 s of simulated route, lockstep)"
  rm -f "$MEMORY"
  "$BIN/sim" --scene "$SCENE" --duration-s 30 --mode lockstep --lcm-url "file://$OUT/explore.lcmlog?mode=w" \
    >"$OUT/explore-sim.log" 2>&1
  # placecells reads the log; its matches have nowhere to go on a read-only file:// bus (counted
  # as handler errors in explore.log), the cells are stored all the same.
  "$BIN/placecells" --mode explore --memory "$MEMORY" --lcm-url "file://$OUT/explore.lcmlog?speed=0" \
    >"$OUT/explore.log" 2>&1
  rm -f "$OUT/explore.lcmlog"
  grep -E "^placecells: explore" "$OUT/explore.log" | sed 's/^/  /'
fi
[ -s "$MEMORY" ] || { echo "bench latency: no place-cell memory $MEMORY (see $OUT/explore.log)" >&2; exit 1; }

FUSED=0
[ -x "$BIN/fused-slam" ] && FUSED=1
# The place cells localize without their distance filter: global fixes, as fused-slam takes them
# (config/fused_slam.ini) and as the demo runs them.
PLACECELLS_INI="$OUT/placecells_global.ini"
sed 's/^enabled = true/enabled = false/' "$ROOT/config/placecells.ini" >"$PLACECELLS_INI"
OUTPUTS="HOMING_VECTOR,POSE_PLACE_CELLS,POSE_EKF@POSE_PLACE_CELLS"
echo "bench latency: $RUNS runs of $DURATION s: sim (real time) -> homing, placecells$([ $FUSED = 1 ] && echo ', fused-slam') -> latency-probe"
[ $FUSED = 1 ] || echo "bench latency: fused-slam is not built: POSE_EKF gets no messages (the probe listens for it all the same)"
for run in $(seq "$RUNS"); do
  rm -f "$OUT/.probe.ready"
  pids=()
  "$BIN/latency-probe" --outputs "$OUTPUTS" --ready-file "$OUT/.probe.ready" --out "$OUT/run-$run.json" \
    --csv "$OUT/run-$run.csv" >"$OUT/run-$run.txt" 2>"$OUT/probe-$run.log" &
  probe_pid=$!; pids+=("$probe_pid")
  "$BIN/homing" --home-first 2>"$OUT/homing-$run.log" &
  pids+=($!)
  "$BIN/placecells" --config "$PLACECELLS_INI" --memory "$MEMORY" 2>"$OUT/placecells-$run.log" &
  pids+=($!)
  if [ $FUSED = 1 ]; then
    "$BIN/fused-slam" 2>"$OUT/fused-slam-$run.log" &
    pids+=($!)
  fi
  wait_for_file "$OUT/.probe.ready"
  sleep 1.5  # the memory loads, the others subscribe
  "$BIN/sim" --scene "$SCENE" --duration-s "$DURATION" --mode realtime --seed "$((run + 10))" >"$OUT/sim-$run.log" 2>&1
  sleep 1  # the last results
  kill -INT "${pids[@]:1}" 2>/dev/null || true
  for p in "${pids[@]:1}"; do wait "$p" || true; done
  kill -INT "$probe_pid"; wait "$probe_pid" || true
  echo "  run $run:"; sed 's/^/    /' "$OUT/run-$run.txt"
done
pids=()
python3 "$ROOT/tools/bench/bench_summary.py" runs "$OUT" --title "End-to-end latency (omni frame -> output), $RUNS runs of $DURATION s, scene $SCENE" \
  --note "fused_slam_built=$FUSED"
