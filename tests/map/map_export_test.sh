#!/usr/bin/env bash
# map-export on a simulated run (slam-sim-eval --write-log: LASER_SCAN, ODOMETRY and
# POSE_GROUND_TRUTH of 40 s in the indoor13 scene): the map from the laser SLAM run over the log
# (the EKF, and the graph back end with --set backend=graph) and the map from the recorded ground
# truth (--pose-channel) agree (the SLAM map's occupied pixels lie within 2 pixels of the truth's);
# every file is written and the YAML points at the PGM; on the simulator's corridor (2 laps, the
# graph closing its loops) the graph's export is nearer the truth than the EKF's; a missing log and
# a log without scans are errors that name the file.
set -euo pipefail
BIN="$1"
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT
"$BIN/slam-sim-eval" --scene indoor13 --duration-s 40 --write-log --out "$OUT/sim" > /dev/null
"$BIN/map-export" "$OUT/sim/sim.lcmlog" --out "$OUT/slam"
"$BIN/map-export" "$OUT/sim/sim.lcmlog" --pose-channel POSE_GROUND_TRUTH --out "$OUT/truth"
# The graph back end (backend = graph): the scans at their optimized poses.
"$BIN/map-export" "$OUT/sim/sim.lcmlog" --set backend=graph --out "$OUT/graph" 2> "$OUT/graph.err"
grep -q "graph back end" "$OUT/graph.err" || { echo "FAIL: map-export did not run the graph back end:"; cat "$OUT/graph.err"; exit 1; }
grep -q "the scans at their optimized poses" "$OUT/graph.err" || { cat "$OUT/graph.err"; exit 1; }
for d in slam graph; do
  for f in map.pgm map.yaml map.gridmap map.simplemap map.png map_trajectory.csv; do
    test -s "$OUT/$d/$f" || { echo "FAIL: $OUT/$d/$f missing"; exit 1; }
  done
done
for d in slam graph; do
python3 - "$OUT" "$d" <<'PY'
import math, sys
out, est = sys.argv[1], sys.argv[2]
def pgm(path):
    data = open(path, 'rb').read()
    parts, i = [], 0
    while len(parts) < 4:
        if data[i:i+1] == b'#':
            i = data.index(b'\n', i) + 1
            continue
        j = i
        while data[j:j+1] not in b' \n': j += 1
        parts.append(data[i:j]); i = j + 1
    assert parts[0] == b'P5', parts
    w, h = int(parts[1]), int(parts[2])
    px = data[i:i + w * h]
    assert len(px) == w * h, (len(px), w * h)
    return w, h, px
def yaml(path):
    d = {}
    for line in open(path):
        k, v = line.split(':', 1)
        d[k.strip()] = v.strip()
    return d
ys, yt = yaml(out + '/' + est + '/map.yaml'), yaml(out + '/truth/map.yaml')
assert ys['image'] == 'map.pgm' and ys['mode'] == 'trinary' and float(ys['resolution']) == 0.05, ys
def occupied(dirname):
    y = yaml(out + '/' + dirname + '/map.yaml')
    ox, oy, _ = [float(v) for v in y['origin'].strip('[]').split(',')]
    w, h, px = pgm(out + '/' + dirname + '/map.pgm')
    res = float(y['resolution'])
    cells = set()
    for r in range(h):
        for c in range(w):
            if px[r * w + c] == 0:
                cells.add((math.floor(ox / res + 0.5) + c, math.floor(oy / res + 0.5) + (h - 1 - r)))
    return cells
s, t = occupied(est), occupied('truth')
# The laser SLAM's map frame is its start pose, the truth's the world's: place the SLAM's cells by
# the first scan's pose in each (map_trajectory.csv).
import csv, math
a = next(csv.DictReader(open(out + '/' + est + '/map_trajectory.csv')))
b = next(csv.DictReader(open(out + '/truth/map_trajectory.csv')))
assert a['utime'] == b['utime'], (a, b)
ta = float(a['theta_rad'])
th0 = float(b['theta_rad']) - ta
ax, ay = float(a['x_m']), float(a['y_m'])
x0 = float(b['x_m']) - (math.cos(th0) * ax - math.sin(th0) * ay)
y0 = float(b['y_m']) - (math.sin(th0) * ax + math.cos(th0) * ay)
res = 0.05
def to_world(cell):
    x, y = (cell[0] + 0.5) * res, (cell[1] + 0.5) * res
    wx = x0 + math.cos(th0) * x - math.sin(th0) * y
    wy = y0 + math.sin(th0) * x + math.cos(th0) * y
    return (math.floor(wx / res), math.floor(wy / res))
s = {to_world(c) for c in s}
near = sum(1 for (x, y) in s if any((x + dx, y + dy) in t for dx in range(-2, 3) for dy in range(-2, 3)))
print(f"map-export test ({est}): {len(s)} occupied cells from the laser SLAM, {len(t)} from the ground truth; "
      f"{near / max(1, len(s)):.3f} of the SLAM's within 2 cells of the truth's")
