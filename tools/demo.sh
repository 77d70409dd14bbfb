#!/usr/bin/env bash
# The demo, run by `./snapnav demo` inside the private bus namespace:
#  1. bus health: probe frames of 100 B..1 MB from a publisher to a subscriber process,
#     recorded by lcm-logger and replayed by lcm-logplayer, checked byte for byte;
#  2. the place-cell memory: `launch config/deploy/demo.deploy --group explore` (gridgen renders
#     the scene's grid, calibrate-mirror finds the mirror and the mask of the robot's own parts in its
#     frames, the robot drives over the grid nodes into a log, laser SLAM is replayed over it and
#     placecells explores it at laser SLAM's pose);
#  3. the simulated lab in real time: `launch config/deploy/demo.deploy --group lab` (sim driven by
#     the navigator, homing, landmarks, place cells, laser SLAM, dead reckoning, RatSLAM, fused
#     SLAM, the viewer's snapshots, the recorder); with --fault, one process is killed with SIGKILL
#     half-way and the launcher restarts it;
#  4. log-report turns the recording and the process logs into report.md, summary.json and PNGs;
#     demo-report.md gathers everything, with the verdicts.
# --two-host runs the robot (sim) and the base station (everything else) in two network namespaces
# joined by a veth pair, as two machines on a LAN (tools/deploy/two_host_net.sh); --soak runs the
# lab for hours with the route repeated and judges memory, delivery and the estimators' error over
# time (./snapnav soak --stack). Every process's RSS and CPU time are sampled (processes.csv).
# The whole script is one block, read before it runs: a run of an hour is not thrown off when the file
# changes under it (bash reads a script as it goes).
{
set -euo pipefail
BIN="$1"; shift
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
DEPLOY="$ROOT/config/deploy/demo.deploy"
OUT="$ROOT/logs/demo-$(date -u +%Y%m%d-%H%M%S)"
COUNT=90
DURATION=60
SCENE=indoor13
FAULT=""
EXPLORED=""
FAULT_AT=""
BUS_HEALTH=1
KEEP_LOG=1
TWO_HOST=0
FRAME_ENCODING=jpeg
CLOCK_OFFSET=0
LAPS=3
SOAK=0
ATE_WINDOW=""
MAX_GROWTH_MB=20
LINK_GOAL_MS=3
EXPLORE_ONLY=0
usage() {
  cat <<'EOF'
usage: ./snapnav demo [--out DIR] [--duration-s S] [--scene NAME] [--fault [PROCESS]] [--fault-at-s T]
                      [--explored DIR] [--no-bus-health] [--drop-log] [--two-host] [--raw-frames]
                      [--link-mtu B] [--link-goal-ms MS] [--clock-offset-s S] [--laps N] [--soak]
                      [--ate-window-s S] [--explore-only]
  --out DIR         output folder (default logs/demo-<UTC time>)
  --duration-s S    seconds of the simulated lab in real time (default 60)
  --scene NAME      config/scenes/NAME.scene (default indoor13; its grid must have a 6_6 position)
  --fault [PROC]    kill -9 PROC (default homing) half-way; the launcher must restart it and the
                    recorder must lose nothing (the report compares published and recorded counts)
  --fault-at-s T    when to kill it, seconds after sim started (default: half the duration)
  --explored DIR    reuse the place-cell memory and grid of an earlier demo's folder DIR (same
                    scene): skips step 2
  --explore-only    stop after step 2: OUT holds the place-cell memory, the grid and the camera's
                    mask for --explored of later runs (exit status: whether they are there)
  --no-bus-health   skip step 1
  --drop-log        delete run.lcmlog after the report
  --two-host        two hosts on this machine: sim in a "robot" network namespace, the recorder,
                    estimators and viewer in a "base" one, joined by a veth pair (link-local
                    addresses, no route out, ttl=1); the report adds the link: every message across,
                    frame latency robot -> base (median, p95), commands back to the robot
  --link-mtu B      --two-host: the veth's MTU (default 1500, Ethernet's; 9000: jumbo frames)
  --link-goal-ms MS --two-host: the bound on the link's median latency of a 1 MB frame (default 3)
  --raw-frames      raw 640x480 RGB frames (1 MB each) instead of JPEG ones
  --clock-offset-s S  the robot's clock S seconds off: sim adds S to every utime it publishes
  --laps N          the navigator's laps of the route (default 3; 0: until the run ends)
  --soak            a long run (./snapnav soak --stack): the route repeated (--laps 0), no bus-health
                    step; judged: RSS growth per process after the warm-up (10 minutes; a quarter of
                    runs under 20 minutes) at most 20 MB, nothing lost or missed, no restart, no
                    estimator's error growing over time (--ate-window-s, default duration/12)
  --ate-window-s S  the report's error-over-time windows [s] (default: none, or duration/12 with --soak)
