#!/usr/bin/env bash
# The demo's place-cell memory, explored once (ctest demo_explored_memory, a fixture): the demo's own
# step 2 (`tools/demo.sh --explore-only`: `launch config/deploy/demo.deploy --group explore` into OUT).
# The tests that run the demo's lab but do not test exploring (soak_stack_2min, robots_three_on_one_bus,
# two_host_demo_and_clock_offset, demo_fault_run) reuse it with --explored OUT. Fails unless the
# memory, the grid's home image and the camera's mask are there.
set -euo pipefail
BIN="$1"; OUT="$2"
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
rm -rf "$OUT"; mkdir -p "$OUT"  # placecells extends a memory it finds: start afresh
"$ROOT/tools/demo.sh" "$BIN" --out "$OUT" --no-bus-health --explore-only >"$OUT/explore.log" 2>&1 ||
  { echo "explore fixture: the demo's explore step failed (the last lines of $OUT/explore.log):" >&2; tail -n 20 "$OUT/explore.log" >&2; exit 1; }
for f in placecells.mem grid/images/6_6.png camera_mask.png; do
  [ -s "$OUT/$f" ] || { echo "explore fixture: $OUT/$f missing after the explore group" >&2; exit 1; }
done
grep -E "placecells: (saved|explore, memory)|done \(--explore-only\)" "$OUT/explore.log" || true
echo "explore fixture: memory in $OUT (${SECONDS} s)"
