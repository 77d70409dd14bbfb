#!/usr/bin/env python3
"""Checks of a deployment run's output folder (log-report's summary.json and delivery.csv, the
process samples of process_stats.py, the recorded log). Each writes CHECK.json (flat keys, units in
the names) and CHECK.md into the folder, prints the markdown, and exits 1 when a verdict fails.

  run_checks.py link OUT [--clock-offset-s S] [--max-median-ms 3] [--max-lab-median-ms 20] [--frames ENC]
      Two hosts (tools/demo.sh --two-host): every frame's time from the robot to the base (sim
      --frame-times on the robot, latency-probe --frames-csv on the base; one clock): the link alone
      (link-idle-sent.csv, link-idle-arrived.csv) and during the lab (processes/sim-frame-times.csv,
      link-base.csv), frames lost on the way, every sensor channel of the robot in the base's log, the navigator's
      commands received by the robot, and each channel's stamps against the base's clock in the log
      (with the robot's clock S s off, every channel, sensors and estimators' outputs alike, must be
      S s off: message time only).
  run_checks.py soak OUT [--warmup-s 600] [--max-rss-growth-mb 20] [--estimator-warmup CHANNEL=S ...]
      A long run (tools/demo.sh --soak): RSS growth per process after the warm-up, nothing lost or
      missed, no estimator's error growing after the warm-up (log-report --ate-window-s, its
      ate_windows.csv; an estimator may have a longer warm-up of its own; one left with fewer than 3
      windows is shown, not judged; dead reckoning, which nothing corrects, is shown but not judged).
  run_checks.py robots OUT --prefixes R1_,R2_,... --duration-s S [--realtime-factor 1]
      Several robots on one bus (tools/deploy/robots.sh): every process of robot k received only
      channels of robot k (no cross-talk), no subscriber missed a message, every sim published at its
      rates for the whole run (S simulated seconds) and kept its pace (realtime_factor simulated
      seconds per wall second, within 0.5 s), CPU per process.
"""
import argparse
import csv
import json
import os
import statistics
import struct
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import process_stats  # noqa: E402

SENSORS = ("OMNI_FRAME", "LASER_SCAN", "ODOMETRY", "POSE_GROUND_TRUTH")
LCM_SYNC = 0xEDA1DA01


def load_json(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError) as e:
        print(f"run_checks: {path}: {e}", file=sys.stderr)
        return {}


def load_delivery(out):
    """Rows of log-report's delivery.csv (process, channel, published, received, ...)."""
    rows = []
    try:
        with open(os.path.join(out, "delivery.csv")) as f:
            for r in csv.DictReader(f):
                for k in ("runs", "reported_runs", "published", "received", "rejected", "handler_errors", "recorded"):
                    r[k] = int(r[k])
                rows.append(r)
    except OSError as e:
        print(f"run_checks: {e}", file=sys.stderr)
    return rows