EOF
}
while [ $# -gt 0 ]; do
  case "$1" in
    --out) OUT="$2"; shift 2 ;;
    --duration-s) DURATION="$2"; shift 2 ;;
    --scene) SCENE="$2"; shift 2 ;;
    --fault)
      if [ $# -gt 1 ] && [ "${2#--}" = "$2" ]; then FAULT="$2"; shift 2; else FAULT=homing; shift; fi ;;
    --fault-at-s) FAULT_AT="$2"; shift 2 ;;
    --explored) EXPLORED="$(cd "$2" && pwd)"; shift 2 ;;
    --no-bus-health) BUS_HEALTH=0; shift ;;
    --drop-log) KEEP_LOG=0; shift ;;
    --two-host) TWO_HOST=1; shift ;;
    --raw-frames) FRAME_ENCODING=rgb8; shift ;;
    --link-mtu) export TWO_HOST_MTU="$2"; shift 2 ;;
    --link-goal-ms) LINK_GOAL_MS="$2"; shift 2 ;;
    --clock-offset-s) CLOCK_OFFSET="$2"; shift 2 ;;
    --laps) LAPS="$2"; shift 2 ;;
    --soak) SOAK=1; LAPS=0; BUS_HEALTH=0; shift ;;
    --ate-window-s) ATE_WINDOW="$2"; shift 2 ;;
    --explore-only) EXPLORE_ONLY=1; shift ;;
    -h | --help) usage; exit 0 ;;
    *) echo "demo: unknown argument $1" >&2; usage >&2; exit 2 ;;
  esac
done
if [ "$EXPLORE_ONLY" = 1 ] && [ -n "$EXPLORED" ]; then
  echo "demo: --explore-only explores, --explored reuses an exploration: give one of them" >&2; exit 2
fi
[ -n "$FAULT_AT" ] || FAULT_AT=$(awk -v d="$DURATION" 'BEGIN { print d / 2 }')
[ -n "$ATE_WINDOW" ] || { [ "$SOAK" = 0 ] || ATE_WINDOW=$(awk -v d="$DURATION" 'BEGIN { print d / 12 }'); }
if [ -n "$FAULT" ]; then
  case "$FAULT" in
    recorder | sim) echo "demo: --fault $FAULT: pick a processing process (homing, laser-slam, landmarks, placecells, navigator, dead-reckoning, ratslam, fused-slam, viewer)" >&2; exit 2 ;;
  esac
fi
SIZES=100,65536,1048576
mkdir -p "$OUT"
OUT="$(cd "$OUT" && pwd)"
pids=()
cleanup() {
  for p in "${pids[@]:-}"; do [ -n "$p" ] && kill "$p" 2>/dev/null || true; done
  [ "$TWO_HOST" = 0 ] || two_host_down
}
trap cleanup EXIT
# Where each side runs: on two hosts the robot's or the base's namespace, else here. `(at HOST CMD) &`
# leaves CMD's own pid in $! (it execs), so it can be signalled.
at() {
  local host=$1
  shift
  if [ "$TWO_HOST" = 1 ]; then exec_on "$host" "$@"; else exec "$@"; fi
}
if [ "$TWO_HOST" = 1 ]; then
  # shellcheck source=deploy/two_host_net.sh
  source "$ROOT/tools/deploy/two_host_net.sh"
  two_host_up || exit 1
