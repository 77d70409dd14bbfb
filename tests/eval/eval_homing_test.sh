#!/usr/bin/env bash
# The homing evaluation's error bounds on the simulated indoor 13x13 room (issue targets):
# AAE <= 15 degrees and return ratio >= 0.9 with the shipped configuration, raw images
# unwrapped, and the compass within 2 degrees (median) on pure rotations.
set -euo pipefail
BIN="$1"
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT
"$BIN/eval-homing" --scene indoor13 --quick --out "$OUT" 2> >(tr '\r' '\n' | grep -v '/1[0-9]*$' >&2)
python3 - "$OUT/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
aae, ret, comp = s["average_angular_error_deg"], s["return_ratio"], s["compass_pure_rotation_median_error_deg"]
print(f"AAE {aae:.2f} deg, return ratio {ret:.3f}, compass median {comp:.2f} deg, {s['frames_per_second']:.0f} vectors/s")
assert s["grid_positions"] == 168, s["grid_positions"]
assert aae <= 15.0, f"AAE {aae} > 15"
assert ret >= 0.9, f"return ratio {ret} < 0.9"
assert comp <= 2.0, f"compass median {comp} > 2"
# The thesis configuration is reported beside it.
assert "thesis_configuration_aae_deg" in s
PY
test -s "$OUT/vector_map.png"
