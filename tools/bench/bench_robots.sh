#!/usr/bin/env bash
# How many simulated robots this machine keeps at 10 Hz with nothing dropped (`./snapnav bench
# robots`, inside the private bus namespace). For N = 1, 2, ... robots (config/deploy/robots.deploy
# through tools/deploy/robots.sh: each robot's sim in real time with dead reckoning, laser SLAM,
# place cells and homing, one recorder and one viewer for all) it runs --duration-s and checks that
# every sim kept real time at its rates (10 Hz frames and scans, 50 Hz odometry) and that no
# subscriber or the logger missed a message; it stops at the first N that fails (--runs runs each:
# N passes when most of its runs pass). bench.json and bench.md: the largest N that passed, the
# CPU of each N, and at the first failing N what failed, the processes that fell behind (a subscriber
# that missed messages, the recorder, a sim behind real time) and the busiest process. The machine's
# load average and the CPU other sessions used are noted for each run: on shared cores other work takes
# its part (the kernel's autogroup scheduling shares the cores between sessions, not processes: a
# neighbouring session with two busy processes leaves the robots one core).
set -euo pipefail
BIN="$1"; shift
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
OUT="$ROOT/logs/bench-robots"
DURATION=40
MAX=8
RUNS=3
while [ $# -gt 0 ]; do
  case "$1" in
    --out) OUT="$2"; shift 2 ;;
    --duration-s) DURATION="$2"; shift 2 ;;
    --max) MAX="$2"; shift 2 ;;
    --runs) RUNS="$2"; shift 2 ;;
    -h | --help)
      echo "usage: ./snapnav bench robots [--out DIR] [--duration-s 40] [--max 8] [--runs 3]"; exit 0 ;;
    *) echo "bench robots: unknown argument $1 (--out DIR, --duration-s S, --max N, --runs R)" >&2; exit 2 ;;
  esac
done
mkdir -p "$OUT"
OUT="$(cd "$OUT" && pwd)"
rm -rf "$OUT"/n* "$OUT/bench.json" "$OUT/bench.md"
echo "bench robots: 1..$MAX robots, $DURATION s each, $RUNS run(s) per count; $(nproc) cores, load average $(cut -d' ' -f1-3 /proc/loadavg)"
# CPU time of the whole machine (all cores, busy and total jiffies) from /proc/stat.
machine_cpu() { awk '/^cpu / { print $2 + $3 + $4 + $7 + $8 + $9, $2 + $3 + $4 + $5 + $6 + $7 + $8 + $9 }' /proc/stat; }
# The place-cell memory once, for every run.
"$BIN/launch" "$ROOT/config/deploy/robots.deploy" --group explore --out "$OUT/explored" --status-every-s 0 \
  >"$OUT/explore.log" 2>&1 || { echo "bench robots: exploring failed (see $OUT/explore.log)" >&2; exit 1; }
for n in $(seq "$MAX"); do
  passed=0
  for r in $(seq "$RUNS"); do
    dir="$OUT/n$n-run$r"
    load_before=$(cut -d' ' -f1 /proc/loadavg)
    cpu_before=$(machine_cpu)
    "$ROOT/tools/deploy/robots.sh" "$BIN" --count "$n" --duration-s "$DURATION" --explored "$OUT/explored" \
      --out "$dir" --drop-log >"$OUT/n$n-run$r.log" 2>&1 && passed=$((passed + 1)) || true
    # The machine's load around the run (other users' work counts: the cores are shared).
    echo "$load_before $(cut -d' ' -f1 /proc/loadavg)" >"$dir/loadavg.txt"
    echo "$cpu_before $(machine_cpu) $(nproc)" >"$dir/machine_cpu.txt"
    python3 - "$dir/robots.json" "$n" "$r" <<'PY'
import json, sys
try:
    j = json.load(open(sys.argv[1]))
except (OSError, ValueError):
    j = {}
b0, t0, b1, t1, ncpu = (float(x) for x in open(sys.argv[1].replace("robots.json", "machine_cpu.txt")).read().split())
busy = round(100 * ncpu * (b1 - b0) / max(1.0, t1 - t0), 1)  # % of one core, all cores together
ours = j.get("robots_cpu_total_percent", 0)
print(f"  {sys.argv[2]} robots, run {sys.argv[3]}: {'PASS' if j.get('robots_ok') else 'FAIL'}; "
      f"CPU {ours} % of one core, busiest {j.get('robots_busiest_process', '?')} "
      f"{j.get('robots_busiest_process_cpu_percent', '?')} %; the machine {busy} % of {100 * ncpu:g} "
      f"(other work about {max(0.0, busy - ours):.0f} %); load average before/after "
      f"{open(sys.argv[1].replace('robots.json', 'loadavg.txt')).read().strip()}")