fi
step() { printf '\n[demo] %s\n' "$*"; }
wait_for_file() { for _ in $(seq 200); do [ -s "$1" ] && return 0; sleep 0.05; done; echo "demo: $1 did not appear" >&2; exit 1; }
verdict() { [ "$1" = 0 ] && echo PASS || echo FAIL; }
# The launcher's output filters ignore Ctrl-C: the launcher gets it, stops the processes in
# reverse order, and its last words (and the report of what was recorded) still come through.
quiet() { (trap '' INT; exec "$@"); }
SECONDS=0
STEPS=4

if [ "$TWO_HOST" = 1 ]; then
  step "two hosts on this machine (network namespaces joined by a veth pair, bus $TWO_HOST_LCM_URL):"
  two_host_describe | sed 's/^/  /'
else
  step "private bus: $(ip -brief link show lo | tr -s ' '); route $(ip route show 224.0.0.0/4)"
fi
live_rc=0; replay_rc=0
if [ "$BUS_HEALTH" = 1 ]; then
  step "1/$STEPS bus health: $COUNT probe frames ($SIZES bytes) at 30 Hz, recorded and replayed"
  PROBES="$OUT/probes.lcmlog"
  (at base lcm-logger -f -q -c BUS_CHECK "$PROBES") &
  logger_pid=$!; pids+=($logger_pid)
  (at base "$BIN/bus-check" verify --count "$COUNT" --sizes "$SIZES" --timeout-s 15 --ready-file "$OUT/.live.ready" >"$OUT/probes-live.txt" 2>/dev/null) &
  verify_pid=$!; pids+=($verify_pid)
  wait_for_file "$OUT/.live.ready"; sleep 0.5
  (at robot "$BIN/bus-check" publish --count "$COUNT" --sizes "$SIZES" --rate-hz 30 2>/dev/null)
  wait "$verify_pid" || live_rc=$?
  sleep 0.3; kill -INT "$logger_pid"; wait "$logger_pid" || true
  (at base "$BIN/bus-check" verify --count "$COUNT" --sizes "$SIZES" --timeout-s 15 --ready-file "$OUT/.replay.ready" >"$OUT/probes-replay.txt" 2>/dev/null) &
  verify_pid=$!; pids+=($verify_pid)
  wait_for_file "$OUT/.replay.ready"
  (at base lcm-logplayer -s 2 "$PROBES" >/dev/null)
  wait "$verify_pid" || replay_rc=$?
  rm -f "$OUT"/.*.ready "$PROBES"
  sed 's/^/  live:   /' "$OUT/probes-live.txt"; sed 's/^/  replay: /' "$OUT/probes-replay.txt"
else
  step "1/$STEPS bus health: skipped (--no-bus-health)"
fi
t_bus=$SECONDS

EXPLORE_OUT="$OUT"
if [ -n "$EXPLORED" ]; then
  step "2/$STEPS place-cell memory: reusing $EXPLORED/placecells.mem (--explored)"
  EXPLORE_OUT="$EXPLORED"
  explore_rc=0
  [ -s "$EXPLORED/placecells.mem" ] && [ -s "$EXPLORED/grid/images/6_6.png" ] && [ -s "$EXPLORED/camera_mask.png" ] ||
    { echo "demo: --explored $EXPLORED: no placecells.mem, grid/images/6_6.png or camera_mask.png there" >&2; exit 2; }
else
  step "2/$STEPS place-cell memory of '$SCENE': launch $(basename "$DEPLOY") --group explore"
  # A memory left in OUT by an earlier run would be extended, not explored afresh.
  rm -f "$OUT/placecells.mem" "$OUT/camera_mask.png"
  set +e
  (at base "$BIN/launch" "$DEPLOY" --group explore --out "$OUT" --status-every-s 10 "scene=$SCENE") 2>&1 |
    quiet grep --line-buffered -vE '^ {11}|^launch: variable ' | quiet sed -u 's/^/  /'
  explore_rc=${PIPESTATUS[0]}
  set -e
  [ -s "$OUT/placecells.mem" ] && [ -s "$OUT/camera_mask.png" ] || explore_rc=1
