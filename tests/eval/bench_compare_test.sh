#!/usr/bin/env bash
# bench-compare times every method of the SLAM comparison (a short run) and writes a figure for
# each into bench.json and bench.md. It once ended with "error: map::at" after printing three of
# them, because fused_no_vision had no unit of update.
set -euo pipefail
BIN="$1"
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT
"$BIN/bench-compare" --scene corridor --duration-s 3 --runs 1 --out "$OUT" >"$OUT/stdout" 2>"$OUT/stderr" || {
  echo "FAIL: bench-compare exited with $?"; cat "$OUT/stderr"; exit 1; }
python3 - "$OUT" <<'PY'
import json, math, sys
out = sys.argv[1]
j = json.load(open(out + "/bench.json"))
md = open(out + "/bench.md").read()
for m in ["dead_reckoning", "laser_slam", "ratslam", "fused_slam", "fused_no_vision"]:
    for k in ["_ms_per_update", "_ms_per_frame"]:
        v = j.get(m + k)
        assert isinstance(v, (int, float)) and math.isfinite(v) and v > 0, f"{m}{k} = {v!r}"
    assert f"| {m} |" in md, f"bench.md has no row for {m}"
for k in ["place_cells_ms_per_view", "place_cells_ms_per_localize", "fused_slam_ms_per_visual_update"]:
    assert isinstance(j.get(k), (int, float)) and j[k] > 0, f"{k} = {j.get(k)!r}"
print("ok: bench-compare timed every method:", ", ".join(f"{m} {j[m + '_ms_per_update']:.3f} ms"
      for m in ["laser_slam", "ratslam", "fused_slam", "fused_no_vision"]))
PY
