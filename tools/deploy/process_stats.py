#!/usr/bin/env python3
"""Resident memory and CPU time of the processes of a run, sampled from /proc.

  process_stats.py sample --out CSV [--status-file FILE]... [--pid NAME=PID]... [--interval-s 5]
      Every interval, the RSS (VmRSS) and the CPU time used so far (user + system) of every process
      the launcher's status files name as running (their pids follow restarts) and of every
      --pid; one row per process and sample: t_s,process,pid,rss_kb,cpu_s. Runs until SIGINT or
      SIGTERM, or until every --pid has ended and the status files say the launchers stopped.
  process_stats.py summary CSV [--warmup-s 10] [--max-rss-growth-mb 20] [--json FILE] [--md FILE]
      Per process: RSS at its first sample, after the warm-up, at the end, its maximum and its growth
      after the warm-up; CPU seconds and the share of one core over the time it was sampled. Flat JSON
      keys (rss_NAME_growth_kb, cpu_NAME_percent, ...), a markdown table; exit 1 when a process grew
      by more than --max-rss-growth-mb after the warm-up.
"""
import argparse
import csv
import json
import os
import signal
import sys
import time

CLOCK_TICKS = os.sysconf("SC_CLK_TCK")


def read_proc(pid):
    """(rss_kb, cpu_s) of a live process, or None."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            stat = f.read()
        # Fields after the command name (which may hold spaces), ")" closes it: utime, stime are 14, 15.
        fields = stat[stat.rindex(")") + 2:].split()
        cpu_s = (int(fields[11]) + int(fields[12])) / CLOCK_TICKS
        rss_kb = None
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    rss_kb = int(line.split()[1])
                    break
        return (rss_kb, cpu_s) if rss_kb is not None else None
    except (OSError, ValueError, IndexError):
        return None


def read_status(path):
    """{name: pid} of the running processes of a launcher's status file, and whether it still runs."""
    running, launcher_active = {}, True
    try:
        with open(path) as f:
            for line in f:
                if line.startswith("# launch status") and "stopping" in line:
                    launcher_active = False
                if line.startswith("#") or not line.strip():
                    continue
                parts = line.rstrip("\n").split("\t")
                if len(parts) >= 3 and parts[1] in ("running", "starting") and parts[2] not in ("0", ""):
                    running[parts[0]] = int(parts[2])
    except OSError:
        pass  # not written yet
    return running, launcher_active


def cmd_sample(a):
    stop = []
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.append(1))
    fixed = {}
    for item in a.pid:
        name, _, pid = item.partition("=")
        if not name or not pid.isdigit():
            sys.exit(f"process_stats: --pid expects NAME=PID, got '{item}'")
        fixed[name] = int(pid)
    t0 = time.monotonic()
    with open(a.out, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["t_s", "process", "pid", "rss_kb", "cpu_s"])
        while not stop:
            t = round(time.monotonic() - t0, 1)
            procs = dict(fixed)
            launchers_done = True
            for path in a.status_file:
                running, launcher_active = read_status(path)
                launchers_done = launchers_done and os.path.exists(path) and not launcher_active and not running
                procs.update(running)
            fixed_alive = False
            for name, pid in sorted(procs.items()):
                r = read_proc(pid)
                if r:
                    fixed_alive = fixed_alive or fixed.get(name) == pid
                    w.writerow([t, name, pid, r[0], f"{r[1]:.2f}"])
            f.flush()
            if not fixed_alive and launchers_done:
                break  # everything it watches has ended
            deadline = time.monotonic() + a.interval_s
            while not stop and time.monotonic() < deadline:
                time.sleep(min(0.2, a.interval_s))
    return 0


def summarize(rows, warmup_s):
    """Per process (by name): samples, RSS figures, CPU seconds over all its pids, sampled span."""
    by_name = {}
    for r in rows:
        by_name.setdefault(r["process"], []).append(r)
    out = {}
    for name, samples in by_name.items():
        samples.sort(key=lambda r: r["t_s"])
        after = [r for r in samples if r["t_s"] >= samples[0]["t_s"] + warmup_s] or samples[-1:]
        cpu, first_cpu = 0.0, {}
        last_cpu = {}
        for r in samples:
            first_cpu.setdefault(r["pid"], r["cpu_s"])
            last_cpu[r["pid"]] = r["cpu_s"]
        # CPU used while sampled: the growth of each pid's counter (a restart is a new pid).
        cpu = sum(last_cpu[p] - first_cpu[p] for p in last_cpu)
        span = samples[-1]["t_s"] - samples[0]["t_s"]
        out[name] = {
            "samples": len(samples),
            "pids": len(last_cpu),
            "rss_initial_kb": samples[0]["rss_kb"],
            "rss_start_kb": after[0]["rss_kb"],
            "rss_start_t_s": after[0]["t_s"],
            "rss_end_kb": samples[-1]["rss_kb"],
            "rss_end_t_s": samples[-1]["t_s"],
            "rss_max_kb": max(r["rss_kb"] for r in samples),
            "rss_growth_kb": samples[-1]["rss_kb"] - after[0]["rss_kb"],
            "cpu_s": round(cpu, 2),
            "sampled_s": span,
            "cpu_percent": round(100.0 * cpu / span, 1) if span > 0 else 0.0,
        }
    return out