def quantile(values, q):
    """Nearest-rank quantile, as latency-probe's."""
    if not values:
        return float("nan")
    v = sorted(values)
    return v[min(len(v) - 1, max(0, int(-(-q * len(v) // 1)) - 1))]


def log_stamp_offsets(path, max_events_per_channel=2000):
    """Per channel: the median over its events of (log timestamp - message utime) [s]: the recorder's
    clock against the message's. Reads the headers and each payload's utime only."""
    diffs = {}
    with open(path, "rb") as f:
        while True:
            head = f.read(28)
            if len(head) < 28:
                break
            sync, _, ts, clen, dlen = struct.unpack(">IqqII", head)
            if sync != LCM_SYNC:
                raise ValueError(f"{path}: no event at byte {f.tell() - 28}")
            channel = f.read(clen).decode("utf-8", "replace")
            data_start = f.tell()
            d = diffs.setdefault(channel, [])
            if len(d) < max_events_per_channel and dlen >= 16:
                utime = struct.unpack(">q", f.read(16)[8:16])[0]
                d.append((ts - utime) * 1e-6)
            f.seek(data_start + dlen)
    return {ch: statistics.median(v) for ch, v in diffs.items() if v}


def finish(out, name, j, md, ok):
    j[f"{name}_ok"] = ok
    with open(os.path.join(out, f"{name}.json"), "w") as f:
        json.dump(j, f, indent=2)
        f.write("\n")
    with open(os.path.join(out, f"{name}.md"), "w") as f:
        f.write(md)
    print(md, end="")
    return 0 if ok else 1


def check_link(a):
    out, j, md, ok = a.out, {}, [], True

    def verdict(good, text):
        nonlocal ok
        ok = ok and good
        md.append(f"- {'PASS' if good else 'FAIL'}: {text}")

    # Frame latency robot -> base: when sim handed each frame to the bus and when a probe on the base
    # had it; one clock, two network namespaces. First the link alone (10 s of raw frames, nothing else
    # running: link-idle-*.csv), then during the lab (processes/sim-frame-times.csv, link-base.csv).
    def read_times(path, column):
        with open(path) as f:
            return {int(r["utime"]): int(r[column]) for r in csv.DictReader(f)}

    md += ["## The link: robot -> base", ""]
    for name, sent_csv, arrived_csv, what in (
            ("idle", "link-idle-sent.csv", "link-idle-arrived.csv", "the link alone, raw 1 MB frames"),
            ("lab", os.path.join("processes", "sim-frame-times.csv"), "link-base.csv", "during the lab")):
        try:
            sent = read_times(os.path.join(out, sent_csv), "publish_utime")
            arrived = read_times(os.path.join(out, arrived_csv), "recv_utime")
        except OSError as e:
            verdict(False, f"{what}: {e}")
            continue
        both = [u for u in sent if u in arrived]
        lat = [(arrived[u] - sent[u]) / 1000.0 for u in both]
        k = f"link_{name}_"
        j.update({k + "frames_sent": len(sent), k + "frames_arrived": len(both), k + "frames_lost": len(sent) - len(both),
                  k + "frame_latency_median_ms": round(quantile(lat, 0.5), 3),
                  k + "frame_latency_p95_ms": round(quantile(lat, 0.95), 3),
                  k + "frame_latency_max_ms": round(max(lat), 3) if lat else None})
        verdict(len(both) > 0 and len(both) == len(sent), f"{what}: every frame sim published reached the base: "
                                                           f"{len(both)} of {len(sent)}")
        figures = (f"median {j[k + 'frame_latency_median_ms']} ms, p95 {j[k + 'frame_latency_p95_ms']} ms, "
                   f"max {j[k + 'frame_latency_max_ms']} ms")
        if name == "idle":
            verdict(bool(lat) and quantile(lat, 0.5) < a.max_median_ms,
                    f"{what}: from sim's publish to the base's receipt {figures} (goal: median < {a.max_median_ms:g} ms)")
        else:
            verdict(bool(lat) and quantile(lat, 0.5) < a.max_lab_median_ms,
                    f"{what} ({a.frames} frames): {figures} (bound: median < {a.max_lab_median_ms:g} ms; the "
                    f"subscribers on the base share its 2 cores)")

    # Delivery: the robot's sensors in the base's log, every subscriber complete, commands back.
    rows = load_delivery(out)
    s = load_json(os.path.join(out, "summary.json"))
    sim = {r["channel"]: r for r in rows if r["process"] == "sim"}
    for ch in SENSORS:
        r = sim.get(ch)
        good = r is not None and r["published"] > 0 and r["recorded"] == r["published"]
        j[f"link_{ch.lower()}_published"] = r["published"] if r else 0
        j[f"link_{ch.lower()}_recorded"] = r["recorded"] if r else 0
        verdict(good, f"{ch}: the robot published {r['published'] if r else 0}, the base's log holds "
                      f"{r['recorded'] if r else 0}")
    lost_total, missed = s.get("delivery_lost_total"), s.get("delivery_missed_by_subscribers_total")
    verdict(lost_total == 0 and missed == 0, f"every channel: {lost_total} messages lost to the recorder, "
                                             f"{missed} missed by a subscriber (of {s.get('delivery_exact_channels')} channels)")
    nav = next((r for r in rows if r["process"] == "navigator" and r["channel"] == "DRIVE_COMMAND"), None)
    cmd = sim.get("DRIVE_COMMAND")
    good = nav is not None and cmd is not None and nav["published"] > 0 and cmd["received"] == nav["published"]
    j["link_drive_commands_published"] = nav["published"] if nav else 0
    j["link_drive_commands_received_by_robot"] = cmd["received"] if cmd else 0
    verdict(good, f"commands back: the navigator (base) published {j['link_drive_commands_published']} "
                  f"DRIVE_COMMAND, the robot's sim received {j['link_drive_commands_received_by_robot']}")
    rejected = sum(r["rejected"] + r["handler_errors"] for r in rows)
    j["link_rejected_or_failed"] = rejected
    verdict(rejected == 0, f"{rejected} messages rejected or failed in a handler, by any process")

    # Clocks: every channel in the base's log carries the robot's time.
    offsets = log_stamp_offsets(os.path.join(out, "run.lcmlog"))
    md += ["", f"## Clocks: the robot's clock {a.clock_offset_s:+g} s off", "",
           "Median over each channel's events of (the base's log time - the message's utime): the sensors carry the "
           "robot's clock; an output carries its input's time, so it shows the same offset (a process stamping "
           "with its own clock would show 0).", "",
           "| channel | log time - utime (s) |", "|---|---|"]
    bad = []
    for ch, d in sorted(offsets.items()):
        md.append(f"| {ch} | {d:+.3f} |")
        j[f"clock_{ch.lower()}_log_minus_utime_s"] = round(d, 4)
        if abs(d + a.clock_offset_s) > 0.5:
            bad.append(ch)
    md.append("")
    verdict(not bad and len(offsets) > 5, f"{len(offsets)} channels stamped in the robot's time "
                                          f"(log time - utime within 0.5 s of {-a.clock_offset_s:+g} s)"
                                          + (f"; not: {', '.join(bad)}" if bad else ""))
    md.insert(0, f"# Two hosts: {'PASS' if ok else 'FAIL'}\n")
    return finish(out, "link", j, "\n".join(md) + "\n", ok)


def read_ate_windows(path):
    """log-report's ate_windows.csv: {channel (lower case): [(window start s, RMSE m), ...]}; {} if absent."""
    if not os.path.exists(path):
        return {}
    out = {}
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            out.setdefault(row["channel"].lower(), []).append((float(row["window_start_s"]), float(row["rmse_m"])))
    return out


def check_soak(a):
    out, j, md, ok = a.out, {}, ["# Soak", ""], True

    def verdict(good, text):
        nonlocal ok
        ok = ok and good
        md.append(f"- {'PASS' if good else 'FAIL'}: {text}")

    s = load_json(os.path.join(out, "summary.json"))
    stats = process_stats.summarize(process_stats.load_rows(os.path.join(out, "processes.csv")), a.warmup_s)
    j.update(process_stats.flat_json(stats, a.max_rss_growth_mb * 1024))
    grown = {n: v["rss_growth_kb"] for n, v in stats.items() if v["rss_growth_kb"] > a.max_rss_growth_mb * 1024}
    worst = max(stats.items(), key=lambda kv: kv[1]["rss_growth_kb"]) if stats else ("-", {"rss_growth_kb": 0})
    verdict(bool(stats) and not grown, f"RSS growth after {a.warmup_s:g} s of warm-up at most {a.max_rss_growth_mb:g} MB "
                                       f"per process (largest: {worst[0]} {worst[1]['rss_growth_kb'] / 1024:+.1f} MB)"
                                       + (f"; grew: {', '.join(grown)}" if grown else ""))
    lost, missed = s.get("delivery_lost_total"), s.get("delivery_missed_by_subscribers_total")
    verdict(lost == 0 and missed == 0, f"{lost} messages lost to the recorder, {missed} missed by a subscriber "
                                       f"({s.get('delivery_exact_channels')} channels)")
    restarts = s.get("process_restarts_total")
    verdict(restarts == 0, f"{restarts} process restarts")
    # Each estimator's error windows after its warm-up (the run's, or its own: --estimator-warmup); the
    # growth is the mean of the last third of them minus the first third's, judged against half their
    # mean + 2 cm. Without ate_windows.csv, summary.json's growth over the whole run.
    warmups = {}
    for item in a.estimator_warmup or []:
        ch, _, sec = item.partition("=")
        warmups[ch.strip().lower()] = float(sec)
    windows = read_ate_windows(os.path.join(out, "ate_windows.csv"))
    growing, judged_any = [], False
    for k in sorted(s):
        if not k.endswith("_ate_growth_m"):
            continue
        ch = k[: -len("_ate_growth_m")]
        warm = warmups.get(ch, a.warmup_s)
        rmse = [r for start, r in windows.get(ch, []) if start >= warm] if windows else None
        if rmse is None:
            growth, mean, n = s[k], s.get(f"{ch}_ate_window_mean_m", 0), s.get(f"{ch}_ate_windows")
            after = ""
        else:
            n = len(rmse)
            third = max(1, n // 3)
            growth = (sum(rmse[-third:]) - sum(rmse[:third])) / third if n else 0.0
            mean = sum(rmse) / n if n else 0.0
            after = f" after {warm:g} s"
        limit = 0.5 * mean + 0.02
        by_design = "dead_reckoning" in ch
        too_short = rmse is not None and len(rmse) < 3
        judged = not by_design and not too_short
        judged_any = judged_any or judged
        j[f"{ch}_ate_growth_after_warmup_m"] = round(growth, 4) if rmse is not None else None
        j[f"{ch}_ate_growth_limit_m"] = round(limit, 4) if judged else None
        if by_design:
            note = " (not corrected by anything: grows by design)"
        elif too_short:
            note = (f" (not judged: its warm-up of {warm:g} s leaves {len(rmse)} windows of this run, a longer run "
                    f"judges it; growth over the whole run {s[k]:+.3f} m)")
        else:
            note = f" (limit {limit:.3f} m)"
        md.append(f"  - {ch.upper()}: window RMSE first {s.get(ch + '_ate_window_first_m')} m, last "
                  f"{s.get(ch + '_ate_window_last_m')} m, max {s.get(ch + '_ate_window_max_m')} m, trend "
                  f"{s.get(ch + '_ate_trend_m_per_h'):+.3f} m/h"
                  + ("" if too_short else f"; growth{after} {growth:+.3f} m"
                     + (f" over {n} windows" if rmse is not None else "")) + note)
        if judged and growth > limit:
            growing.append(ch.upper())
    verdict(not growing and judged_any,
            "no estimator's error grows over the run after its warm-up (growth = mean of the last third of the "
            "windows minus the first third's, at most half their mean + 2 cm)"
            + (f"; growing: {', '.join(growing)}" if growing else ""))
    md += ["", process_stats.markdown(stats, a.warmup_s)]
    md[0] = f"# Soak: {'PASS' if ok else 'FAIL'}"
    return finish(out, "soak", j, "\n".join(md) + "\n", ok)


def check_robots(a):
    out, j, md, ok = a.out, {}, [], True

    def verdict(good, text):
        nonlocal ok
        ok = ok and good
        md.append(f"- {'PASS' if good else 'FAIL'}: {text}")

    prefixes = [p for p in a.prefixes.split(",") if p]
    rows = load_delivery(out)
    # Cross-talk: a process of robot k (its log in robots/<prefix>/) receives only channels of robot k.
    cross = [f"{r['process']} <- {r['channel']}" for r in rows if "/" in r["process"] and r["received"] > 0
             and r["process"].split("/")[0] in prefixes and not r["channel"].startswith(r["process"].split("/")[0])]
    j["robots_cross_talk_subscriptions"] = len(cross)
    verdict(not cross, "no cross-talk: every process of a robot received only its robot's channels"
                       + (f" (not: {'; '.join(cross[:5])})" if cross else ""))
    # Nothing dropped: every subscriber that ran once has every message each channel's publisher sent.
    published = {}
    for r in rows:
        if r["published"] > 0:
            published[r["channel"]] = published.get(r["channel"], 0) + r["published"]
    short = []
    for r in rows:
        if r["received"] > 0 and r["runs"] == 1 and r["reported_runs"] == 1 and r["channel"] in published \
                and r["received"] < published[r["channel"]]:
            short.append(f"{r['process']} {r['channel']} {r['received']}/{published[r['channel']]}")
    unrecorded = sorted({f"{r['channel']} {r['recorded']}/{published[r['channel']]}" for r in rows
                         if r["channel"] in published and r["recorded"] < published[r["channel"]]})
    j["robots_subscribers_short"] = len(short)
    j["robots_channels_not_fully_recorded"] = len(unrecorded)
    # Who fell behind, for a bench's "what limits it": each short subscriber (its process name) and the
    # recorder when the log lacks messages.
    j["robots_short_processes"] = sorted({s_.split(" ")[0] for s_ in short} | ({"recorder"} if unrecorded else set()))
    verdict(not short and not unrecorded, "nothing dropped: every subscriber and the recorder have every message"
            + (f" (short: {'; '.join(short[:5])})" if short else "") + (f" (log: {'; '.join(unrecorded[:5])})" if unrecorded else ""))
    # Rates: each sim published 10 Hz frames and scans and 50 Hz odometry for the whole run.
    rates_ok = True
    for p in prefixes:
        sim = {r["channel"]: r["published"] for r in rows if r["process"] == f"{p}/sim"}
        frames, scans, odo = sim.get(p + "OMNI_FRAME", 0), sim.get(p + "LASER_SCAN", 0), sim.get(p + "ODOMETRY", 0)
        j[f"robots_{p.lower()}frames"] = frames
        rates_ok = rates_ok and frames >= 10 * a.duration_s and scans >= 10 * a.duration_s and odo >= 50 * a.duration_s
        md.append(f"  - {p}: {frames} frames, {scans} scans, {odo} odometry in {a.duration_s:g} s")
    verdict(rates_ok, f"every sim published its frames and scans at 10 Hz and odometry at 50 Hz for {a.duration_s:g} s")
    # Each sim kept its pace: its own report ("wall W s" at each 10 s of simulated time) against
    # realtime_factor simulated seconds per wall second (1: real time).
    factor = a.realtime_factor
    late = []
    for p in prefixes:
        try:
            with open(os.path.join(out, "robots", p, "sim.log")) as f:
                lines = [ln for ln in f if ln.startswith("sim: t=")]
        except OSError:
            lines = []
        for ln in lines:
            t = float(ln.split("t=")[1].split()[0])
            wall = float(ln.rsplit("wall", 1)[1].split()[0])
            if wall * factor > t + 0.5:
                late.append(f"{p} {t:g} s at wall {wall:g} s")
    j["robots_late_sims"] = sorted({ln.split(" ")[0] + "/sim" for ln in late})
    pace = "real time (its simulated time within 0.5 s of its wall time)" if factor == 1 else \
        f"its pace ({factor:g} s of simulated time per wall second, within 0.5 s)"
    j["robots_realtime_factor"] = factor
    verdict(not late, f"every sim kept {pace}" + (f" (late: {'; '.join(late[:5])})" if late else ""))
    stats = process_stats.summarize(process_stats.load_rows(os.path.join(out, "processes.csv")), 10)
    j.update({k: v for k, v in process_stats.flat_json(stats).items() if k.startswith("cpu_")})
    total = sum(v["cpu_s"] for v in stats.values())
    span = max((v["sampled_s"] for v in stats.values()), default=0)
    j["robots_cpu_total_percent"] = round(100 * total / span, 1) if span else 0
    busiest = max(stats.items(), key=lambda kv: kv[1]["cpu_percent"]) if stats else ("-", {"cpu_percent": 0})
    j["robots_busiest_process"] = busiest[0]
    j["robots_busiest_process_cpu_percent"] = busiest[1]["cpu_percent"]
    md += ["", f"CPU: {j['robots_cpu_total_percent']} % of one core in all (2 cores: 200 %); the busiest process "
               f"{busiest[0]} {busiest[1]['cpu_percent']} %.", "", process_stats.markdown(stats, 10)]
    md.insert(0, f"# {len(prefixes)} robots on one bus: {'PASS' if ok else 'FAIL'}\n")
    return finish(out, "robots", j, "\n".join(md) + "\n", ok)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("link")
    p.add_argument("out")
    p.add_argument("--clock-offset-s", type=float, default=0)
    p.add_argument("--max-median-ms", type=float, default=3, help="the link alone: median latency bound [ms]")
    p.add_argument("--max-lab-median-ms", type=float, default=20, help="during the lab: median latency bound [ms]")
    p.add_argument("--frames", default="jpeg", help="the lab's frame encoding, for the report")
    p = sub.add_parser("soak")
    p.add_argument("out")
    p.add_argument("--warmup-s", type=float, default=600)
    p.add_argument("--max-rss-growth-mb", type=float, default=20)
    p.add_argument("--estimator-warmup", action="append", metavar="CHANNEL=S",
                   help="an estimator whose error settles later than --warmup-s (repeatable), e.g. POSE_RATSLAM=600")
    p = sub.add_parser("robots")
    p.add_argument("out")
    p.add_argument("--prefixes", required=True)
    p.add_argument("--duration-s", type=float, required=True, help="each sim's simulated seconds")
    p.add_argument("--realtime-factor", type=float, default=1.0, help="the sims' simulated seconds per wall second")
    a = ap.parse_args()
    return {"link": check_link, "soak": check_soak, "robots": check_robots}[a.cmd](a)


if __name__ == "__main__":
    sys.exit(main())
