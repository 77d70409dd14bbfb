#!/usr/bin/env python3
"""Summary of a soak run (tools/soak/soak.sh): merges the publisher's, the verifier's and the log
verifier's JSON with the RSS samples and the kernel's UDP counters into OUT/summary.json (flat keys,
units in the names) and OUT/soak.md. Exit 0 when nothing was dropped or corrupted and no process's
RSS grew by more than --max-rss-growth-mb from the end of the warm-up to the end."""
import argparse
import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "deploy"))
import process_stats  # noqa: E402


def load(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError) as e:
        print(f"soak: {path}: {e}", file=sys.stderr)
        return {}


def counters(text):
    return {k: int(v) for k, v in (item.split("=") for item in text.split())} if text else {}


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("out")
    ap.add_argument("--duration-s", type=float, required=True)
    ap.add_argument("--max-rss-growth-mb", type=float, default=20)
    ap.add_argument("--udp-before", default="")
    ap.add_argument("--udp-after", default="")
    ap.add_argument("--exit-codes", default="")
    a = ap.parse_args()

    s = {"duration_s": a.duration_s}
    pub = load(os.path.join(a.out, "publisher.json"))
    ver = load(os.path.join(a.out, "verifier.json"))
    log = load(os.path.join(a.out, "logger.json"))
    for part in (pub, ver, log):
        s.update(part)

    before, after = counters(a.udp_before), counters(a.udp_after)
    for k in ("in_datagrams", "in_errors", "rcvbuf_errors"):
        if k in before and k in after:
            s[f"udp_{k}"] = after[k] - before[k]

    # RSS per process: initial (first sample), start (first sample after the warm-up, when the
    # buffers are allocated), end (last sample), max.
    warmup_s = min(10.0, a.duration_s / 4)
    try:
        stats = process_stats.summarize(process_stats.load_rows(os.path.join(a.out, "rss.csv")), warmup_s)
    except (OSError, ValueError, KeyError) as e:
        print(f"soak: rss.csv: {e}", file=sys.stderr)
        stats = {}
    s["rss_warmup_s"] = warmup_s
    s.update({k: v for k, v in process_stats.flat_json(stats, a.max_rss_growth_mb * 1024).items()
              if not k.startswith("cpu_")})
    rss_ok = s.pop("goal_flat_rss_met")
    s.pop("max_rss_growth_allowed_kb")

    exit_codes = dict(item.split("=") for item in a.exit_codes.split(",") if item)
    drops = 0
    for who in ("verifier", "logger"):
        for stream in ("frames", "scans"):
            for what in ("missing", "corrupt", "out_of_order", "duplicates"):
                drops += int(s.get(f"{who}_{stream}_{what}", 1))
    sent_ok = s.get("publisher_frames_sent", -1) == s.get("verifier_frames_expected", -2) and \
        s.get("publisher_scans_sent", -1) == s.get("verifier_scans_expected", -2)
    zero_drops = drops == 0 and sent_ok and all(v == "0" for v in exit_codes.values())
    s["messages_lost_or_damaged"] = drops
    s["goal_zero_drops_met"] = zero_drops
    s["max_rss_growth_allowed_kb"] = a.max_rss_growth_mb * 1024
    s["goal_flat_rss_met"] = rss_ok
    for k, v in exit_codes.items():
        s[f"exit_code_{k.replace('-', '_')}"] = int(v)
    with open(os.path.join(a.out, "summary.json"), "w") as f:
        json.dump(s, f, indent=2)
        f.write("\n")

    def n(key):
        return s.get(key, "?")

    md = [
        "# snapnav soak",
        "",
        f"{n('publisher_frames_sent')} frames of {n('publisher_frame_bytes')} bytes at {n('publisher_frame_rate_hz')} Hz "
        f"and {n('publisher_scans_sent')} scans of {n('publisher_beams')} beams at {n('publisher_scan_rate_hz')} Hz, "
        f"{a.duration_s:g} s, one publisher process, UDP multicast in a private network namespace.",
        "",
        "| subscriber | frames received | frames missing | scans received | scans missing | corrupt | out of order | duplicates |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for who, name in (("verifier", "bus-check soak-verify (live)"), ("logger", "lcm-logger (its recording, checked)")):
        corrupt = sum(int(s.get(f"{who}_{x}_corrupt", 0)) for x in ("frames", "scans"))
        order = sum(int(s.get(f"{who}_{x}_out_of_order", 0)) for x in ("frames", "scans"))
        dup = sum(int(s.get(f"{who}_{x}_duplicates", 0)) for x in ("frames", "scans"))
        md.append(f"| {name} | {n(who + '_frames_received')} | {n(who + '_frames_missing')} | {n(who + '_scans_received')} "
                  f"| {n(who + '_scans_missing')} | {corrupt} | {order} | {dup} |")
    md += [
        "",
        f"Kernel UDP counters over the run (this namespace): {n('udp_in_datagrams')} datagrams in, "
        f"{n('udp_rcvbuf_errors')} dropped for a full receive buffer (RcvbufErrors), {n('udp_in_errors')} in errors. "
        f"Publisher: {n('publisher_late_publishes')} publishes more than a frame period late (max {n('publisher_max_late_ms')} ms).",
        "",
        process_stats.markdown(stats, warmup_s),
        "",
        f"Goals: zero dropped messages: **{'met' if zero_drops else 'MISSED'}**; RSS growth <= "
        f"{a.max_rss_growth_mb:g} MB per process: **{'met' if rss_ok else 'MISSED'}**.",
        "",
    ]
    with open(os.path.join(a.out, "soak.md"), "w") as f:
        f.write("\n".join(md))
    print("\n".join(md))
    print(f"soak: {os.path.join(a.out, 'summary.json')}, {os.path.join(a.out, 'soak.md')}")
    return 0 if zero_drops and rss_ok else 1


if __name__ == "__main__":
    sys.exit(main())
