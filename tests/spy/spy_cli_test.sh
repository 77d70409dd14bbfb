#!/usr/bin/env bash
# ./snapnav spy and logplayer-gui (ctest spy_says_its_bus_and_display, about 20 s): lcm-spy says which
# bus it watches; a display that cannot be opened is one line naming it (no Java stack trace), checked
# before --private starts the command beside it; --private runs lcm-spy on a private bus with the
# command, and lcm-spy's window (SpyReport, under Xvfb) shows what the command publishes there.
#   spy_cli_test.sh BIN_DIR OUT_DIR
set -uo pipefail
BIN="$1"; OUT="$2"
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
rm -rf "$OUT"; mkdir -p "$OUT"
fail() { echo "FAIL: $*"; exit 1; }
pids=()
cleanup() { for p in "${pids[@]:-}"; do [ -n "$p" ] && kill "$p" 2>/dev/null || true; done; }
trap cleanup EXIT

# One clear line for a bad display, not AWT's stack trace (it was 26 lines).
expect_display_error() {  # LABEL OUTPUT STATUS
  local label="$1" out="$2" rc="$3"
  echo "--- $label (exit $rc):"; echo "$out"
  [ "$rc" != 0 ] || fail "$label: exit status 0 without a display"
  grep -qF "cannot open the display ':97531'" <<<"$out" || fail "$label: the display is not named"
  ! grep -qE '^\s+at |Exception|AWTError' <<<"$out" || fail "$label: a Java stack trace"
  [ "$(grep -c 'cannot open the display' <<<"$out")" = 1 ] || fail "$label: the display error more than once"
}

out="$(env -u SNAPNAV_BUS DISPLAY=:97531 "$ROOT/snapnav" spy 2>&1)"; rc=$?
expect_display_error "spy" "$out" "$rc"
grep -qF "NOT a private bus" <<<"$out" || fail "spy does not say it watches this machine's network"
grep -qF "./snapnav spy --private -- COMMAND" <<<"$out" || fail "spy does not offer --private"

marker="$OUT/command-started"
out="$(env -u SNAPNAV_BUS DISPLAY=:97531 "$ROOT/snapnav" spy --private -- touch "$marker" 2>&1)"; rc=$?
expect_display_error "spy --private" "$out" "$rc"
[ ! -e "$marker" ] || fail "spy --private started the command although the display cannot be opened"

out="$(env -u SNAPNAV_BUS DISPLAY=:97531 "$ROOT/snapnav" logplayer-gui "$OUT/none.lcmlog" 2>&1)"; rc=$?
expect_display_error "logplayer-gui" "$out" "$rc"

out="$(env -u SNAPNAV_BUS -u DISPLAY -u WAYLAND_DISPLAY "$ROOT/snapnav" spy 2>&1)"; rc=$?
echo "--- spy without DISPLAY (exit $rc):"; echo "$out"
[ "$rc" != 0 ] && grep -qF "no display is set" <<<"$out" || fail "spy without DISPLAY"

out="$(env -u SNAPNAV_BUS "$ROOT/snapnav" spy -- true 2>&1)"; rc=$?
[ "$rc" != 0 ] && grep -qF "add --private" <<<"$out" || fail "spy -- CMD without --private: $out"

# --private under Xvfb: bus-check publishes beside lcm-spy on the private bus; lcm-spy's channel table
# shows its probes.
command -v Xvfb >/dev/null || fail "Xvfb not found (Debian package xvfb: ./snapnav setup installs it)"
Xvfb -displayfd 3 -screen 0 1280x1024x24 -nolisten tcp 3>"$OUT/display" 2>"$OUT/xvfb.log" &
pids+=($!)
for _ in $(seq 100); do [ -s "$OUT/display" ] && break; sleep 0.1; done
[ -s "$OUT/display" ] || fail "Xvfb did not start (see $OUT/xvfb.log)"
csv="$OUT/spy.csv"
env -u SNAPNAV_BUS DISPLAY=":$(head -1 "$OUT/display")" "$ROOT/snapnav" spy --private --report "$csv" \
  --report-after-s 15 -- bash -c '
    for _ in $(seq 600); do [ -s "$1" ] && break; sleep 0.1; done
    sleep 1
    exec "$2/bus-check" publish --count 30 --rate-hz 10 --sizes 100' probe "$csv" "$BIN" >"$OUT/spy.log" 2>&1
rc=$?
echo "--- spy --private under Xvfb (exit $rc):"; cat "$OUT/spy.log"
[ "$rc" = 0 ] || fail "spy --private --report exited $rc"
grep -qF "spy: watching the private bus" "$OUT/spy.log" || fail "spy --private does not say it watches the private bus"
last="$(awk -F, '$2 == "BUS_CHECK" { n = $4 } END { print n + 0 }' "$csv")"
echo "lcm-spy shows $last BUS_CHECK messages (30 published)"
[ "$last" -ge 25 ] || fail "lcm-spy on the private bus shows $last of the 30 probes published beside it"
echo "PASS"