fi
t_explore=$((SECONDS - t_bus))
if [ "$EXPLORE_ONLY" = 1 ]; then
  step "done (--explore-only): the memory, grid and mask in $OUT ($(verdict $explore_rc), ${t_explore} s)"
  exit "$explore_rc"
fi
HOME_XY=$(awk -F, '$1=="images/6_6.png" { printf "%s,%s", $4, $5 }' "$EXPLORE_OUT/grid/positions.csv" 2>/dev/null || true)

step "3/$STEPS the simulated lab '$SCENE' for $DURATION s in real time: launch $(basename "$DEPLOY") --group lab${FAULT:+, fault: kill -9 $FAULT at ${FAULT_AT} s}"
STATUS="$OUT/launch.status"                # the base's (every process but sim on two hosts)
SIM_STATUS="$STATUS"
[ "$TWO_HOST" = 0 ] || SIM_STATUS="$OUT/launch-robot.status"
rm -f "$STATUS" "$SIM_STATUS" "$OUT/fault.txt" "$OUT/run.lcmlog"  # the recorder appends (--append), so that a restart keeps the start
rm -rf "$OUT/processes" "$OUT"/link-*.csv                         # the process logs are appended to as well
if [ -n "$FAULT" ]; then
  (
    # Wait for sim to run, then kill the process by the pid the launcher reports.
    for _ in $(seq 1200); do
      awk -F'\t' '$1=="sim" && $2=="running" { found=1 } END { exit !found }' "$SIM_STATUS" 2>/dev/null && break
      sleep 0.1
    done
    sleep "$FAULT_AT"
    pid=$(awk -F'\t' -v n="$FAULT" '$1==n && $2=="running" { print $3 }' "$STATUS" 2>/dev/null)
    if [ -z "$pid" ] || [ "$pid" = 0 ]; then
      echo "[demo] fault: $FAULT is not running; nothing killed" >&2
      exit 0
    fi
    printf '\n[demo] fault: kill -9 %s (pid %s), %s s after sim started\n\n' "$FAULT" "$pid" "$FAULT_AT" >&2
    kill -9 "$pid"
    printf '%s\t%s\t%s\n' "$FAULT" "$pid" "$FAULT_AT" >"$OUT/fault.txt"
  ) &
  pids+=($!)
fi
LAB_VARS=("scene=$SCENE" "duration_s=$DURATION" "memory=$EXPLORE_OUT/placecells.mem"
  "mask=$EXPLORE_OUT/camera_mask.png" "home_image=$EXPLORE_OUT/grid/images/6_6.png" "frame_encoding=$FRAME_ENCODING" "clock_offset_s=$CLOCK_OFFSET"
  "laps=$LAPS")
# Every process's RSS and CPU time, from the launchers' status files.
STATUS_FILES=(--status-file "$STATUS")
[ "$TWO_HOST" = 0 ] || STATUS_FILES+=(--status-file "$SIM_STATUS")
python3 "$ROOT/tools/deploy/process_stats.py" sample --out "$OUT/processes.csv" --interval-s 5 "${STATUS_FILES[@]}" &
sampler_pid=$!; pids+=($sampler_pid)
# A launcher's output: all of it into its log, its processes' chosen lines (echo) to the terminal.
show_launcher() {
  quiet tee "$1" | quiet grep --line-buffered -vE '^ {11}|^launch: variable |^[a-z.-]+ +\|   [A-Z_]+ +received' |
    quiet sed -u "s/^/  $2/"
}
set +e
if [ "$TWO_HOST" = 0 ]; then
  "$BIN/launch" "$DEPLOY" --group lab --out "$OUT" --status-every-s 10 --status-file "$STATUS" "${LAB_VARS[@]}" 2>&1 |
    show_launcher "$OUT/launch.log" ""
  lab_rc=${PIPESTATUS[0]}
