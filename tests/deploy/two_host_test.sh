#!/usr/bin/env bash
# Two hosts on one machine (ctest two_host_demo_and_clock_offset, run inside ./snapnav bus): the demo
# deployment with sim on a "robot" network namespace and everything else on a "base" one, joined by
# a veth pair (tools/demo.sh --two-host). Two runs of 30 s:
#  A. raw 1 MB frames, jumbo-frame link (MTU 9000): the probes byte-identical across the link and
#     through the base's logger and replay; every message of every channel arrives (each publisher's
#     count against the log and against every subscriber); the robot's sensors in the base's log;
#     the navigator's commands back at the robot; a 1 MB frame across the idle link in < 3 ms median;
#  B. JPEG frames (the default), Ethernet MTU, the robot's clock 2 s off: every channel in the base's
#     log, the sensors' and every estimator's outputs alike, carries the robot's time (2 s off the
#     base's clock), nothing is rejected or ignored as stale, the robot is driven as in A, and each
#     estimator's error is as in A (message time only: nothing mixes in the base's clock).
set -euo pipefail
# EXPLORED (optional): an explored memory's folder both runs reuse (ctest's demo_explored_memory);
# without it run A explores and B reuses A's.
BIN="$1"; OUT="$2"; EXPLORED="${3:-}"
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
rm -rf "$OUT"; mkdir -p "$OUT"
rc_a=0; rc_b=0
explored_a=(); [ -z "$EXPLORED" ] || explored_a=(--explored "$EXPLORED")
"$ROOT/tools/demo.sh" "$BIN" --two-host --raw-frames --link-mtu 9000 --duration-s 30 --drop-log "${explored_a[@]}" \
  --out "$OUT/a" || rc_a=$?
"$ROOT/tools/demo.sh" "$BIN" --two-host --clock-offset-s 2 --link-goal-ms 10 --duration-s 30 --no-bus-health \
  --explored "${EXPLORED:-$OUT/a}" --out "$OUT/b" || rc_b=$?
python3 - "$OUT/a" "$OUT/b" "$rc_a" "$rc_b" <<'PY'
import json, os, re, sys
a_dir, b_dir, rc_a, rc_b = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
def load(d, f): return json.load(open(os.path.join(d, f)))
bad = []
sa, sb = load(a_dir, "summary.json"), load(b_dir, "summary.json")
la, lb = load(a_dir, "link.json"), load(b_dir, "link.json")
if rc_a: bad.append(f"run A: the demo exited {rc_a} (demo-report.md)")
if rc_b: bad.append(f"run B: the demo exited {rc_b} (demo-report.md)")
for name, s, l in (("A", sa, la), ("B", sb, lb)):
    if not l.get("link_ok"): bad.append(f"run {name}: the link check failed (link.md)")
    for ch in ("omni_frame", "laser_scan", "odometry", "pose_ground_truth"):
        if not (l.get(f"link_{ch}_published", 0) >= 300 and l.get(f"link_{ch}_recorded") == l.get(f"link_{ch}_published")):
            bad.append(f"run {name}: {ch} published {l.get(f'link_{ch}_published')} recorded {l.get(f'link_{ch}_recorded')}")
    if s.get("delivery_lost_total") != 0 or s.get("delivery_missed_by_subscribers_total") != 0:
        bad.append(f"run {name}: lost {s.get('delivery_lost_total')}, missed {s.get('delivery_missed_by_subscribers_total')}")
    if l.get("link_drive_commands_received_by_robot", 0) < 1000 or \
            l["link_drive_commands_received_by_robot"] != l["link_drive_commands_published"]:
        bad.append(f"run {name}: commands back {l.get('link_drive_commands_received_by_robot')} of {l.get('link_drive_commands_published')}")
    if s.get("navigator_status_arrivals", 0) < 1: bad.append(f"run {name}: the navigator reached no waypoint")
if not la.get("link_idle_frame_latency_median_ms", 99) < 3: bad.append(f"run A: 1 MB frame median {la.get('link_idle_frame_latency_median_ms')} ms")
print(f"A: 1 MB frames across the idle link: median {la.get('link_idle_frame_latency_median_ms')} ms, p95 {la.get('link_idle_frame_latency_p95_ms')} ms; "
      f"during the lab: median {la.get('link_lab_frame_latency_median_ms')} ms, p95 {la.get('link_lab_frame_latency_p95_ms')} ms")
# B: the robot's clock 2 s off, everywhere in the base's log.
clocks = {k[6:-len("_log_minus_utime_s")]: v for k, v in lb.items() if k.startswith("clock_")}
print("B: log time - utime per channel: " + ", ".join(f"{k} {v:+.3f} s" for k, v in sorted(clocks.items())))
if len(clocks) < 15 or any(abs(v + 2) > 0.5 for v in clocks.values()): bad.append("run B: a channel not in the robot's time")
sim_b = open(os.path.join(b_dir, "processes", "sim.log")).read()
m = re.search(r"(\d+) drive commands, (\d+) ignored as stale, (\d+) watchdog stops", sim_b)
if not m or int(m.group(2)) or int(m.group(3)): bad.append(f"run B: sim: {m.group(0) if m else 'no done line'}")
# Each estimator as in A: its outputs and its error.
print("estimator           poses A/B      ATE A (m)  ATE B (m)")
for ch in ("pose_dead_reckoning", "pose_laser_slam", "pose_ekf", "pose_place_cells", "pose_ratslam"):
    na, nb = sa.get(f"messages_{ch.upper()}", 0), sb.get(f"messages_{ch.upper()}", 0)
    ea, eb = sa.get(f"{ch}_ate_rmse_m"), sb.get(f"{ch}_ate_rmse_m")
    print(f"{ch:20s} {na:5d}/{nb:<5d}  {ea}  {eb}")
    if not na or abs(nb - na) > 0.05 * na + 2: bad.append(f"{ch}: {na} poses in A, {nb} in B")
    if ea is None or eb is None or eb > 2 * ea + 0.05: bad.append(f"{ch}: ATE {ea} m in A, {eb} m in B")
ha, hb = sa.get("homing_vector_mean_error_deg"), sb.get("homing_vector_mean_error_deg")
print(f"homing mean angular error: A {ha} deg, B {hb} deg")
if ha is None or hb is None or hb > ha + 10: bad.append(f"homing: {ha} deg in A, {hb} in B")
if bad: sys.exit("FAIL: " + "; ".join(bad))
print("PASS")
PY
