#!/usr/bin/env bash
# RatSLAM on the simulated indoor13 route with ground truth (eval-ratslam, shipped configs), 8 laps
# of its 2 x 2 m square (about 61 m): loop closures on the laps and none between distant places,
# RatSLAM's ATE bounded and below dead reckoning's, and at the end RatSLAM is nearer the truth than
# dead reckoning (the loop closures pull it back). A run of under a minute.
set -euo pipefail
BIN="$1"
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT
"$BIN/eval-ratslam" --scene indoor13 --laps 8 --out "$OUT" >/dev/null 2> >(tr '\r' '\n' | grep -v 'simulated' | grep -v '^[a-z_]* = ' >&2)
python3 - "$OUT/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
ate, dr = s["ratslam_ate_rmse_m"], s["dead_reckoning_ate_rmse_m"]
final, dr_final = s["ratslam_ate_unaligned_final_m"], s["dead_reckoning_ate_unaligned_final_m"]
print(f"ratslam ATE {ate:.3f} m (dead reckoning {dr:.3f} m), final error {final:.3f} m (dead reckoning {dr_final:.3f} m), "
      f"{s['ratslam_loop_closures']} loop closures ({s['ratslam_false_loop_closures']} false), "
      f"{s['ratslam_templates']} templates, {s['ratslam_experiences']} experiences, "
      f"{s['ratslam_ms_per_image_mean']:.2f} ms per image, {s['ratslam_ms_per_odometry_mean']:.3f} ms per odometry")
assert s["laps"] == 8, s["laps"]
assert s["ratslam_loop_closures"] >= 15, f"{s['ratslam_loop_closures']} loop closures < 15"
assert s["ratslam_false_loop_closures"] == 0, f"{s['ratslam_false_loop_closures']} loop closures between places > 1 m apart"
assert s["ratslam_inconsistent_links"] == 0, f"{s['ratslam_inconsistent_links']} inconsistent links"
assert ate <= 0.12, f"RatSLAM ATE {ate} m > 0.12 m"
assert ate < dr, f"RatSLAM ATE {ate} m is not below dead reckoning's {dr} m"
assert final < dr_final, f"RatSLAM's final error {final} m is not below dead reckoning's {dr_final} m"
assert 40 <= s["ratslam_templates"] <= 300, s["ratslam_templates"]
PY
test -s "$OUT/experience_map.png"
test -s "$OUT/errors.png"