else
  # The same file on both hosts: the base first (the recorder and everything that listens), then the
  # robot, whose sim ends the run; then the base is stopped. sim notes when it hands each frame to
  # the bus (processes/sim-frame-times.csv), a probe on the base when each arrives (link-base.csv):
  # one clock, so the difference is the frame's time across the link.
  LAB_VARS+=(robot=robot base=base start_time_s=now)
  # The link alone first: 10 s of raw 1 MB frames from sim on the robot to a probe on the base, nothing
  # else running (link-idle-*.csv), then the same probe during the lab.
  (at base "$BIN/latency-probe" --frames-csv "$OUT/link-idle-arrived.csv" --ready-file "$OUT/.probe.ready" \
    >/dev/null 2>"$OUT/latency-idle.log") &
  probe_pid=$!; pids+=($probe_pid)
  wait_for_file "$OUT/.probe.ready"
  rm -f "$OUT/.probe.ready"
  (at robot "$BIN/sim" --mode realtime --duration-s 10 --encoding rgb8 --start-time-s now \
    --frame-times "$OUT/link-idle-sent.csv" >"$OUT/link-idle-sim.log" 2>&1)
  sleep 0.5
  kill -INT "$probe_pid"; wait "$probe_pid"
  (at base "$BIN/latency-probe" --frames-csv "$OUT/link-base.csv" --out "$OUT/latency-base.json" \
    --ready-file "$OUT/.probe.ready" >"$OUT/latency-base.txt" 2>"$OUT/latency-base.log") &
  probe_pid=$!; pids+=($probe_pid)
  wait_for_file "$OUT/.probe.ready"
  rm -f "$OUT/.probe.ready"
  (at base "$BIN/launch" "$DEPLOY" --group lab --host base --out "$OUT" --status-every-s 10 --status-file "$STATUS" \
    "${LAB_VARS[@]}") > >(show_launcher "$OUT/launch.log" "[base]  ") 2>&1 &
  base_pid=$!; pids+=($base_pid)
  # The base is up when every process of it runs (its last, the viewer, printed its ready line).
  for _ in $(seq 1200); do
    awk -F'\t' '!/^#/ && NF > 1 { n++; if ($2 == "running") r++ } END { exit !(n > 0 && n == r) }' "$STATUS" 2>/dev/null && break
    kill -0 "$base_pid" 2>/dev/null || break
    sleep 0.1
  done
  (at robot "$BIN/launch" "$DEPLOY" --group lab --host robot --out "$OUT" --status-every-s 10 --status-file "$SIM_STATUS" \
    "${LAB_VARS[@]}") 2>&1 | show_launcher "$OUT/launch-robot.log" "[robot] "
  robot_rc=${PIPESTATUS[0]}
  sleep 2  # the last messages reach the base
  kill -INT "$base_pid"
  wait "$base_pid"
  base_rc=$?
  kill -INT "$probe_pid"
  wait "$probe_pid"
  lab_rc=$((robot_rc || base_rc))
fi
kill -INT "$sampler_pid" 2>/dev/null; wait "$sampler_pid"
set -e
t_lab=$((SECONDS - t_bus - t_explore))

step "4/$STEPS report"
report_rc=0
LOG="$OUT/run.lcmlog"
"$BIN/log-report" "$LOG" --out "$OUT" ${HOME_XY:+--home "$HOME_XY"} --process-logs "$OUT/processes" \
  ${ATE_WINDOW:+--ate-window-s "$ATE_WINDOW"} >/dev/null || report_rc=$?
# Every process's memory and CPU; the link between the hosts; the long run's verdicts.
CHECKS="$ROOT/tools/deploy/run_checks.py"
python3 "$ROOT/tools/deploy/process_stats.py" summary "$OUT/processes.csv" --json "$OUT/processes.json" \
  --md "$OUT/processes.md" >/dev/null || true
