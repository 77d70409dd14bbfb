#!/usr/bin/env bash
# Run inside the private bus (./snapnav bus --): the demo deployment, short (30 s of the lab), with
# the fault: homing is killed with SIGKILL 15 s in. The launcher must restart it, the other
# processes must keep running (one run each), the recorder must have every message sim published,
# the restarted homing must publish again, and the demo's report must say so. EXPLORED (optional): a
# folder of the demo's explore step (tools/demo.sh --explore-only; ctest's demo_explored_memory) reused
# with --explored; without it the demo explores first.
set -euo pipefail
BIN="$1"; OUT="$2"; EXPLORED="${3:-}"
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
rm -rf "$OUT"
rc=0
"$ROOT/tools/demo.sh" "$BIN" --out "$OUT" --duration-s 30 --fault homing --fault-at-s 15 --no-bus-health --drop-log \
  ${EXPLORED:+--explored "$EXPLORED"} || rc=$?
fail() { echo "FAIL: $*" >&2; exit 1; }
[ -f "$OUT/summary.json" ] || fail "no report"
python3 - "$OUT/summary.json" "$OUT/processes/homing.log" <<'PY'
import json, re, sys
s = json.load(open(sys.argv[1]))
bad = []
if s.get("process_homing_runs") != 2: bad.append("homing runs %s (want 2)" % s.get("process_homing_runs"))
for name in ("sim", "recorder", "dead-reckoning", "laser-slam", "placecells", "landmarks", "navigator", "ratslam",
             "fused-slam", "viewer"):
    if s.get("process_%s_runs" % name) != 1: bad.append("%s runs %s (want 1)" % (name, s.get("process_%s_runs" % name)))
for ch in ("omni_frame", "laser_scan", "odometry", "pose_ground_truth", "drive_command", "pose_laser_slam"):
    p, r = s.get("delivery_%s_published" % ch), s.get("delivery_%s_recorded" % ch)
    print("%s: published %s, recorded %s" % (ch.upper(), p, r))
    if not p or p != r: bad.append("%s published %s recorded %s" % (ch, p, r))
frames = s.get("delivery_omni_frame_published", 0)
if frames < 250: bad.append("only %s frames in 30 s" % frames)
# The restarted homing published vectors, and the log holds those of both runs.
second = [int(m.group(1)) for m in re.finditer(r"^homing: frames (\d+)", open(sys.argv[2]).read(), re.M)]
vectors = s.get("homing_vector_vectors", 0)
print("homing: second run %s frames, %s vectors recorded of %s frames" % (second, vectors, frames))
if not second or second[-1] <= 0: bad.append("the restarted homing processed nothing")
elif not (second[-1] < vectors < frames): bad.append("vectors recorded %s: not both runs' (second run %s)" % (vectors, second[-1]))
if s.get("navigator_status_arrivals", 0) < 1: bad.append("the navigator reached no waypoint")
if bad: sys.exit("FAIL: " + "; ".join(bad))
PY
grep -q "^## Fault: kill -9 homing 15 s into the run (PASS)" "$OUT/demo-report.md" || fail "the demo report has no passing fault section"
[ "$rc" = 0 ] || fail "the demo exited with $rc"
echo PASS
