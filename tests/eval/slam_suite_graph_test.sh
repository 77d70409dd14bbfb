#!/usr/bin/env bash
# The graph back end (issue 22) on real logs under ctest: eval-slam --suite with
# tests/eval/slam_suite_graph_bounds.ini and --set backend=graph (the shipped config/laser_slam.ini
# otherwise): each run's graph ATE within its own bound (goal_ate_m: the measured ATE with margin) and
# no worse than dead reckoning, no loop closure wrong against the reference beyond the run's allowance
# (below), the EKF beside it in every row. Skipped (77) without ../shared beside the clone.
set -euo pipefail
BIN="$1"
SRC="$(cd "$(dirname "$0")/../.." && pwd)"
DATA="$SRC/../shared/data"
if [ ! -f "$DATA/laser/mit-csail.clf" ] || [ ! -f "$SRC/../shared/tools/carmen_raw_like.py" ]; then
  echo "SKIP: needs ../shared/data/laser (the real logs) and ../shared/tools/carmen_raw_like.py beside the clone"
  exit 77
fi
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT
status=0
"$BIN/eval-slam" --suite "$SRC/tests/eval/slam_suite_graph_bounds.ini" --set backend=graph --out "$OUT" || status=$?
cat "$OUT/suite.md"
if [ "$status" -ne 0 ]; then
  echo "FAIL: eval-slam --suite exited $status (a run beyond its bound or worse than dead reckoning; suite.md above)"
  exit 1
fi
python3 - "$OUT" <<'PY'
import json, os, sys
out = sys.argv[1]
s = json.load(open(os.path.join(out, "summary.json")))
assert s["backend"] == "graph", s["backend"]
runs = [k[: -len("_graph_ate_rmse_m")] for k in s if k.endswith("_graph_ate_rmse_m")]
assert len(runs) == s["runs"] and len(runs) >= 5, runs
# Closures the reference calls wrong (their two poses more than 0.5 m or 5 deg apart in it): none,
# but on CSAIL, whose reference follows the odometry's late headings in fast turns, and one each on
# the two every-3rd-scan runs since the front end has the walls (2026-12-07: Freiburg's 5.2 deg in
# heading only, where the reference's heading jitters; ACES's 0.65 m along a corridor, a wrong one;
# over all 101 real runs the walls left as many closures wrong as before, 163 against 166:
# docs/experiments/2026-12-07-graph-front-end-walls.md).
allowed_wrong = {"csail": 20, "aces-n1e3": 1, "freiburg-079-n1e3": 1}
for n in runs:
    assert s[n + "_pass"], n
    assert s[n + "_loop_accepted"] > 0, n + ": no loop closure"
    assert s[n + "_loop_wrong"] <= allowed_wrong.get(n, 0), "%s: %d wrong closures" % (n, s[n + "_loop_wrong"])
    assert s[n + "_graph_ate_rmse_m"] <= s[n + "_ekf_ate_rmse_m"] * 1.5, n + ": far worse than the EKF"
    assert os.path.getsize(os.path.join(out, n, "graph_map.png")) > 10000, n
print("graph suite: %d runs within their bounds" % len(runs))
PY
