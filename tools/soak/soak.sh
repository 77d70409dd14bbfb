#!/usr/bin/env bash
# The soak test, run by `./snapnav soak` inside the private bus namespace: one process publishes
# 1 MB omni frames at 30 Hz and 681-beam laser scans at 10 Hz for --duration-s; a verifier
# process and lcm-logger subscribe. lcm-logger writes into a FIFO read by a log verifier, so the
# logger's recording is checked message by message without 9 GB of disk per 5 minutes. The RSS of
# every process is sampled; the kernel's UDP counters (RcvbufErrors: datagrams dropped because a
# receive buffer was full) are read before and after. Writes into --out: summary.json, soak.md,
# rss.csv, and each process's own JSON and log. Exit 0 when nothing was dropped and no process's
# RSS grew by more than --max-rss-growth-mb between the end of the warm-up and the end.
set -euo pipefail
BIN="$1"; shift
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
OUT="$ROOT/logs/soak"
DURATION=300
RSS_INTERVAL=5
MAX_GROWTH_MB=20
FRAME_BYTES=1048576
FRAME_HZ=30
SCAN_HZ=10
while [ $# -gt 0 ]; do
  case "$1" in
    --out) OUT="$2"; shift 2 ;;
    --duration-s) DURATION="$2"; shift 2 ;;
    --rss-interval-s) RSS_INTERVAL="$2"; shift 2 ;;
    --max-rss-growth-mb) MAX_GROWTH_MB="$2"; shift 2 ;;
    --frame-bytes) FRAME_BYTES="$2"; shift 2 ;;
    *) echo "soak: unknown argument $1 (--out DIR, --duration-s S, --rss-interval-s S, --max-rss-growth-mb MB, --frame-bytes B)" >&2; exit 2 ;;
  esac
done
mkdir -p "$OUT"
rm -f "$OUT"/*.json "$OUT/rss.csv" "$OUT/soak.md"
FIFO="$(mktemp -u /tmp/snapnav-soak.XXXXXX.fifo)"
mkfifo "$FIFO"
pids=()
sampler_pid=""
cleanup() {
  [ -n "$sampler_pid" ] && kill "$sampler_pid" 2>/dev/null || true
  for p in "${pids[@]:-}"; do kill "$p" 2>/dev/null || true; done
  rm -f "$FIFO" "$OUT/.verifier.ready"
}
trap cleanup EXIT
udp_counters() { awk '/^Udp:/ { if (++n == 2) print "in_datagrams=" $2, "in_errors=" $4, "rcvbuf_errors=" $6 }' /proc/net/snmp; }
wait_for_file() { for _ in $(seq 200); do [ -s "$1" ] && return 0; sleep 0.05; done; echo "soak: $1 did not appear" >&2; exit 1; }
SOAK=(--duration-s "$DURATION" --frame-bytes "$FRAME_BYTES" --frame-rate-hz "$FRAME_HZ" --scan-rate-hz "$SCAN_HZ")

echo "soak: ${DURATION} s of ${FRAME_BYTES}-byte frames at ${FRAME_HZ} Hz and scans at ${SCAN_HZ} Hz; private bus $(ip route show 224.0.0.0/4 | tr -s ' ')"
echo "soak: net.core.rmem_max = $(cat /proc/sys/net/core/rmem_max) bytes, LCM URL $LCM_DEFAULT_URL"
# The log verifier opens the FIFO first (it blocks until lcm-logger opens it for writing).
"$BIN/bus-check" soak-verify "${SOAK[@]}" --log "$FIFO" --out "$OUT/logger.json" >"$OUT/logger-verify.txt" 2>"$OUT/logger-verify.log" &
reader_pid=$!; pids+=("$reader_pid")
lcm-logger -f -q -c 'SOAK_.*' "$FIFO" >"$OUT/lcm-logger.log" 2>&1 &
logger_pid=$!; pids+=("$logger_pid")
"$BIN/bus-check" soak-verify "${SOAK[@]}" --timeout-s 10 --ready-file "$OUT/.verifier.ready" --out "$OUT/verifier.json" \
  >"$OUT/verifier.txt" 2>"$OUT/verifier.log" &
verifier_pid=$!; pids+=("$verifier_pid")
wait_for_file "$OUT/.verifier.ready"
sleep 0.5  # lcm-logger says nothing once subscribed

udp_before="$(udp_counters)"
"$BIN/bus-check" soak-publish "${SOAK[@]}" --out "$OUT/publisher.json" 2> >(tee "$OUT/publisher.log" | grep --line-buffered -E "^bus-check soak-publish: [0-9]+ s:" | sed -u 's/^bus-check //' >&2) &
publisher_pid=$!; pids+=("$publisher_pid")
python3 "$ROOT/tools/deploy/process_stats.py" sample --out "$OUT/rss.csv" --interval-s "$RSS_INTERVAL" \
  --pid "publisher=$publisher_pid" --pid "verifier=$verifier_pid" --pid "lcm-logger=$logger_pid" --pid "log-verifier=$reader_pid" &
sampler_pid=$!
publisher_rc=0; wait "$publisher_pid" || publisher_rc=$?
verifier_rc=0; wait "$verifier_pid" || verifier_rc=$?
udp_after="$(udp_counters)"
kill -INT "$sampler_pid" 2>/dev/null || true; wait "$sampler_pid" 2>/dev/null || true; sampler_pid=""
sleep 0.5
kill -INT "$logger_pid"; wait "$logger_pid" || true
reader_rc=0; wait "$reader_pid" || reader_rc=$?
cat "$OUT/verifier.txt" "$OUT/logger-verify.txt"

python3 "$ROOT/tools/soak/soak_summary.py" "$OUT" --duration-s "$DURATION" --max-rss-growth-mb "$MAX_GROWTH_MB" \
  --udp-before "$udp_before" --udp-after "$udp_after" \
  --exit-codes "publisher=$publisher_rc,verifier=$verifier_rc,log-verifier=$reader_rc"
