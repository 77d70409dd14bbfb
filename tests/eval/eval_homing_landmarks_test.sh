#!/usr/bin/env bash
# Landmark homing's error bounds on the simulated indoor 13x13 room (issue targets): SURF
# keypoints with the scale-compensated ALV (consensus, the shipped [landmark_alv]) reach an AAE
# of at most 10 degrees and a return ratio of at least 0.95, raw images unwrapped.
set -euo pipefail
BIN="$1"
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT
"$BIN/eval-homing" --scene indoor13 --method surf --alv scale --out "$OUT" 2> >(tr '\r' '\n' | grep -v '/1[0-9]*$' >&2)
python3 - "$OUT/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
aae, ret = s["average_angular_error_deg"], s["return_ratio"]
print(f"SURF scale ALV: AAE {aae:.2f} deg, return ratio {ret:.3f}, {s['mean_landmarks_per_view']:.0f} landmarks, "
      f"{s['mean_matches']:.0f} matches, {s['ms_per_frame']:.1f} ms/frame")
assert s["grid_positions"] == 168, s["grid_positions"]
assert s["method"] == "surf" and s["alv"] == "scale"
assert aae <= 10.0, f"AAE {aae} > 10"
assert ret >= 0.95, f"return ratio {ret} < 0.95"
PY
test -s "$OUT/vector_map.png"
