#!/usr/bin/env bash
# Several simulated robots on one bus (`./snapnav robots`, inside the private bus namespace):
# config/deploy/robots.deploy with N robots (robot.deploy once per channel prefix R1_, R2_, ...: sim
# in real time on the scene's route, dead reckoning, laser SLAM, place cells, homing), one recorder
# and one viewer for all. Then: log-report of the whole log with every process's counts
# (delivery.csv), one report per robot (its channels only: ATE against its own ground truth), and
# the checks (tools/deploy/run_checks.py robots): no cross-talk, nothing dropped, every sim at its
# rates in real time, CPU and RSS per process. Exit 0 when every check passed.
set -euo pipefail
BIN="$1"; shift
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
DEPLOY="$ROOT/config/deploy/robots.deploy"
OUT="$ROOT/logs/robots-$(date -u +%Y%m%d-%H%M%S)"
COUNT=3
DURATION=60
SCENE=indoor13
EXPLORED=""
FRAME_ENCODING=jpeg
FACTOR=1
KEEP_LOG=1
usage() {
  cat <<'EOF'
usage: ./snapnav robots [--count N] [--duration-s S] [--out DIR] [--explored DIR] [--scene NAME]
                        [--raw-frames] [--realtime-factor F] [--drop-log]
  --count N         robots on the bus, prefixes R1_ .. RN_ (default 3)
  --duration-s S    seconds each robot's sim runs in real time (default 60)
  --out DIR         output folder (default logs/robots-<UTC time>)
  --explored DIR    reuse the place-cell memory and grid of an earlier run's folder (same scene)
  --scene NAME      config/scenes/NAME.scene (default indoor13)
  --raw-frames      raw 1 MB frames instead of JPEG ones
  --realtime-factor F  simulated seconds per wall second (default 1: real time); 0.5: the same run, every
                    rate and check in simulated time, at half the CPU (the ctest on shared cores); the
                    capacity at 1 is ./snapnav bench robots
  --drop-log        delete run.lcmlog after the report
Writes robots.md and robots.json (the checks), report.md / summary.json / delivery.csv (the whole
log), R1_/report.md ... (each robot), processes.csv (RSS and CPU every 2 s), viewer/ (all robots).
EOF
}
while [ $# -gt 0 ]; do
  case "$1" in
    --count) COUNT="$2"; shift 2 ;;
    --duration-s) DURATION="$2"; shift 2 ;;
    --out) OUT="$2"; shift 2 ;;
    --explored) EXPLORED="$(cd "$2" && pwd)"; shift 2 ;;
    --scene) SCENE="$2"; shift 2 ;;
    --raw-frames) FRAME_ENCODING=rgb8; shift ;;
    --realtime-factor) FACTOR="$2"; shift 2 ;;
    --drop-log) KEEP_LOG=0; shift ;;
    -h | --help) usage; exit 0 ;;
    *) echo "robots: unknown argument $1" >&2; usage >&2; exit 2 ;;
  esac
done
[[ "$COUNT" =~ ^[1-9][0-9]*$ ]] || { echo "robots: --count must be a positive integer, got '$COUNT'" >&2; exit 2; }
mkdir -p "$OUT"
OUT="$(cd "$OUT" && pwd)"
PREFIXES=$(seq -s, -f 'R%g_' 1 "$COUNT")
pids=()
cleanup() { for p in "${pids[@]:-}"; do [ -n "$p" ] && kill "$p" 2>/dev/null || true; done; }
trap cleanup EXIT
quiet() { (trap '' INT; exec "$@"); }
SECONDS=0

EXPLORE_OUT="$OUT"
if [ -n "$EXPLORED" ]; then
  EXPLORE_OUT="$EXPLORED"
  [ -s "$EXPLORED/placecells.mem" ] && [ -s "$EXPLORED/camera_mask.png" ] ||
    { echo "robots: --explored $EXPLORED: no placecells.mem or camera_mask.png there" >&2; exit 2; }
else
  echo "robots: the place-cell memory of '$SCENE' (launch robots.deploy --group explore)"
  rm -f "$OUT/placecells.mem" "$OUT/camera_mask.png"  # an earlier run's memory would be extended, not made afresh
  "$BIN/launch" "$DEPLOY" --group explore --out "$OUT" --status-every-s 0 "scene=$SCENE" >"$OUT/explore.log" 2>&1 ||
    { echo "robots: exploring failed (see $OUT/explore.log)" >&2; exit 1; }
