#!/usr/bin/env bash
# The viewer on a recorded log, run inside `./snapnav bus --`: sim (real time, 4 s),
# dead-reckoning and homing on the private bus, lcm-logger records; then the viewer reads the
# log through file://LOG?speed=0 and writes PNG snapshots, which must show the ground truth and
# dead reckoning trajectories, the homing arrow and a panorama. Without a display and without
# --png the viewer must refuse with a clear error; with Qt's offscreen platform its window path
# runs over the same log.
set -euo pipefail
BIN="$1"
CHECK="$2"
TMP="$(mktemp -d)"
pids=()
cleanup() {
  for p in "${pids[@]:-}"; do kill "$p" 2>/dev/null || true; done
  rm -rf "$TMP"
}
trap cleanup EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

echo "== recording: sim + dead-reckoning + homing for 4 s"
lcm-logger -f -q "$TMP/run.lcmlog" &
logger_pid=$!; pids+=("$logger_pid")
"$BIN/dead-reckoning" 2>"$TMP/dr.log" &
dr_pid=$!; pids+=("$dr_pid")
"$BIN/homing" --home-first 2>"$TMP/homing.log" &
homing_pid=$!; pids+=("$homing_pid")
sleep 0.7
"$BIN/sim" --duration-s 4 --mode realtime >"$TMP/sim.log" 2>&1 || { cat "$TMP/sim.log"; fail "sim"; }
sleep 0.5
kill -INT "$dr_pid" "$homing_pid"; wait "$dr_pid" || true; wait "$homing_pid" || true
sleep 0.2
kill -INT "$logger_pid"; wait "$logger_pid" || true

echo "== viewer --png on file://LOG?speed=0"
env -u DISPLAY -u WAYLAND_DISPLAY -u QT_QPA_PLATFORM \
  "$BIN/viewer" --lcm-url "file://$TMP/run.lcmlog?speed=0" --png "$TMP/png" --png-interval-s 2 2>"$TMP/viewer.log" ||
  { cat "$TMP/viewer.log"; fail "viewer exited non-zero"; }
grep -E "^viewer: (t |[0-9]+ snapshots)" "$TMP/viewer.log"
[ -s "$TMP/png/viewer-final.png" ] || fail "no viewer-final.png"
[ -s "$TMP/png/viewer-t00002.0s.png" ] || fail "no snapshot at 2 s of message time"
"$CHECK" "$TMP/png/viewer-final.png" --homing POSE_GROUND_TRUTH POSE_DEAD_RECKONING || fail "snapshot looks blank"
if [ -n "${SNAPNAV_VIEWER_TEST_KEEP:-}" ]; then cp "$TMP/png/viewer-final.png" "$SNAPNAV_VIEWER_TEST_KEEP"; fi

echo "== no display and no --png: a clear error"
rc=0
env -u DISPLAY -u WAYLAND_DISPLAY -u QT_QPA_PLATFORM \
  "$BIN/viewer" --lcm-url "file://$TMP/run.lcmlog?speed=0" >"$TMP/nodisplay.out" 2>&1 || rc=$?
cat "$TMP/nodisplay.out"
[ "$rc" != 0 ] || fail "viewer without a display and without --png exited 0"
grep -q "no display" "$TMP/nodisplay.out" || fail "the error does not say there is no display"

echo "== the window path (Qt offscreen platform)"
QT_QPA_PLATFORM=offscreen timeout 60 "$BIN/viewer" --lcm-url "file://$TMP/run.lcmlog?speed=0" --close-at-end \
  2>"$TMP/window.log" || { cat "$TMP/window.log"; fail "viewer window run"; }
grep -q "POSE_DEAD_RECKONING *received [1-9]" "$TMP/window.log" || { cat "$TMP/window.log"; fail "window run saw no poses"; }
echo "PASS: viewer snapshots of a recorded run show the trajectories, the homing arrow and the panorama"
