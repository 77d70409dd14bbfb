#!/usr/bin/env bash
# Localization in a saved map against a true ground truth (ctest localize_mrpt_simulated_loop): MRPT's
# simulated loop (Debian's mrpt-common), its map made by laser SLAM and map-export, then localize-eval
# from 4 unknown starts against simul.rawlog.GT.txt. Every start relocalized within 10 s of message
# time (issue 22's kidnap goal), no wrong global pose, no loss, the ATE in the map's frame below 0.3 m
# (the map is laser SLAM's, not the truth's). An open hall: its walls lie 10-30 m from the robot
# (docs/localization.md, the global search's range). Skipped (77) without the dataset.
set -euo pipefail
BIN="$1"
R=/usr/share/mrpt/datasets/graphslam-engine-demos/action_observations_map/simul.rawlog
if [ ! -f "$R" ] || [ ! -f "$R.GT.txt" ]; then
  echo "SKIP: needs $R and its .GT.txt (Debian's mrpt-common)"
  exit 77
fi
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT
"$BIN/log-import" rawlog "$R" --out "$OUT/simul.lcmlog" > "$OUT/import.txt" 2>&1
"$BIN/map-export" "$OUT/simul.lcmlog" --out "$OUT/map" > "$OUT/map-export.txt" 2>&1
"$BIN/localize-eval" "$OUT/simul.lcmlog" --map "$OUT/map/map.yaml" --reference "$R.GT.txt" --starts 4 --out "$OUT/eval"
python3 "$(dirname "$0")/check_localize.py" "$OUT/eval/localize.json" 4 10 0.3 "MRPT's simulated loop"