link_rc=0
[ "$TWO_HOST" = 0 ] || python3 "$CHECKS" link "$OUT" --clock-offset-s "$CLOCK_OFFSET" --frames "$FRAME_ENCODING" --max-median-ms "$LINK_GOAL_MS" >/dev/null || link_rc=$?
soak_rc=0
# RatSLAM's error rises while its experience map is laid over the first laps and levels off after
# about 10 minutes (the hour's soak, docs/deployment.md): its growth is judged from 600 s on, so a
# short soak shows it without judging it.
[ "$SOAK" = 0 ] || python3 "$CHECKS" soak "$OUT" --warmup-s "$(awk -v d="$DURATION" 'BEGIN { print (d >= 1200) ? 600 : d / 4 }')" \
  --estimator-warmup POSE_RATSLAM=600 --max-rss-growth-mb "$MAX_GROWTH_MB" >/dev/null || soak_rc=$?
# The fault's verdict: restarted, sim's channels complete in the log, the other processes never restarted.
fault_rc=0
fault_text=""
if [ -n "$FAULT" ]; then
  fault_text=$(python3 - "$OUT/summary.json" "$FAULT" "$OUT/fault.txt" <<'PY' || true
import json, os, sys
s = json.load(open(sys.argv[1])); fault = sys.argv[2]
ok = True; lines = []
if not os.path.exists(sys.argv[3]):
    ok = False; lines.append("- %s was not killed (it was not running)" % fault)
runs = s.get("process_%s_runs" % fault, 0)
lines.append("- %s: %d runs (killed once, restarted by the launcher)" % (fault, runs))
ok &= runs == 2
for ch in ("omni_frame", "laser_scan", "odometry", "pose_ground_truth"):
    p, r = s.get("delivery_%s_published" % ch), s.get("delivery_%s_recorded" % ch)
    lines.append("- sim %s: published %s, recorded %s" % (ch.upper(), p, r))
    ok &= p is not None and p == r and p > 0
others = {k[8:-5]: v for k, v in s.items() if k.startswith("process_") and k.endswith("_runs") and k[8:-5] != fault}
restarted = [k for k, v in others.items() if v != 1]
lines.append("- the other processes: %s" % (", ".join("%s %d run%s" % (k, v, "s" if v != 1 else "") for k, v in sorted(others.items()))))
ok &= not restarted
lines.append("- lost in total (channels with exact counts): %s" % s.get("delivery_lost_total"))
ok &= s.get("delivery_lost_total") == 0
print("PASS" if ok else "FAIL")
print("\n".join(lines))
PY
)
  [ "$(echo "$fault_text" | head -1)" = PASS ] || fault_rc=1