fi

pace="in real time"
[ "$FACTOR" = 1 ] || pace="at $FACTOR x real time"
echo "robots: $COUNT robots ($PREFIXES) for $DURATION s $pace, one recorder, one viewer; bus $LCM_DEFAULT_URL"
STATUS="$OUT/launch.status"
rm -rf "$OUT/processes" "$OUT/robots" "$OUT/run.lcmlog" "$STATUS"
python3 "$ROOT/tools/deploy/process_stats.py" sample --out "$OUT/processes.csv" --interval-s 2 --status-file "$STATUS" &
sampler_pid=$!; pids+=($sampler_pid)
"$BIN/launch" "$DEPLOY" --group lab --out "$OUT" --status-every-s 0 --status-file "$STATUS" \
  "robots=$PREFIXES" "scene=$SCENE" "duration_s=$DURATION" "realtime_factor=$FACTOR" "frame_encoding=$FRAME_ENCODING" \
  "memory=$EXPLORE_OUT/placecells.mem" "mask=$EXPLORE_OUT/camera_mask.png" "home_image=$EXPLORE_OUT/grid/images/6_6.png" >"$OUT/launch.log" 2>&1 &
launch_pid=$!; pids+=($launch_pid)
# The run ends when every sim has ended (each runs duration_s from its own start).
sims_done() {
  awk -F'\t' '$1 ~ /\.sim$/ { n++; if ($2 == "exited" || $2 == "failed" || $2 == "stopped") d++ }
              END { exit !(n > 0 && n == d) }' "$STATUS" 2>/dev/null
}
while kill -0 "$launch_pid" 2>/dev/null && ! sims_done; do sleep 0.5; done
sleep 1  # the last messages
kill -INT "$launch_pid" 2>/dev/null || true
lab_rc=0; wait "$launch_pid" || lab_rc=$?
kill -INT "$sampler_pid" 2>/dev/null || true; wait "$sampler_pid" || true
t_lab=$SECONDS
grep -E "^launch: (error|.*FAILED)" "$OUT/launch.log" || true

LOG="$OUT/run.lcmlog"
dirs="$OUT/processes"
for p in ${PREFIXES//,/ }; do dirs="$dirs,$OUT/robots/$p"; done
report_rc=0
"$BIN/log-report" "$LOG" --out "$OUT" --process-logs "$dirs" >/dev/null 2>"$OUT/log-report.log" || report_rc=$?
for p in ${PREFIXES//,/ }; do
  "$BIN/log-report" "$LOG" --channel-prefix "$p" --out "$OUT/$p" --process-logs "$OUT/robots/$p" >/dev/null 2>>"$OUT/log-report.log" ||
    report_rc=$?
done
check_rc=0
python3 "$ROOT/tools/deploy/run_checks.py" robots "$OUT" --prefixes "$PREFIXES" --duration-s "$DURATION" --realtime-factor "$FACTOR" >/dev/null || check_rc=$?
{
  echo
  echo "Each robot's estimators against its own ground truth (ATE RMSE, m; \`$(basename "$OUT")/R*_/report.md\`):"
  echo
  echo "| robot | dead reckoning | laser SLAM | place cells | homing vectors (valid) |"
  echo "|---|---|---|---|---|"
  for p in ${PREFIXES//,/ }; do
    python3 - "$OUT/$p/summary.json" "$p" <<'PY'
import json, sys
s, p = json.load(open(sys.argv[1])), sys.argv[2].lower()
g = lambda k: s.get(p + k, "-")
print(f"| {sys.argv[2]} | {g('pose_dead_reckoning_ate_rmse_m')} | {g('pose_laser_slam_ate_rmse_m')} | "
      f"{g('pose_place_cells_ate_rmse_m')} | {g('homing_vector_valid')} |")
PY
  done
  echo
  echo "Log: $(stat -c %s "$LOG" 2>/dev/null || echo 0) bytes for $DURATION s of $COUNT robots ($pace); run time ${t_lab} s."
  [ -s "$OUT/viewer/viewer-final.png" ] && printf '\n![every robot in one viewer](viewer/viewer-final.png)\n'
} >>"$OUT/robots.md"
[ "$KEEP_LOG" = 1 ] || rm -f "$LOG"
cat "$OUT/robots.md"
echo "robots: $OUT/robots.md"
[ "$lab_rc" = 0 ] && [ "$report_rc" = 0 ] && [ "$check_rc" = 0 ]
