#!/usr/bin/env bash
# lcm-spy shows the true rates (ctest lcm_spy_shows_published_rates, inside ./snapnav bus, about 40 s):
# Xvfb as its display, `./snapnav spy --report` beside `sim` in real time for 20 s; SpyReport reads
# lcm-spy's own window (its channel table) every second. Every channel sim publishes must show, in the
# window, at least 95 % of the messages sim published and, while sim runs, a rate within 5 % of the
# published one. ENCODING (default jpeg, the sim's default) picks the frames: with rgb8 (1 MB raw
# frames) the Java lcm-spy loses most frames (its socket's receive buffer is the kernel's default).
set -euo pipefail
BIN="$1"; OUT="$2"; ENCODING="${3:-jpeg}"
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
DURATION=20
command -v Xvfb >/dev/null || { echo "FAIL: Xvfb not found (Debian package xvfb: ./snapnav setup installs it)"; exit 1; }
rm -rf "$OUT"; mkdir -p "$OUT"
pids=()
cleanup() { for p in "${pids[@]:-}"; do [ -n "$p" ] && kill "$p" 2>/dev/null || true; done; }
trap cleanup EXIT
# A display of our own: Xvfb picks a free number and writes it to fd 3.
Xvfb -displayfd 3 -screen 0 1280x1024x24 -nolisten tcp 3>"$OUT/display" 2>"$OUT/xvfb.log" &
pids+=($!)
for _ in $(seq 100); do [ -s "$OUT/display" ] && break; sleep 0.1; done
[ -s "$OUT/display" ] || { echo "FAIL: Xvfb did not start (see $OUT/xvfb.log)"; exit 1; }
export DISPLAY=":$(head -1 "$OUT/display")"
"$ROOT/snapnav" spy --report "$OUT/spy.csv" --report-after-s $((DURATION + 8)) --report-every-s 1 >"$OUT/spy.log" 2>&1 &
spy_pid=$!; pids+=($spy_pid)
# lcm-spy listens once its window is up (SpyReport then writes the CSV header).
for _ in $(seq 300); do [ -s "$OUT/spy.csv" ] && break; sleep 0.1; done
[ -s "$OUT/spy.csv" ] || { echo "FAIL: lcm-spy did not start in 30 s"; cat "$OUT/spy.log"; exit 1; }
sleep 2
t0=$(date +%s.%N)
"$BIN/sim" --mode realtime --duration-s "$DURATION" --encoding "$ENCODING" >"$OUT/sim.log" 2>&1
t1=$(date +%s.%N)
spy_rc=0; wait "$spy_pid" || spy_rc=$?
[ "$spy_rc" = 0 ] || { echo "FAIL: ./snapnav spy --report exited $spy_rc"; cat "$OUT/spy.log"; exit 1; }
python3 - "$OUT" "$DURATION" "$t0" "$t1" <<'PY'
import csv, os, re, statistics, sys
out, duration = sys.argv[1], float(sys.argv[2])
# sim's own counts (glue::Bus::ReportStats): "  CHANNEL   received N, published N, ..."
published = {m.group(1): int(m.group(2)) for m in
             re.finditer(r"^  (\S+) +received \d+, published (\d+)", open(os.path.join(out, "sim.log")).read(), re.M)}
rows = list(csv.DictReader(open(os.path.join(out, "spy.csv"))))
last_t = max(float(r["t_s"]) for r in rows)
final = {r["channel"]: int(r["messages"]) for r in rows if float(r["t_s"]) == last_t}
# The spy's time of the sim's start: the first row with a message on ODOMETRY.
started = min(float(r["t_s"]) for r in rows if r["channel"] == "ODOMETRY" and int(r["messages"]) > 0)
bad = []
print(f"{'channel':20s} {'published':>9s} {'in lcm-spy':>10s} {'rate published':>15s} {'lcm-spy Hz (median)':>20s}")
for ch, n in sorted(published.items()):
    if n == 0:
        continue
    rate = n / duration
    # Readings well inside the run (lcm-spy's Hz is over its last second).
    hz = [float(r["hz"]) for r in rows if r["channel"] == ch and started + 3 <= float(r["t_s"]) <= started + duration - 2]
    med = statistics.median(hz) if hz else 0.0
    got = final.get(ch, 0)
    print(f"{ch:20s} {n:9d} {got:10d} {rate:15.2f} {med:20.2f}")
    if got < 0.95 * n: bad.append(f"{ch}: lcm-spy shows {got} of {n} messages")
    if abs(med - rate) > 0.05 * rate: bad.append(f"{ch}: lcm-spy shows {med:.2f} Hz, {rate:.2f} Hz were published")
if "OMNI_FRAME" not in published: bad.append("sim published no OMNI_FRAME")
if bad: sys.exit("FAIL: " + "; ".join(bad))
print("PASS: lcm-spy's window shows every channel's messages and rate within 5 %")
PY