def load_rows(path):
    rows = []
    with open(path) as f:
        for r in csv.DictReader(f):
            rows.append({"t_s": float(r["t_s"]), "process": r["process"], "pid": int(r["pid"]),
                         "rss_kb": int(r["rss_kb"]), "cpu_s": float(r["cpu_s"])})
    return rows


def key(name):
    return "".join(c if c.isalnum() else "_" for c in name.lower())


def flat_json(stats, max_growth_kb=None):
    j = {}
    for name, s in stats.items():
        k = key(name)
        for field in ("rss_initial_kb", "rss_start_kb", "rss_end_kb", "rss_max_kb", "rss_growth_kb", "samples"):
            j[f"rss_{k}_{field[4:] if field.startswith('rss_') else field}"] = s[field]
        j[f"cpu_{k}_s"] = s["cpu_s"]
        j[f"cpu_{k}_percent"] = s["cpu_percent"]
    if max_growth_kb is not None:
        j["max_rss_growth_allowed_kb"] = max_growth_kb
        j["goal_flat_rss_met"] = bool(stats) and all(s["rss_growth_kb"] <= max_growth_kb for s in stats.values())
    return j


def markdown(stats, warmup_s):
    lines = [f"| process | RSS at start (MB) | after {warmup_s:g} s warm-up (MB) | at end (MB) | max (MB) "
             "| growth after warm-up (MB) | CPU (s) | CPU (% of one core) |",
             "|---|---|---|---|---|---|---|---|"]
    for name in sorted(stats):
        s = stats[name]
        lines.append(f"| {name}{' (' + str(s['pids']) + ' runs)' if s['pids'] > 1 else ''} | {s['rss_initial_kb'] / 1024:.1f} "
                     f"| {s['rss_start_kb'] / 1024:.1f} (t={s['rss_start_t_s']:g} s) | {s['rss_end_kb'] / 1024:.1f} "
                     f"(t={s['rss_end_t_s']:g} s) | {s['rss_max_kb'] / 1024:.1f} | {s['rss_growth_kb'] / 1024:+.1f} "
                     f"| {s['cpu_s']:.1f} | {s['cpu_percent']:.1f} |")
    total = sum(s["cpu_s"] for s in stats.values())
    span = max((s["sampled_s"] for s in stats.values()), default=0)
    if span > 0:
        lines.append(f"| all | | | | | | {total:.1f} | {100 * total / span:.1f} |")
    return "\n".join(lines) + "\n"


def cmd_summary(a):
    stats = summarize(load_rows(a.csv), a.warmup_s)
    max_kb = a.max_rss_growth_mb * 1024 if a.max_rss_growth_mb is not None else None
    j = flat_json(stats, max_kb)
    md = markdown(stats, a.warmup_s)
    if a.json:
        with open(a.json, "w") as f:
            json.dump(j, f, indent=2)
            f.write("\n")
    if a.md:
        with open(a.md, "w") as f:
            f.write(md)
    print(md, end="")
    return 0 if max_kb is None or j["goal_flat_rss_met"] else 1


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("sample", help="sample RSS and CPU time into a CSV file")
    s.add_argument("--out", required=True)
    s.add_argument("--status-file", action="append", default=[], help="a launcher's --status-file (repeatable)")
    s.add_argument("--pid", action="append", default=[], help="NAME=PID of a process to sample (repeatable)")
    s.add_argument("--interval-s", type=float, default=5)
    m = sub.add_parser("summary", help="RSS and CPU per process from a sample CSV")
    m.add_argument("csv")
    m.add_argument("--warmup-s", type=float, default=10)
    m.add_argument("--max-rss-growth-mb", type=float)
    m.add_argument("--json")
    m.add_argument("--md")
    a = ap.parse_args()
    if a.cmd == "sample":
        if not a.status_file and not a.pid:
            ap.error("sample needs --status-file or --pid")
        return cmd_sample(a)
    return cmd_summary(a)


if __name__ == "__main__":
    sys.exit(main())
