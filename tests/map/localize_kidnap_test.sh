#!/usr/bin/env bash
# Localization in a saved map with a kidnapping, on the private bus (./snapnav bus --):
# 1. the map, made beforehand: slam-sim-eval drives the indoor13 room for 60 s (lockstep) and
#    map-export turns the run into map.yaml + map.pgm (the poses the simulator recorded);
# 2. sim (real time, another seed) drives the route again and at 25 s carries the robot to the
#    other side of the room turned round (kidnap_at_s, kidnap_to: odometry does not see it);
#    laser-slam --mode localize --map map.yaml starts knowing nothing; the recorder keeps the
#    ground truth, the poses and the status;
# 3. map-export --live writes the grid laser-slam publishes (the saved map) while it runs;
# 4. from the log: the first pose within 0.3 m / 10 deg of the truth after the start and after
#    the kidnapping (goal: relocalized within 10 s), the status lost in between, the poses after
#    the recovery on the truth; the live export a map_server map equal to the saved one.
set -euo pipefail
BIN="$1"; CONFIG="$2"; HERE="$(cd "$(dirname "$0")" && pwd)"
OUT="${3:-}"
if [ -z "$OUT" ]; then OUT="$(mktemp -d)"; KEEP=0; else KEEP=1; fi
mkdir -p "$OUT"
pids=()
cleanup() { for p in "${pids[@]}"; do kill -INT "$p" 2>/dev/null || true; done; }
trap cleanup EXIT
fail() { echo "FAIL: $*" >&2; for f in "$OUT"/*.err; do echo "--- $f" >&2; tail -15 "$f" >&2; done; exit 1; }

"$BIN/slam-sim-eval" --scene indoor13 --duration-s 60 --write-log --out "$OUT/mapping" > /dev/null
"$BIN/map-export" "$OUT/mapping/sim.lcmlog" --pose-channel POSE_GROUND_TRUTH --out "$OUT/map" > "$OUT/map-export.out"
cat "$OUT/map-export.out"

sed -e 's/^mode = .*/mode = realtime/' -e 's/^duration_s = .*/duration_s = 45/' -e 's/^seed = .*/seed = 7/' \
    -e 's/^kidnap_at_s = .*/kidnap_at_s = 25/' -e 's/^kidnap_to = .*/kidnap_to = 5.5,2.2,150/' \
    -e 's/^rate_hz = 10$/rate_hz = 10/' -e 's/^encoding = .*/encoding = gray8/' "$CONFIG/sim.ini" > "$OUT/sim.ini"
# Camera frames are not needed: one a second, small.
python3 - "$OUT/sim.ini" <<'PY'
import re, sys
p = sys.argv[1]; s = open(p).read()
sec = s.index('[camera]'); end = s.index('[', sec + 1)
cam = re.sub(r'^rate_hz = .*$', 'rate_hz = 1', s[sec:end], flags=re.M)
cam = re.sub(r'^width_px = .*$', 'width_px = 160', cam, flags=re.M)
cam = re.sub(r'^height_px = .*$', 'height_px = 120', cam, flags=re.M)
s = s[:sec] + cam + s[end:]
mir = s.index('[mirror]'); end = s.index('[', mir + 1)
m = s[mir:end]
for k, v in (('center_x_px', '80'), ('center_y_px', '60'), ('inner_radius_px', '10'), ('outer_radius_px', '55')):
    m = re.sub(r'^%s = .*$' % k, '%s = %s' % (k, v), m, flags=re.M)
s = s[:mir] + m + s[end:]
open(p, 'w').write(s)
PY

"$BIN/laser-slam" --mode localize --map "$OUT/map/map.yaml" > "$OUT/laser-slam.out" 2> "$OUT/laser-slam.err" &
pids+=($!); slam=$!
for i in $(seq 100); do grep -q "^laser-slam: odometry from" "$OUT/laser-slam.err" && break; sleep 0.1; done
grep -q "^laser-slam: odometry from" "$OUT/laser-slam.err" || fail "laser-slam did not start"
"$BIN/recorder" --channel 'POSE_GROUND_TRUTH|POSE_LASER_SLAM|LOCALIZATION_STATUS|LASER_SLAM_GRID' "$OUT/run.lcmlog" \
    > "$OUT/recorder.out" 2> "$OUT/recorder.err" &
pids+=($!); rec=$!
sleep 1
"$BIN/sim" --config "$OUT/sim.ini" > "$OUT/sim.out" 2> "$OUT/sim.err" || fail "sim failed"
"$BIN/map-export" --live --out "$OUT/live" --timeout-s 15 > "$OUT/live.out" 2> "$OUT/live.err" || fail "map-export --live failed"
cat "$OUT/live.out"
kill -INT "$slam" "$rec"
wait "$slam" || fail "laser-slam exited with $?"
wait "$rec" || true
trap - EXIT
grep "^laser-slam: localize in\|^laser-slam: mean update" "$OUT/laser-slam.err"

python3 - "$OUT" "$HERE" <<'PY'
import bisect, math, sys
out, here = sys.argv[1], sys.argv[2]
sys.path.insert(0, here)
import lcmlog
truth, est, status, grids = [], [], [], []
for ch, _, data in lcmlog.events(out + '/run.lcmlog'):
    if ch == 'POSE_GROUND_TRUTH': truth.append(lcmlog.pose(data))
    elif ch == 'POSE_LASER_SLAM': est.append(lcmlog.pose(data))
    elif ch == 'LOCALIZATION_STATUS': status.append(lcmlog.localization_status(data))
    elif ch == 'LASER_SLAM_GRID': grids.append(lcmlog.occupancy_grid(data))
assert truth and est and status, (len(truth), len(est), len(status))
assert grids and grids[0]['source'].startswith('map_file:'), 'no saved map on LASER_SLAM_GRID'
tt = [t['utime'] for t in truth]
def truth_at(u):
    i = bisect.bisect_left(tt, u)
    best = min((j for j in (i - 1, i) if 0 <= j < len(tt)), key=lambda j: abs(tt[j] - u))
    return truth[best] if abs(tt[best] - u) <= 30000 else None
# The kidnapping: the ground truth jumps.
kidnap = None
for a, b in zip(truth, truth[1:]):
    if math.hypot(b['x'] - a['x'], b['y'] - a['y']) > 0.5:
        kidnap = b['utime']; break
assert kidnap, 'no kidnapping in the ground truth'
start = truth[0]['utime']
def ok(e):
    t = truth_at(e['utime'])
    if t is None: return None
    d = math.hypot(e['x'] - t['x'], e['y'] - t['y'])
    h = abs(math.atan2(math.sin(e['theta'] - t['theta']), math.cos(e['theta'] - t['theta'])))
    return d <= 0.3 and h <= math.radians(10)
first = next((e['utime'] for e in est if e['utime'] < kidnap and ok(e)), None)
assert first is not None, 'never localized before the kidnapping'
after = next((e['utime'] for e in est if e['utime'] >= kidnap and ok(e)), None)
assert after is not None, 'never relocalized after the kidnapping'
# Noticed: tracking declared lost after the kidnapping (the status counts it; the global search
# may find the pose on the very scan that declared it, so LOST need not be published).
before = [s for s in status if s['utime'] < kidnap]
lost = status[-1]['losses'] > (before[-1]['losses'] if before else 0)
assert status[-1]['map'].endswith('map.yaml'), status[-1]['map']
post = [ok(e) for e in est if e['utime'] >= after]
post = [p for p in post if p is not None]
good = sum(post) / max(1, len(post))
print('localize kidnap test: localized %.2f s after the start; kidnapped at %.2f s; relocalized %.2f s after the kidnapping '
      '(goal <= 10 s); lost in between: %s (%d global searches, %d relocalizations); %d of %d poses since then within 0.3 m / 10 deg (%.3f)'
      % ((first - start) * 1e-6, (kidnap - start) * 1e-6, (after - kidnap) * 1e-6, lost, status[-1]['global_searches'], status[-1]['relocalizations'], sum(post), len(post), good))
assert (after - kidnap) * 1e-6 <= 10, 'relocalization took more than 10 s'
assert lost, 'the kidnapping was never noticed (no loss counted after it)'
assert good >= 0.95, 'the poses after the recovery are off the truth'
# The live export: a map_server map equal to the saved one.
def yaml(p):
    d = {}
    for line in open(p):
        k, v = line.split(':', 1); d[k.strip()] = v.strip()
    return d
def pgm(p):
    data = open(p, 'rb').read()
    parts, i = [], 0
    while len(parts) < 4:
        if data[i:i+1] == b'#':
            i = data.index(b'\n', i) + 1; continue
        j = i
        while data[j:j+1] not in b' \n': j += 1
        parts.append(data[i:j]); i = j + 1
    assert parts[0] == b'P5' and parts[3] == b'255', parts
    w, h = int(parts[1]), int(parts[2])
    return w, h, data[i:i + w * h]
ys, yl = yaml(out + '/map/map.yaml'), yaml(out + '/live/map.yaml')
for k in ('image', 'resolution', 'origin', 'negate', 'occupied_thresh', 'free_thresh', 'mode'):
    assert k in yl, ('live map.yaml lacks', k)
assert yl['image'] == 'map.pgm' and yl['mode'] == 'trinary' and float(yl['resolution']) == float(ys['resolution']), yl
ol = [float(v) for v in yl['origin'].strip('[]').split(',')]
os_ = [float(v) for v in ys['origin'].strip('[]').split(',')]
assert len(ol) == 3 and all(abs(a - b) < 1e-4 for a, b in zip(ol, os_)), (ol, os_)
ws, hs, ps = pgm(out + '/map/map.pgm')
wl, hl, pl = pgm(out + '/live/map.pgm')
assert (ws, hs) == (wl, hl), ((ws, hs), (wl, hl))
assert set(pl) <= {0, 205, 254}, set(pl)
same = sum(1 for a, b in zip(ps, pl) if a == b) / len(ps)
print('localize kidnap test: live export %d x %d, %.4f of its pixels as the saved map' % (wl, hl, same))
assert same >= 0.999, same
PY
[ "$KEEP" = 1 ] || rm -rf "$OUT"
echo "localize kidnap test: passed"
