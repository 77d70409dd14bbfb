#!/usr/bin/env bash
# The homing evaluation's error bounds on the simulated indoor 13x13 room, raw images unwrapped,
# the shipped configuration:
# - the shipped camera (realistic, the robot's parts masked by a calibrated mask): return ratio
#   >= 0.95 (issue 21's goal), the compass within 2 degrees (median) on pure rotations, and the
#   AAE within its measured 22.1 deg + 2 (issue 21's goal of 15 deg is not met: docs/homing.md);
# - the clean camera: AAE <= 15 degrees (the earlier issue's target, 14.0 measured).
set -euo pipefail
BIN="$1"
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT
"$BIN/eval-homing" --scene indoor13 --quick --out "$OUT/realistic" 2> >(tr '\r' '\n' | grep -v '/1[0-9]*$' >&2)
"$BIN/eval-homing" --scene indoor13 --camera clean --quick --no-return --out "$OUT/clean" \
  2> >(tr '\r' '\n' | grep -v '/1[0-9]*$' >&2)
python3 - "$OUT/realistic/summary.json" "$OUT/clean/summary.json" <<'PY'
import json, sys
s, c = (json.load(open(p)) for p in sys.argv[1:3])
aae, ret, comp = s["average_angular_error_deg"], s["return_ratio"], s["compass_pure_rotation_median_error_deg"]
print(f"realistic camera, mask {s['mask']}: AAE {aae:.2f} deg, return ratio {ret:.3f}, compass median {comp:.2f} deg, "
      f"{s['frames_per_second']:.0f} vectors/s; clean camera: AAE {c['average_angular_error_deg']:.2f} deg")
assert (s["camera"], s["mask"]) == ("realistic", "calibrated"), (s["camera"], s["mask"])
assert s["grid_positions"] == 168, s["grid_positions"]
assert aae <= 24.0, f"AAE {aae} > 24"
assert ret >= 0.95, f"return ratio {ret} < 0.95"
assert comp <= 2.0, f"compass median {comp} > 2"
assert (c["camera"], c["mask"]) == ("clean", "none"), (c["camera"], c["mask"])
assert c["average_angular_error_deg"] <= 15.0, f"clean camera: AAE {c['average_angular_error_deg']} > 15"
# The thesis configuration is reported beside it.
assert "thesis_configuration_aae_deg" in s
PY
test -s "$OUT/realistic/vector_map.png"
