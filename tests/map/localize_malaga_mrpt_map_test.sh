#!/usr/bin/env bash
# Localization in a map another tool made (ctest localize_malaga_in_mrpts_map): MRPT's own map of the
# Malaga building (malaga-cs-fac-building.simplemap.gz, Debian's mrpt-common: not made from this run
# or by snapnav), the Malaga loop (the real laser + odometry rawlog beside it) localized in it from 4
# unknown starts, against icp-slam's trajectory (eval-slam --icp-slam, MRPT's icp-slam as the Malaga
# suite run uses it). Every start relocalized within 10 s of message time, no wrong global pose, no
# loss, the ATE in the map's frame below 0.25 m (two SLAM systems' maps of one building: ~0.1 m
# apart). Skipped (77) without the dataset or icp-slam.
set -euo pipefail
BIN="$1"
D=/usr/share/mrpt/datasets
R="$D/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog"
M="$D/malaga-cs-fac-building.simplemap.gz"
if [ ! -f "$R" ] || [ ! -f "$M" ]; then
  echo "SKIP: needs $R and $M (Debian's mrpt-common)"
  exit 77
fi
if ! command -v icp-slam > /dev/null; then
  echo "SKIP: needs MRPT's icp-slam (Debian's mrpt-apps) for the reference"
  exit 77
fi
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT
"$BIN/log-import" rawlog "$R" --out "$OUT/malaga.lcmlog" > "$OUT/import.txt" 2>&1
"$BIN/eval-slam" --log "$OUT/malaga.lcmlog" --icp-slam "$R" --out "$OUT/icp" > "$OUT/eval-slam.txt" 2>&1
"$BIN/localize-eval" "$OUT/malaga.lcmlog" --map "$M" --reference "$OUT/icp/icp_slam_trajectory.csv" --starts 4 \
  --out "$OUT/eval"
python3 "$(dirname "$0")/check_localize.py" "$OUT/eval/localize.json" 4 10 0.25 "the Malaga loop in MRPT's map of the building"
