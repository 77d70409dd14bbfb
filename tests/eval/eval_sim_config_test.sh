#!/usr/bin/env bash
# eval homing and eval localization take all of a --sim-config file or refuse it (issue 21):
# [effects] change eval homing's figures (they were once silently ignored), and a changed key the
# evaluations do not use ([laser] beams, [sim] scene) is refused naming file, line and key.
set -euo pipefail
BIN="$1"
CONFIG="$2"
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT
sed 's/^beams = [0-9]*/beams = 100/' "$CONFIG/sim.ini" > "$OUT/laser.ini"
sed 's/^scene = [a-z0-9_]*/scene = corridor/' "$CONFIG/sim.ini" > "$OUT/scene.ini"
# The clean camera (the shipped camera is the realistic one): panoramas rendered directly take [effects].
sed '0,/^preset = realistic /s//preset = clean /' "$CONFIG/sim.ini" > "$OUT/clean.ini"
[ "$(grep -c '^preset = clean' "$OUT/clean.ini")" = 1 ]
sed 's/^noise_sigma = [0-9.]*/noise_sigma = 40/; s/^blur_sigma_px = [0-9.]*/blur_sigma_px = 3/' "$OUT/clean.ini" > "$OUT/noisy.ini"
grep -q '^beams = 100' "$OUT/laser.ini" && grep -q '^scene = corridor' "$OUT/scene.ini"
grep -q '^noise_sigma = 40' "$OUT/noisy.ini" && grep -q '^blur_sigma_px = 3' "$OUT/noisy.ini"
beams_line=$(grep -n '^beams = 100' "$OUT/laser.ini" | cut -d: -f1)
scene_line=$(grep -n '^scene = corridor' "$OUT/scene.ini" | cut -d: -f1)

refused() {  # TOOL FILE EXPECTED-TEXT: the refusal comes before any rendering
  if "$BIN/$1" --sim-config "$2" --out "$OUT/refused" >"$OUT/stdout" 2>"$OUT/stderr"; then
    echo "FAIL: $1 accepted $2"; exit 1
  fi
  grep -qF "$3" "$OUT/stderr" || { echo "FAIL: $1 did not say '$3':"; cat "$OUT/stderr"; exit 1; }
  echo "ok: $1 refuses: $(cat "$OUT/stderr")"
}
refused eval-homing "$OUT/laser.ini" "laser.ini:$beams_line: [laser] beams = 100: eval homing does not use it"
refused eval-homing "$OUT/scene.ini" "scene.ini:$scene_line: [sim] scene = corridor: eval homing does not use it"
refused eval-localization "$OUT/laser.ini" "laser.ini:$beams_line: [laser] beams = 100: eval localization does not use it"

# The clean camera's file and one with other [effects] are taken; the effects change the figures.
run() {  # NAME SIM-CONFIG
  "$BIN/eval-homing" --scene indoor_objects11 --input panorama --quick --no-return --sim-config "$2" \
    --out "$OUT/$1" >/dev/null 2>"$OUT/$1.log" || { cat "$OUT/$1.log"; exit 1; }
}
run clean "$OUT/clean.ini"
run noisy "$OUT/noisy.ini"
python3 - "$OUT/clean/summary.json" "$OUT/noisy/summary.json" <<'PY'
import json, sys
clean, noisy = (json.load(open(p)) for p in sys.argv[1:3])
print(f"AAE shipped effects {clean['average_angular_error_deg']:.2f} deg, "
      f"noise 40 + blur 3 px {noisy['average_angular_error_deg']:.2f} deg")
assert clean["effects"]["noise_sigma"] == 0 and clean["effects"]["blur_sigma_px"] == 0, clean["effects"]
assert noisy["effects"]["noise_sigma"] == 40 and noisy["effects"]["blur_sigma_px"] == 3, noisy["effects"]
assert abs(noisy["average_angular_error_deg"] - clean["average_angular_error_deg"]) > 1.0, "the [effects] were not applied"
PY

# The realistic camera's optics act on the raw image: an evaluation that would render panoramas
# directly refuses it (eval homing --input panorama) or renders raw frames (eval ratslam): never
# is the preset dropped silently. The shipped camera is the realistic one.
grep -q '^preset = realistic ' "$CONFIG/sim.ini"
if "$BIN/eval-homing" --input panorama --quick --out "$OUT/rp" 2>"$OUT/stderr"; then
  echo "FAIL: eval-homing rendered panoramas directly with the realistic camera"; exit 1
fi
grep -qF "without the realistic camera's optics" "$OUT/stderr" || { cat "$OUT/stderr"; exit 1; }
echo "ok: eval-homing --input panorama refuses the realistic camera"
"$BIN/eval-ratslam" --scene indoor13 --laps 0 --duration-s 2 --mask truth --out "$OUT/rs" \
  >/dev/null 2>"$OUT/rs.log" || { cat "$OUT/rs.log"; exit 1; }
grep -q "realistic (raw, unwrapped), mask truth" "$OUT/rs.log" || { head -3 "$OUT/rs.log"; exit 1; }
python3 - "$OUT/rs/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
assert s["camera"] == "realistic" and s["raw_frames"] is True and s["mask"] == "truth", (s["camera"], s["raw_frames"], s["mask"])
print("ok: eval-ratslam renders the realistic camera's raw frames, with the robot's parts masked")
PY
# By default the realistic camera's frames are masked as a lab masks them: calibrate-mirror's mask of
# 60 frames of the camera (--mask calibrated); the clean camera's are not masked.
"$BIN/eval-ratslam" --scene indoor13 --laps 0 --duration-s 2 --out "$OUT/rd" >/dev/null 2>"$OUT/rd.log" ||
  { cat "$OUT/rd.log"; exit 1; }
grep -q "realistic (raw, unwrapped), mask calibrated" "$OUT/rd.log" || { head -3 "$OUT/rd.log"; exit 1; }
"$BIN/eval-ratslam" --config "$OUT/clean.ini" --scene indoor13 --laps 0 --duration-s 2 --out "$OUT/rc" >/dev/null \
  2>"$OUT/rc.log" || { cat "$OUT/rc.log"; exit 1; }
grep -q "clean (panoramas), mask none" "$OUT/rc.log" || { head -3 "$OUT/rc.log"; exit 1; }
python3 - "$OUT/rd/summary.json" "$OUT/rc/summary.json" <<'PY'
import json, sys
d, c = (json.load(open(p)) for p in sys.argv[1:3])
assert (d["camera"], d["mask"]) == ("realistic", "calibrated"), (d["camera"], d["mask"])
assert (c["camera"], c["mask"]) == ("clean", "none"), (c["camera"], c["mask"])
print("ok: eval-ratslam masks the realistic camera's frames with a calibrated mask by default, not the clean one's")
PY
# A mask is of raw frames: panoramas rendered directly (the clean camera without --raw) refuse it.
if "$BIN/eval-ratslam" --config "$OUT/clean.ini" --scene indoor13 --laps 0 --duration-s 2 --mask truth --out "$OUT/rs2" 2>"$OUT/stderr"; then
  echo "FAIL: eval-ratslam took a mask without raw frames"; exit 1
fi
grep -qF "needs --raw or the realistic camera" "$OUT/stderr" || { cat "$OUT/stderr"; exit 1; }
echo "ok: eval-ratslam refuses a mask without raw frames"
