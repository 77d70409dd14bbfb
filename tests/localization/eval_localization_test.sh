#!/usr/bin/env bash
# The place-cell localization bound on the simulated indoor 13x13 room (issue 6): the default
# configuration (bearing measure with smallest-distance refinement, distance filter on,
# interpolated estimate) against the grid memory, 30 random off-grid test positions with random
# headings: mean position error <= 0.10 m. The thesis' configuration (nearest cell) is reported
# beside it. A reduced run (grid memory, one measure) of about a minute.
set -euo pipefail
BIN="$1"
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT
"$BIN/eval-localization" --scene indoor13 --memories grid --measures bearing-smallest --filters on --tests 30 \
  --out "$OUT" 2> >(tr '\r' '\n' | grep -v '/[0-9]*$' | grep -v '^  ' >&2)
python3 - "$OUT/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
mean, mx = s["mean_localization_error_m"], s["max_localization_error_m"]
print(f"mean error {mean:.3f} m, max {mx:.3f} m, thesis configuration (nearest cell) "
      f"{s['thesis_configuration_mean_localization_error_m']:.3f} m, heading {s['mean_heading_error_deg']:.2f} deg, "
      f"{s['ms_per_query']:.1f} ms/query, grid {s['grid_cells']} cells")
assert s["test_positions"] == 30, s["test_positions"]
assert s["grid_cells"] == 169, s["grid_cells"]
assert s["queries_without_answer"] == 0, s["queries_without_answer"]
assert mean <= 0.10, f"mean localization error {mean} m > 0.10 m"
assert s["mean_heading_error_deg"] <= 5.0, f"heading error {s['mean_heading_error_deg']} deg > 5"
PY
test -s "$OUT/map_grid.png"
test -s "$OUT/results.csv"