PY
  done
  [ $((2 * passed)) -gt "$RUNS" ] || break
done
python3 - "$OUT" "$RUNS" "$DURATION" <<'PY'
import glob, json, os, re, statistics, sys
out, runs, duration = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
by_n = {}
for d in sorted(p for p in glob.glob(os.path.join(out, "n*-run*")) if os.path.isdir(p)):
    n = int(re.search(r"n(\d+)-run", d).group(1))
    try:
        j = json.load(open(os.path.join(d, "robots.json")))
    except (OSError, ValueError):
        j = {"robots_ok": False}
    failed = []
    try:
        failed = [re.split(r"[:(]", ln[8:])[0].strip() for ln in open(os.path.join(d, "robots.md")) if ln.startswith("- FAIL:")]
    except OSError:
        failed = ["no report"]
    try:
        j["load"] = open(os.path.join(d, "loadavg.txt")).read().split()
    except OSError:
        j["load"] = ["?", "?"]
    try:
        b0, t0, b1, t1, ncpu = (float(x) for x in open(os.path.join(d, "machine_cpu.txt")).read().split())
        j["machine_busy"] = 100 * ncpu * (b1 - b0) / max(1.0, t1 - t0)
    except (OSError, ValueError):
        j["machine_busy"] = None
    by_n.setdefault(n, []).append((j, failed))
best = 0
s = {"duration_s": duration, "runs_per_count": runs, "cores": os.cpu_count()}
md = ["# Robots on one bus at 10 Hz", "",
      f"Each count of robots for {duration:g} s in real time ({runs} run(s) each; a count passes when most runs pass): "
      "every sim at 10 Hz frames and scans and 50 Hz odometry in real time, no subscriber or logger missing a message.",
      "", "| robots | passed runs | CPU, all processes (% of one core; median) | busiest process (% of one core) "
      "| other work on the machine (% of one core; median) | machine load average before / after | what failed | fell behind |",
      "|---|---|---|---|---|---|---|---|"]
for n in sorted(by_n):
    rs = by_n[n]
    ok = sum(1 for j, _ in rs if j.get("robots_ok"))
    cpu = statistics.median([j.get("robots_cpu_total_percent", 0) for j, _ in rs])
    others = [max(0.0, j["machine_busy"] - j.get("robots_cpu_total_percent", 0)) for j, _ in rs if j.get("machine_busy") is not None]
    others_pct = round(statistics.median(others)) if others else "?"
    s[f"robots_{n}_other_work_cpu_percent"] = others_pct
    j0 = rs[0][0]
    fails = sorted({f for _, fs in rs for f in fs})
    s[f"robots_{n}_passed_runs"] = ok
    s[f"robots_{n}_cpu_total_percent"] = cpu
    if 2 * ok > len(rs):
        best = n
    md.append(f"| {n} | {ok}/{len(rs)} | {cpu} | {j0.get('robots_busiest_process', '?')} "
              f"{j0.get('robots_busiest_process_cpu_percent', '?')} | {others_pct} | {' / '.join(j0['load'])} | {'; '.join(fails) or '-'} "
              f"| {', '.join(sorted({p for jr, _ in rs for p in jr.get('robots_short_processes', []) + jr.get('robots_late_sims', [])})) or '-'} |")
s["robots_max_at_10hz"] = best
first_fail = next((n for n in sorted(by_n) if n > best), None)
if first_fail:
    j, fails = by_n[first_fail][0]
    # What limits it: the processes that fell behind at the first failing count (a subscriber that
    # missed messages, the recorder, a sim behind real time), over its runs; the busiest process beside.
    behind = sorted({p for jr, _ in by_n[first_fail] for p in jr.get("robots_short_processes", []) + jr.get("robots_late_sims", [])})
    s["limiting_count"] = first_fail
    s["limiting_processes"] = behind
    s["busiest_process"] = j.get("robots_busiest_process")
    s["busiest_process_cpu_percent"] = j.get("robots_busiest_process_cpu_percent")
    md += ["", f"**{best} robots** keep 10 Hz with nothing dropped; at {first_fail}: {'; '.join(fails)}; fell behind: "
               f"{', '.join(behind) or 'none named'} (the busiest process {j.get('robots_busiest_process')}, "
               f"{j.get('robots_busiest_process_cpu_percent')} % of one core; all {j.get('robots_cpu_total_percent')} % of "
               f"the {100 * (os.cpu_count() or 2)} % of {os.cpu_count()} cores)."]
else:
    md += ["", f"**{best} robots** passed: the largest count tried (--max)."]
json.dump(s, open(os.path.join(out, "bench.json"), "w"), indent=2)
open(os.path.join(out, "bench.md"), "w").write("\n".join(md) + "\n")
print("\n".join(md))
PY
