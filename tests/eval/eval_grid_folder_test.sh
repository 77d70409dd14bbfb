#!/usr/bin/env bash
# eval homing --grid and eval localization --grid (issue 21): a folder as gridgen writes it is read
# back to the figures of the rendered evaluation, and bad folders (no positions.csv, a missing
# image, a CSV line that does not parse, images of different sizes, two images at one grid
# index) are reported by file and line.
set -euo pipefail
BIN="$1"
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT

# Bad folders: small panoramas written here (PNG by hand, no image library needed).
python3 - "$OUT" <<'PY'
import os, struct, sys, zlib
out = sys.argv[1]
def png(path, w, h, seed):
    rows = b"".join(b"\x00" + bytes(((x * 7 + y * 13 + seed) % 251) for x in range(w)) for y in range(h))
    chunk = lambda t, d: struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xffffffff)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))
def folder(name, lines, sizes):
    d = os.path.join(out, name)
    os.makedirs(d)
    for i, (w, h) in enumerate(sizes):
        png(os.path.join(d, f"p{i}.png"), w, h, i)
    with open(os.path.join(d, "positions.csv"), "w") as f:
        f.write("file,ix,iy,x_m,y_m,heading_rad,utime\n" + "".join(l + "\n" for l in lines))
ok = ["p0.png,0,0,0.0,0.0,0,0", "p1.png,1,0,0.2,0.0,0,0", "p2.png,0,1,0.0,0.2,0,0", "p3.png,1,1,0.2,0.2,0,0"]
folder("missing_image", ok[:2] + ["p9.png,0,1,0.0,0.2,0,0"] + ok[3:], [(720, 120)] * 4)
folder("bad_number", ok[:3] + ["p3.png,1,1,0.2,abc,0,0"], [(720, 120)] * 4)
folder("bad_fields", ok[:1] + ["p1.png,1,0,0.2"] + ok[2:], [(720, 120)] * 4)
folder("sizes", ok, [(720, 120), (720, 120), (360, 60), (720, 120)])
folder("twice", ok[:3] + ["p3.png,1,0,0.2,0.2,0,0"], [(720, 120)] * 4)
os.makedirs(os.path.join(out, "no_csv"))
PY
refused() {  # TOOL FOLDER EXPECTED
  if "$BIN/$1" --grid "$OUT/$2" --out "$OUT/o_$2" >"$OUT/stdout" 2>"$OUT/stderr"; then
    echo "FAIL: $1 accepted $2"; exit 1
  fi
  grep -qF -- "$3" "$OUT/stderr" || { echo "FAIL: $1 on $2 did not say '$3':"; cat "$OUT/stderr"; exit 1; }
  echo "ok: $1 $2: $(grep error "$OUT/stderr")"
}
for tool in eval-homing eval-localization; do
  refused $tool no_csv "no_csv/positions.csv: missing"
  refused $tool missing_image "missing_image/positions.csv:4: $OUT/missing_image/p9.png: missing or not an image"
  refused $tool bad_number "bad_number/positions.csv:5: column y_m: 'abc' is not a number"
  refused $tool bad_fields "bad_fields/positions.csv:3: 4 fields, the header has 7"
  refused $tool sizes "sizes/positions.csv:4: $OUT/sizes/p2.png is 360x60, the first image (p0.png, line 2) is 720x120"
  refused $tool twice "twice/positions.csv:5: a second image at ix 1, iy 0 (the first on line 3)"
done

# gridgen's folder read back: the same figures as the rendered evaluation of the scene. With the clean
# camera, whose images are the same on every render (the realistic one draws new noise per frame).
sed '0,/^preset = realistic /s//preset = clean /' "$(dirname "$0")/../../config/sim.ini" > "$OUT/clean.ini"
grep -q '^preset = clean ' "$OUT/clean.ini"
# At heading 0, as the rendered evaluation:
"$BIN/gridgen" --config "$OUT/clean.ini" --scene indoor_objects11 --heading-deg 0 --out "$OUT/grid" 2>/dev/null
test -s "$OUT/grid/camera.ini"
"$BIN/eval-homing" --scene indoor_objects11 --camera clean --quick --no-return --protocols snapnav,thesis-5x5 \
  --out "$OUT/rendered" \
  >/dev/null 2>"$OUT/rendered.log" || { cat "$OUT/rendered.log"; exit 1; }
"$BIN/eval-homing" --grid "$OUT/grid" --protocols snapnav,thesis-5x5 --out "$OUT/folder" \
  >/dev/null 2>"$OUT/folder.log" || { cat "$OUT/folder.log"; exit 1; }
"$BIN/eval-localization" --grid "$OUT/grid" --measures bearing-smallest --filters on --leave-one-out-stride 12 \
  --out "$OUT/loc" >/dev/null 2>"$OUT/loc.log" || { cat "$OUT/loc.log"; exit 1; }
"$BIN/eval-localization" --scene indoor_objects11 --camera clean --memories grid --measures bearing-smallest --filters on \
  --tests 1 \
  --protocols snapnav,leave-one-out --leave-one-out-stride 12 --out "$OUT/loc_rendered" >/dev/null 2>"$OUT/loc_rendered.log" ||
  { cat "$OUT/loc_rendered.log"; exit 1; }
python3 - "$OUT/rendered/summary.json" "$OUT/folder/summary.json" "$OUT/loc/summary.json" "$OUT/loc_rendered/summary.json" <<'PY'
import json, sys
rendered, folder, loc, loc_rendered = (json.load(open(p)) for p in sys.argv[1:5])
print(f"indoor_objects11: AAE rendered {rendered['average_angular_error_deg']:.2f} deg, from gridgen's folder "
      f"{folder['average_angular_error_deg']:.2f} deg; thesis 5x5 {rendered['thesis_5x5_configuration_aae_deg']:.2f} / "
      f"{folder['thesis_5x5_configuration_aae_deg']:.2f} deg; leave-one-out {loc['leave_one_out_queries']} queries, "
      f"{loc['leave_one_out_mean_localization_error_m']:.3f} m (rendered {loc_rendered['leave_one_out_mean_localization_error_m']:.3f} m)")
assert folder["grid_positions"] == rendered["grid_positions"] == 120, folder["grid_positions"]
assert abs(folder["average_angular_error_deg"] - rendered["average_angular_error_deg"]) < 0.05
assert abs(folder["thesis_5x5_configuration_aae_deg"] - rendered["thesis_5x5_configuration_aae_deg"]) < 0.05
assert folder["thesis_5x5_positions"] == 24
assert loc["leave_one_out_queries"] == 11, loc["leave_one_out_queries"]
assert abs(loc["leave_one_out_mean_nearest_cell_distance_m"] - 0.2) < 1e-6, loc["leave_one_out_mean_nearest_cell_distance_m"]
assert loc_rendered["leave_one_out_queries"] == 11
assert abs(loc["leave_one_out_mean_localization_error_m"] - loc_rendered["leave_one_out_mean_localization_error_m"]) < 0.005
PY