assert len(s) > 500 and len(t) > 500
assert near >= 0.9 * len(s), near
PY
done
# Where the graph closes loops (the corridor, 2 laps, 174 m: 8 corrections) its export places the
# scans at the optimized poses: its trajectory is nearer the truth than the EKF's; a live run's
# recorded poses, corrected by its tables, are that trajectory.
"$BIN/slam-sim-eval" --scene corridor --laps 2 --write-log --out "$OUT/cor" > /dev/null
"$BIN/map-export" "$OUT/cor/sim.lcmlog" --out "$OUT/cor-ekf" 2> /dev/null
"$BIN/map-export" "$OUT/cor/sim.lcmlog" --set backend=graph --out "$OUT/cor-graph" 2> "$OUT/cor-graph.err"
"$BIN/map-export" "$OUT/cor/sim.lcmlog" --pose-channel POSE_GROUND_TRUTH --out "$OUT/cor-truth" 2> /dev/null
# The same graph run live (replay: laser-slam with backend = graph, in lockstep), its published poses
# recorded: as published (--correction-channel '') they are the live estimate; corrected by the last
# of its correction tables (LASER_SLAM_CORRECTION) they are the optimized trajectory.
"$BIN/replay" --only laser-slam --set laser-slam:laser_slam.backend=graph --with-inputs --out "$OUT/cor-live.lcmlog" \
  "$OUT/cor/sim.lcmlog" > /dev/null 2>&1
"$BIN/map-export" "$OUT/cor-live.lcmlog" --pose-channel POSE_LASER_SLAM --out "$OUT/cor-live" 2> "$OUT/cor-live.err"
grep -q "as correction [0-9]* on LASER_SLAM_CORRECTION puts them" "$OUT/cor-live.err" || { cat "$OUT/cor-live.err"; exit 1; }
"$BIN/map-export" "$OUT/cor-live.lcmlog" --pose-channel POSE_LASER_SLAM --correction-channel '' --out "$OUT/cor-published" 2> /dev/null
python3 - "$OUT" <<'PY'
import csv, math, sys
out = sys.argv[1]
def traj(d):
    return [(float(r['x_m']), float(r['y_m'])) for r in csv.DictReader(open(out + '/' + d + '/map_trajectory.csv'))]
def ate(S, R):  # RMSE after the best rotation and translation (SE(2))
    n = len(S)
    ms = (sum(p[0] for p in S) / n, sum(p[1] for p in S) / n)
    mr = (sum(p[0] for p in R) / n, sum(p[1] for p in R) / n)
    sxx = sum((s[0] - ms[0]) * (q[0] - mr[0]) + (s[1] - ms[1]) * (q[1] - mr[1]) for s, q in zip(S, R))
    sxy = sum((s[0] - ms[0]) * (q[1] - mr[1]) - (s[1] - ms[1]) * (q[0] - mr[0]) for s, q in zip(S, R))
    a = math.atan2(sxy, sxx)
    c, sn = math.cos(a), math.sin(a)
    return math.sqrt(sum((c * (p[0] - ms[0]) - sn * (p[1] - ms[1]) + mr[0] - q[0]) ** 2 +
                         (sn * (p[0] - ms[0]) + c * (p[1] - ms[1]) + mr[1] - q[1]) ** 2 for p, q in zip(S, R)) / n)
g, e, t = traj('cor-graph'), traj('cor-ekf'), traj('cor-truth')
assert len(g) == len(e) == len(t) and len(t) > 5000, (len(g), len(e), len(t))
ag, ae = ate(g, t), ate(e, t)
print(f"map-export test (corridor): trajectory ATE graph {ag:.4f} m, EKF {ae:.4f} m")
assert ag < 0.9 * ae and ag < 0.07, (ag, ae)
al, ap = ate(traj('cor-live'), t), ate(traj('cor-published'), t)
print(f"map-export test (corridor, live): published poses {ap:.4f} m, corrected by the last table {al:.4f} m")
assert abs(al - ag) < 1e-4 and al < 0.7 * ap, (al, ag, ap)
PY
grep -q "corrections; the scans at their optimized poses" "$OUT/cor-graph.err" || { cat "$OUT/cor-graph.err"; exit 1; }
if "$BIN/map-export" "$OUT/nothing.lcmlog" --out "$OUT/x" 2> "$OUT/err"; then echo "FAIL: a missing log exported"; exit 1; fi
grep -q "nothing.lcmlog" "$OUT/err" || { echo "FAIL: the error does not name the log:"; cat "$OUT/err"; exit 1; }
if "$BIN/map-export" "$OUT/slam/map.pgm" --out "$OUT/x" 2> "$OUT/err"; then echo "FAIL: a PGM exported as a log"; exit 1; fi
grep -q "map.pgm" "$OUT/err" || { echo "FAIL: the error does not name the file:"; cat "$OUT/err"; exit 1; }
echo "map-export test: passed"
