#!/usr/bin/env bash
# Laser SLAM (the EKF and the graph back end) on MRPT's simulated loop against its true ground truth
# (tests/eval/slam_mrpt_simul_bounds.ini): within the bounds, no wrong loop closure, every scan paired
# with a ground-truth pose. Skipped (77) without Debian's mrpt-common datasets.
set -euo pipefail
BIN="$1"
SRC="$(cd "$(dirname "$0")/../.." && pwd)"
LOG=/usr/share/mrpt/datasets/graphslam-engine-demos/action_observations_map/simul.rawlog
if [ ! -f "$LOG" ] || [ ! -f "$LOG.GT.txt" ]; then
  echo "SKIP: needs $LOG and its .GT.txt (Debian's mrpt-common)"
  exit 77
fi
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT
status=0
"$BIN/eval-slam" --suite "$SRC/tests/eval/slam_mrpt_simul_bounds.ini" --out "$OUT" || status=$?
cat "$OUT/suite.md"
python3 - "$OUT" "$status" <<'PY'
import csv, json, os, sys
out, status = sys.argv[1], int(sys.argv[2])
s = json.load(open(os.path.join(out, "summary.json")))
row = next(csv.DictReader(open(os.path.join(out, "suite.csv"))))
n = "mrpt-simul"
bad = []
if status != 0: bad.append(f"eval-slam --suite exited {status}")
if not s.get(n + "_pass"): bad.append(f"EKF ATE {s.get(n + '_laser_slam_ate_rmse_m')} m beyond its bound")
if not s.get(n + "_graph_pass"): bad.append(f"graph ATE {s.get(n + '_graph_ate_rmse_m')} m beyond its bound or a wrong closure")
if s.get(n + "_loop_wrong", 1) != 0: bad.append(f"{s.get(n + '_loop_wrong')} wrong loop closures")
if int(row["scans"]) != 1733: bad.append(f"{row['scans']} scans, expected 1733")
if bad:
    sys.exit("FAIL: " + "; ".join(bad))
print(f"MRPT's simulated loop: EKF {s[n + '_laser_slam_ate_rmse_m']:.3f} m, graph {s[n + '_graph_ate_rmse_m']:.3f} m "
      f"against the true poses (dead reckoning {s[n + '_dead_reckoning_ate_rmse_m']:.2f} m)")
PY
