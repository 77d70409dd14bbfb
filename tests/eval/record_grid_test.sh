#!/usr/bin/env bash
# record-grid on a private bus (run inside ./snapnav bus --): sim drives its route and publishes
# raw omni frames and its ground-truth pose; record-grid keeps one frame per 20 cm grid node
# within 4 cm. The folder it writes has gridgen's format: each image within the tolerance of its
# node, the frames' calibration in camera.ini, and eval localization --grid reads it.
set -euo pipefail
BIN="$1"
TMP="$(mktemp -d)"
pids=()
cleanup() {
  for p in "${pids[@]:-}"; do kill "$p" 2>/dev/null || true; done
  rm -rf "$TMP"
}
trap cleanup EXIT
"$BIN/record-grid" --pose POSE_GROUND_TRUTH --spacing-m 0.2 --tolerance-m 0.04 --max-images 6 --duration-s 120 \
  --out "$TMP/grid" --ready-file "$TMP/ready" 2>"$TMP/record.log" &
rec=$!
pids+=("$rec")
for _ in $(seq 200); do [ -s "$TMP/ready" ] && break; sleep 0.05; done
[ -s "$TMP/ready" ] || { echo "FAIL: record-grid did not start"; cat "$TMP/record.log"; exit 1; }
sleep 0.3
"$BIN/sim" --duration-s 60 --encoding png >"$TMP/sim.log" 2>&1 || { cat "$TMP/sim.log"; exit 1; }
rc=0
wait "$rec" || rc=$?
tr '\r' '\n' < "$TMP/record.log" | tail -3
[ "$rc" = 0 ] || { echo "FAIL: record-grid exited $rc"; exit 1; }
test -s "$TMP/grid/camera.ini"
python3 - "$TMP/grid" <<'PY'
import csv, math, os, sys
d = sys.argv[1]
rows = list(csv.DictReader(open(os.path.join(d, "positions.csv"))))
print(f"{len(rows)} images")
assert len(rows) >= 3, len(rows)
x0, y0 = None, None
nodes = set()
for r in rows:
    assert os.path.getsize(os.path.join(d, r["file"])) > 1000, r["file"]
    ix, iy, x, y = int(r["ix"]), int(r["iy"]), float(r["x_m"]), float(r["y_m"])
    assert ix >= 0 and iy >= 0
    assert (ix, iy) not in nodes
    nodes.add((ix, iy))
    if x0 is None:
        x0, y0 = x - 0.2 * ix, y - 0.2 * iy  # node (0, 0) from the first image, within the tolerance
    assert math.hypot(x - (x0 + 0.2 * ix), y - (y0 + 0.2 * iy)) <= 0.081, (r, x0, y0)
ini = open(os.path.join(d, "camera.ini")).read()
assert "[mirror]" in ini and "center_x_px" in ini and "[panorama]" in ini
PY
"$BIN/eval-localization" --grid "$TMP/grid" --measures bearing-smallest --filters on --out "$TMP/loc" \
  >"$TMP/loc.out" 2>"$TMP/loc.log" || { cat "$TMP/loc.log"; exit 1; }
grep -q '"leave_one_out_queries"' "$TMP/loc/summary.json"
cat "$TMP/loc.out"
