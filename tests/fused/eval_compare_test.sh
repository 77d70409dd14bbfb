#!/usr/bin/env bash
# The SLAM comparison's bounds (issue 8), a short variant of ./snapnav eval compare: 150 s of the
# corridor route (down the left wing, along the corridor) and the kidnapped robot (carried at 10 s
# to the mirrored place in the right wing, 40 s). Fused SLAM's ATE (aligned, and in the scene
# frame) is below laser-only SLAM's and dead reckoning's, the visual measurements are mostly
# accepted, and the kidnapping is recovered within 10 s of simulated time (laser-only is not).
set -euo pipefail
BIN="$1"
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT
"$BIN/eval-compare" --scene corridor --duration-s 150 --with-kidnap-run --kidnap-run-s 40 --ratslam-rate-hz 5 \
  --out "$OUT" > "$OUT/stdout.txt"
cat "$OUT/stdout.txt"
python3 - "$OUT/summary.json" <<'PY'
import json, math, sys
s = json.load(open(sys.argv[1]))
assert s["runs"] == ["corridor", "corridor_kidnap"], s["runs"]
c = "corridor_"
fused, laser, dr = (s[c + m + "_ate_rmse_m"] for m in ("fused_slam", "laser_slam", "dead_reckoning"))
fused_u, laser_u, dr_u = (s[c + m + "_ate_unaligned_rmse_m"] for m in ("fused_slam", "laser_slam", "dead_reckoning"))
print(f"corridor ATE aligned: fused {fused:.4f} laser {laser:.4f} dead reckoning {dr:.4f} m; "
      f"scene frame: fused {fused_u:.4f} laser {laser_u:.4f} dead reckoning {dr_u:.4f} m")
assert fused < laser and fused < dr, "fused SLAM's aligned ATE is not the lowest"
assert fused_u < laser_u and fused_u < dr_u, "fused SLAM's ATE in the scene frame is not the lowest"
acc, rej = s[c + "visual_measurements_accepted"], s[c + "visual_measurements_rejected"]
assert acc > 2 * rej, f"visual measurements {acc} accepted, {rej} rejected"
k = "corridor_kidnap_"
rec = s[k + "kidnap_recovery_s"]
print(f"kidnap: recovered in {rec} s, {s[k + 'relocalizations']} relocalisations; "
      f"final error fused {s[k + 'fused_slam_ate_unaligned_final_m']:.3f} m, laser {s[k + 'laser_slam_ate_unaligned_final_m']:.3f} m")
assert rec is not None and rec <= 10.0, f"kidnap recovery {rec} s > 10 s"
assert s[k + "fused_slam_ate_unaligned_final_m"] < 0.3
assert s[k + "laser_slam_ate_unaligned_final_m"] > 5.0  # the laser alone stays in the wrong wing
PY
for f in compare.md compare.csv corridor/trajectories.png corridor/errors.png corridor/timing.png corridor_kidnap/errors.png; do
  test -s "$OUT/$f"
done
