#!/usr/bin/env python3
"""Checks localize-eval's localize.json: every start relocalized within MAX_S seconds of message time,
no wrong global pose accepted, no loss, the ATE while localized below MAX_ATE_M.
usage: check_localize.py LOCALIZE_JSON STARTS MAX_S MAX_ATE_M LABEL"""
import json
import sys

path, starts, max_s, max_ate, label = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4]), sys.argv[5]
j = json.load(open(path))
bad = []
if len(j["starts"]) != starts:
    sys.exit(f"FAIL: {len(j['starts'])} starts in {path}, {starts} expected")
for s in j["starts"]:
    n = s["start_scan"]
    if not s["relocalized"]: bad.append(f"start {n}: never relocalized")
    elif s["time_s"] > max_s: bad.append(f"start {n}: relocalized after {s['time_s']:.1f} s (> {max_s:g} s)")
    if s["wrong_accepts"]: bad.append(f"start {n}: {s['wrong_accepts']} wrong global poses accepted")
    if s["losses"]: bad.append(f"start {n}: lost {s['losses']} times")
    if s["relocalized"] and not s["ate_rmse_m"] < max_ate: bad.append(f"start {n}: ATE {s['ate_rmse_m']:.3f} m")
if bad: sys.exit("FAIL: " + "; ".join(bad))
ates = [s["ate_rmse_m"] for s in j["starts"]]
print(f"{label}: every start relocalized within {max(s['time_s'] for s in j['starts']):.1f} s, "
      f"ATE {min(ates):.3f}-{max(ates):.3f} m, none wrong, none lost")