fi
{
  echo "# snapnav demo report"
  echo
  echo "- Date (UTC): $(date -u +%Y-%m-%dT%H:%M:%SZ); run time ${SECONDS} s (bus health ${t_bus} s, place-cell memory ${t_explore} s, lab ${t_lab} s)"
  if [ "$TWO_HOST" = 1 ]; then
    echo "- Bus: UDP multicast between two hosts: network namespaces \"robot\" (sim) and \"base\" (the rest) joined by a veth pair ($TWO_HOST_ROBOT_ADDR, $TWO_HOST_BASE_ADDR), ttl=1, no route out"
  else
    echo "- Bus: UDP multicast in a private network namespace (loopback only, ttl=0)"
  fi
  echo "- Frames: $FRAME_ENCODING; the robot's clock offset: $CLOCK_OFFSET s; the navigator's laps: $LAPS (0: until the end)"
  echo "- Deployment: \`config/deploy/demo.deploy\`, run by \`build/bin/launch\` (groups explore, lab); process logs in \`processes/\`"
  if [ -f "$LOG" ]; then
    if [ "$KEEP_LOG" = 1 ]; then
      echo "- Log: \`$LOG\` ($(stat -c %s "$LOG") bytes); replay it with \`./snapnav bus -- lcm-logplayer $LOG\`"
    else
      echo "- Log: $(stat -c %s "$LOG") bytes, deleted after the report (--drop-log)"
    fi
  fi
  echo
  echo "## 1. Bus health"
  echo
  if [ "$BUS_HEALTH" = 1 ]; then
    echo "| step | result | details |"
    echo "|---|---|---|"
    echo "| live: publisher -> subscriber | $(verdict $live_rc) | $(sed 's/^bus-check verify: //' "$OUT/probes-live.txt") |"
    echo "| replay: lcm-logplayer -> subscriber | $(verdict $replay_rc) | $(sed 's/^bus-check verify: //' "$OUT/probes-replay.txt") |"
  else
    echo "Skipped (--no-bus-health)."
  fi
  echo
  echo "## 2. Place-cell memory ($(verdict $explore_rc))"
  echo
  [ -z "$EXPLORED" ] || printf 'Reused from `%s` (--explored).\n\n' "$EXPLORED"
  grep -hE "^gridgen: scene|^(rim|mask): |^sim: done|^replay: [0-9]+ input events|^placecells: explore, memory" \
    "$EXPLORE_OUT/explore/gridgen.log" "$EXPLORE_OUT/explore/calibrate.log" "$EXPLORE_OUT/explore/drive.log" \
    "$EXPLORE_OUT/explore/slam.log" "$EXPLORE_OUT/explore/placecells.log" 2>/dev/null | sed 's/^/    /' || true
  echo
  echo "The memory is explored as a robot explores: the drive over the grid nodes (sim), laser SLAM over its"
  echo "log (replay), a cell every 0.2 m at laser SLAM's pose (placecells); no ground truth in it."
  echo
  echo "## 3. Simulated lab: scene $SCENE, $DURATION s ($(verdict $lab_rc))"
  echo
  grep -E "^sim: done" "$OUT/processes/sim.log" 2>/dev/null | sed 's/^/    /' || true
  echo
  echo "The launcher's final status:"
  echo
  for f in "$OUT/launch.log" "$OUT/launch-robot.log"; do
    [ -f "$f" ] && sed -n '/^launch: final status/,$p' "$f" | sed 's/^/    /'
  done
  echo
  echo "What each process did (its own last lines):"
  echo
  for f in "$OUT"/processes/*.log; do
    n=$(basename "$f" .log)
    grep -E "^$n: (frames [0-9]|(surf|sift|vline), frames|localize, memory|scans [0-9]|mean update|published [0-9]|[0-9]+ drive|fixes accepted|[0-9]+ templates|visual measurements accepted|mean [0-9.e-]+ ms per scan|[0-9]+ snapshots)" "$f" | sed 's/^/    /' || true
  done
  if [ -s "$OUT/viewer/viewer-final.png" ]; then
    echo
    echo "The viewer's last snapshot (\`viewer/viewer-final.png\`; one every 5 s of the run in \`viewer/\`):"
    echo
    echo "![the viewer at the end of the run](viewer/viewer-final.png)"
  fi
  echo
  echo "Memory and CPU of each process, sampled every 5 s (\`processes.csv\`):"
  echo
  cat "$OUT/processes.md" 2>/dev/null || true
  if [ "$TWO_HOST" = 1 ]; then
    echo
    sed 's/^#/##/' "$OUT/link.md" 2>/dev/null || echo "## Two hosts: no link report"
  fi
  if [ "$SOAK" = 1 ]; then
    echo
    sed 's/^#/##/' "$OUT/soak.md" 2>/dev/null || echo "## Soak: no soak report"
  fi
  if [ -n "$FAULT" ]; then
    echo
    echo "## Fault: kill -9 $FAULT ${FAULT_AT} s into the run ($(echo "$fault_text" | head -1))"
    echo
    echo "$fault_text" | tail -n +2
    grep -hE "^launch: $FAULT: (ended|restarted)" "$OUT/launch.log" | sed 's/^/    /' || true
  fi
  echo
  sed -n '/^## Messages/,$p' "$OUT/report.md" | sed 's/^## /### /'
} >"$OUT/demo-report.md"
[ "$KEEP_LOG" = 1 ] || rm -f "$LOG"
step "report: $OUT/demo-report.md ($(ls "$OUT"/*.png 2>/dev/null | wc -l) figures); run time ${SECONDS} s"
sed -n '1,/^### Messages/p' "$OUT/demo-report.md" | head -n -1
rc=0
for r in $live_rc $replay_rc $explore_rc $lab_rc $report_rc $fault_rc $link_rc $soak_rc; do [ "$r" = 0 ] || rc=1; done
exit $rc
}
