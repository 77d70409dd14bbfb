#!/usr/bin/env bash
# Localization in saved maps on real data (issue 22; docs/localization.md): for each lab's
# corrected CARMEN log at hand, the map made by map-export from the corrected poses (POSE_CARMEN),
# then laser-slam --mode localize's localizer (localize-eval, the shipped config for all) over a
# raw-like log of the same lab (carmen_raw_like.py --noise 1: the same scans, odometry with
# wheel errors) from 4 unknown starts; CSAIL's real raw log in CSAIL's map. Writes
# OUT/LAB/{map,eval} and OUT/summary.md, OUT/summary.json.
# Usage: tools/map/localize_labs.sh BIN DATA RAW_LIKE_TOOL OUT [LAB...] [-- --set SECTION.KEY=VALUE ...]
# (after --: localize-eval's overrides, the same for every lab).
set -euo pipefail
BIN="$1"; DATA="$2"; TOOL="$3"; OUT="$4"; shift 4
LABS=(); SETS=()
while [ $# -gt 0 ]; do
  if [ "$1" = "--" ]; then shift; SETS=("$@"); break; fi
  LABS+=("$1"); shift
done
[ ${#LABS[@]} -gt 0 ] || LABS=(aces seattle orebro freiburg-079 csail)
mkdir -p "$OUT"
for lab in "${LABS[@]}"; do
  d="$OUT/$lab"; mkdir -p "$d"
  if [ "$lab" = csail ]; then
    corrected="$DATA/laser/csail-corrected.log.gz"; raw="$DATA/laser/mit-csail.clf"
  else
    corrected="$DATA/laser/carmen/$lab-corrected.log.gz"; raw=""
  fi
  [ -f "$corrected" ] || { echo "localize-labs: $lab: $corrected missing, skipped"; continue; }
  "$BIN/log-import" carmen "$corrected" --out "$d/corrected.lcmlog" --quiet > "$d/import-corrected.txt" 2>&1 || true
  "$BIN/map-export" "$d/corrected.lcmlog" --pose-channel POSE_CARMEN --out "$d/map" > "$d/map-export.txt" 2>&1
  if [ -z "$raw" ]; then
    python3 "$TOOL" "$corrected" "$d/raw_like.clf" --noise 1 --seed 1 > /dev/null
    raw="$d/raw_like.clf"
  fi
  "$BIN/log-import" carmen "$raw" --out "$d/raw.lcmlog" --quiet > "$d/import-raw.txt" 2>&1 || true
  "$BIN/localize-eval" "$d/raw.lcmlog" --map "$d/map/map.yaml" --reference "$corrected" --starts 4 --out "$d/eval" \
      ${SETS[@]+"${SETS[@]}"} > "$d/localize-eval.txt" 2>&1
  grep "^localize-eval: start" "$d/localize-eval.txt" | sed "s/^/$lab: /"
done
python3 - "$OUT" "${LABS[@]}" <<'PY'
import json, os, statistics, sys
out, labs = sys.argv[1], sys.argv[2:]
rows, summary = [], {}
for lab in labs:
    p = os.path.join(out, lab, 'eval', 'localize.json')
    if not os.path.exists(p): continue
    j = json.load(open(p))
    st = j['starts']
    found = [s for s in st if s['relocalized']]
    ate = [s['ate_rmse_m'] for s in found]
    summary[lab] = {
        'scans': j['scans'], 'referenced_scans': j['referenced_scans'], 'starts': len(st), 'relocalized': len(found),
        'median_time_s': statistics.median([s['time_s'] for s in found]) if found else None,
        'max_time_s': max([s['time_s'] for s in found]) if found else None,
        'median_scans_to': statistics.median([s['scans_to'] for s in found]) if found else None,
        'median_path_m': statistics.median([s['path_m'] for s in found]) if found else None,
        'max_compute_s': max([s['compute_s'] for s in found]) if found else None,
        'ate_rmse_m_median': statistics.median(ate) if ate else None, 'ate_rmse_m_max': max(ate) if ate else None,
        'wrong_accepts': sum(s['wrong_accepts'] for s in st), 'losses': sum(s['losses'] for s in st),
        'localized_fraction': sum(s['localized_scans'] for s in st) / max(1, sum(s['scans'] for s in st)),
        'mean_search_ms': statistics.mean([s['mean_search_ms'] for s in st if s['searches']]) if any(s['searches'] for s in st) else 0,
        'max_search_ms': max(s['max_search_ms'] for s in st), 'mean_track_ms': statistics.mean([s['mean_track_ms'] for s in st]),
    }
json.dump(summary, open(os.path.join(out, 'summary.json'), 'w'), indent=1)
f = lambda v, fmt: '-' if v is None else fmt % v
with open(os.path.join(out, 'summary.md'), 'w') as m:
    m.write('| lab | scans | starts relocalized | time to relocalize, median / max [s] | scans | path [m] | compute max [s] | ATE RMSE median / max [m] | wrong accepted | losses | localized scans | global search mean / max [ms] | tracking [ms/scan] |\n')
    m.write('|---|---|---|---|---|---|---|---|---|---|---|---|---|\n')
    for lab, s in summary.items():
        m.write('| %s | %d | %d / %d | %s / %s | %s | %s | %s | %s / %s | %d | %d | %.1f %% | %.0f / %.0f | %.1f |\n' % (
            lab, s['scans'], s['relocalized'], s['starts'], f(s['median_time_s'], '%.1f'), f(s['max_time_s'], '%.1f'),
            f(s['median_scans_to'], '%.0f'), f(s['median_path_m'], '%.1f'), f(s['max_compute_s'], '%.2f'),
            f(s['ate_rmse_m_median'], '%.3f'), f(s['ate_rmse_m_max'], '%.3f'), s['wrong_accepts'], s['losses'],
            100 * s['localized_fraction'], s['mean_search_ms'], s['max_search_ms'], s['mean_track_ms']))
print(open(os.path.join(out, 'summary.md')).read())
PY
