#!/usr/bin/env python3
"""Benchmark summaries (flat JSON keys with units in their names, and markdown).

  bench_summary.py runs DIR [--title T] [--note KEY=VALUE ...]
      DIR/run-*.json (one per run, e.g. latency-probe --out) -> DIR/summary.json with the median over
      the runs of every number, DIR/bench.md; latency samples in DIR/run-*.csv (output,latency_ms) also
      give pooled quantiles over all runs.
  bench_summary.py collect ROOT --bench NAME:EXIT_CODE:WALL_S ...
      ROOT/NAME/summary.json (or bench.json) of every benchmark -> ROOT/summary.json (keys prefixed with
      NAME_, nested values flattened, NAME_ok and NAME_wall_s added) and ROOT/summary.md.
"""
import argparse
import csv
import glob
import json
import os
import statistics
import sys


def load_json(path):
    with open(path) as f:
        return json.load(f)


def flatten(value, prefix, out):
    if isinstance(value, dict):
        for k, v in value.items():
            flatten(v, f"{prefix}_{k}" if prefix else str(k), out)
    elif isinstance(value, list):
        for i, v in enumerate(value):
            flatten(v, f"{prefix}_{i}", out)
    else:
        out[prefix] = value


def is_number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def fmt(v):
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return f"{v:.4g}" if abs(v) < 1e5 else f"{v:.0f}"
    return str(v)


def quantile(values, q):
    v = sorted(values)
    return v[min(len(v) - 1, int(q * (len(v) - 1) + 0.5))] if v else 0.0


def cmd_runs(a):
    paths = sorted(glob.glob(os.path.join(a.dir, "run-*.json")))
    if not paths:
        print(f"bench: no run-*.json in {a.dir}", file=sys.stderr)
        return 1
    runs = [load_json(p) for p in paths]
    summary = {"runs": len(runs)}
    keys = []
    for r in runs:
        keys += [k for k in r if k not in keys]
    for k in keys:
        values = [r[k] for r in runs if is_number(r.get(k))]
        if values:
            summary[k] = statistics.median(values)
    # Pooled latency quantiles over every sample of every run.
    pooled = {}
    for p in sorted(glob.glob(os.path.join(a.dir, "run-*.csv"))):
        with open(p) as f:
            for row in csv.DictReader(f):
                pooled.setdefault(row["output"], []).append(float(row["latency_ms"]))
    for output, values in pooled.items():
        k = "".join(c.lower() if c.isalnum() else "_" for c in output)
        summary[f"{k}_latency_pooled_samples"] = len(values)
        summary[f"{k}_latency_pooled_median_ms"] = quantile(values, 0.5)
        summary[f"{k}_latency_pooled_p95_ms"] = quantile(values, 0.95)
        summary[f"{k}_latency_pooled_max_ms"] = max(values)
    for note in a.note or []:
        k, _, v = note.partition("=")
        summary[k] = int(v) if v.lstrip("-").isdigit() else v
    with open(os.path.join(a.dir, "summary.json"), "w") as f:
        json.dump(summary, f, indent=2)
        f.write("\n")

    outputs = [k[: -len("_messages")] for k in keys if k.endswith("_messages")]
    md = [f"# {a.title}" if a.title else "# Benchmark", "",
          f"Median over {len(runs)} runs of each run's figure; pooled: every sample of every run.", "",
          "| output | matched per run | median (ms) | p95 (ms) | max (ms) | pooled median / p95 / max (ms) |",
          "|---|---|---|---|---|---|"]
    for o in outputs:
        def g(suffix):
            v = summary.get(f"{o}_{suffix}")
            return fmt(v) if v is not None else "-"
        md.append(f"| {o.upper()} | {g('matched')} | {g('latency_median_ms')} | {g('latency_p95_ms')} | "
                  f"{g('latency_max_ms')} | {g('latency_pooled_median_ms')} / {g('latency_pooled_p95_ms')} / "
                  f"{g('latency_pooled_max_ms')} |")
    md += ["", f"Frames per run (median): {fmt(summary.get('frames', 0))}."]
    for note in a.note or []:
        md.append(f"{note}")
    md.append("")
    with open(os.path.join(a.dir, "bench.md"), "w") as f:
        f.write("\n".join(md))
    print("\n".join(md))
    print(f"bench: {os.path.join(a.dir, 'summary.json')}")
    return 0


def cmd_collect(a):
    summary = {}
    md = ["# snapnav benchmarks", "",
          "Every benchmark of `./snapnav bench`, each in its own folder with its own figures. Keys in "
          "`summary.json` are the benchmark's own, prefixed with its name.", "",
          "| benchmark | result | wall time (s) | figures |", "|---|---|---|---|"]
    sections = []
    failed = 0
    for entry in a.bench:
        name, rc, wall = entry.split(":")
        ok = rc == "0"
        failed += not ok
        summary[f"{name}_ok"] = ok
        summary[f"{name}_wall_s"] = float(wall)
        folder = os.path.join(a.root, name)
        source = None
        for candidate in ("summary.json", "bench.json"):
            path = os.path.join(folder, candidate)
            if os.path.isfile(path):
                source = path
                break
        flat = {}
        if source:
            try:
                flatten(load_json(source), "", flat)
            except (OSError, ValueError) as e:
                print(f"bench: {source}: {e}", file=sys.stderr)
        for k, v in flat.items():
            summary[f"{name}_{k}"] = v
        rel = os.path.relpath(source, a.root) if source else "none"
        md.append(f"| {name} | {'ok' if ok else f'FAILED (exit {rc})'} | {float(wall):.0f} | "
                  f"{f'[{rel}]({rel})' if source else 'none'} |")
        rows = [f"| `{k}` | {fmt(v)} |" for k, v in flat.items() if not isinstance(v, str) or len(v) < 60]
        extra = ""
        bench_md = os.path.join(folder, "bench.md")
        if os.path.isfile(bench_md):
            extra = f" (details: [{os.path.relpath(bench_md, a.root)}]({os.path.relpath(bench_md, a.root)}))"
        sections += [f"## {name}{extra}", ""] + (["| key | value |", "|---|---|"] + rows if rows else ["no figures"]) + [""]
    md += [""] + sections
    with open(os.path.join(a.root, "summary.json"), "w") as f:
        json.dump(summary, f, indent=2)
        f.write("\n")
    with open(os.path.join(a.root, "summary.md"), "w") as f:
        f.write("\n".join(md))
    print("\n".join(md[: 6 + len(a.bench)]))
    print(f"bench: {os.path.join(a.root, 'summary.json')} and summary.md ({len(a.bench)} benchmarks, {failed} failed)")
    return 1 if failed else 0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("runs")
    r.add_argument("dir")
    r.add_argument("--title", default="")
    r.add_argument("--note", action="append")
    c = sub.add_parser("collect")
    c.add_argument("root")
    c.add_argument("--bench", action="append", default=[], help="NAME:EXIT_CODE:WALL_S")
    a = ap.parse_args()
    return cmd_runs(a) if a.cmd == "runs" else cmd_collect(a)


if __name__ == "__main__":
    sys.exit(main())
