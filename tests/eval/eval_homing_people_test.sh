#!/usr/bin/env bash
# Landmark homing among walking people (issue 5 goal): on people11 (six people walking through
# the views, also during the return runs), SIFT with the scale ALV and its consensus, the home
# fused from nine frames one second apart ([view_fusion] persistent), degrades by at most 5
# degrees against the same room without people, and returns home from at least 95% of the starts.
set -euo pipefail
BIN="$1"
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT
"$BIN/eval-homing" --scene people11 --method sift --alv scale --home-frames 9 --home-interval-s 1.0 \
  --current-frames 1 --fusion persistent --min-fraction 0.2 --out "$OUT" 2> >(tr '\r' '\n' | grep -v '/1[0-9]*$' >&2)
python3 - "$OUT/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
aae, empty, ret = s["average_angular_error_deg"], s["average_angular_error_without_people_deg"], s["return_ratio"]
print(f"people11 SIFT scale ALV, home fused from {s['home_frames']} frames: AAE {aae:.2f} deg, without people "
      f"{empty:.2f} deg, degradation {aae - empty:.2f} deg, return ratio {ret:.3f} ({s['return_successes']}/{s['return_starts']})")
assert s["grid_positions"] == 120, s["grid_positions"]
assert s["fusion"] == "persistent" and s["home_frames"] == 9 and s["current_frames"] == 1
assert aae - empty <= 5.0, f"degradation {aae - empty:.2f} > 5 deg"
assert ret >= 0.95, f"return ratio {ret} < 0.95"
PY
test -s "$OUT/vector_map.png"
