#!/usr/bin/env bash
# Route following's error bound on the simulated indoor 13x13 room (issue 6): one lap of thesis
# route 1 with place cells, odometry and homing ends within 15 cm of every waypoint, and does better
# than odometry alone at the end of the lap.
set -euo pipefail
BIN="$1"
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT
"$BIN/eval-route" --scene indoor13 --route 1 --laps 1 --seed 1 --out "$OUT" 2> >(tr '\r' '\n' | grep -v ' ms/step' >&2)
python3 - "$OUT/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
print(f"route 1, {s['laps_completed']} lap(s), {s['arrivals']} waypoints: error mean {s['waypoint_error_mean_m']*100:.1f} cm, "
      f"max {s['waypoint_error_max_m']*100:.1f} cm; odometry only: max {s['dead_reckoning_waypoint_error_max_m']*100:.1f} cm; "
      f"{s['ms_per_step']:.0f} ms/step")
assert s["laps_completed"] == 1, s["laps_completed"]
assert s["arrivals"] == s["waypoints_per_lap"] == 5, (s["arrivals"], s["waypoints_per_lap"])
assert s["waypoint_error_max_m"] <= 0.15, f"max waypoint error {s['waypoint_error_max_m']} > 0.15 m"
assert s["tracking_error_max_m"] <= 0.15, f"tracked estimate off by {s['tracking_error_max_m']} m"
assert s["fixes_accepted"] > 100, s["fixes_accepted"]
PY
test -s "$OUT/trajectory.png"
test -s "$OUT/report.md"
