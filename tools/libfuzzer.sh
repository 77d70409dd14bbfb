#!/usr/bin/env bash
# libFuzzer (clang 14, Debian's clang and libclang-rt-14-dev) on the decoders and on the nodes
# without images, with AddressSanitizer and UBSan, in build-libfuzzer/. Each target runs for
# SECONDS (default 60) from a seed corpus of valid messages; -malloc_limit_mb reports any single
# allocation over 256 MB as a finding. Crashes and findings are left in build-libfuzzer/findings/.
#   tools/libfuzzer.sh [SECONDS]        (./snapnav libfuzzer [SECONDS])
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
BUILD="$ROOT/build-libfuzzer"
SECONDS_EACH="${1:-60}"
command -v clang++ >/dev/null || { echo "libfuzzer: needs clang++ (apt-get install clang libclang-rt-14-dev)" >&2; exit 1; }
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
CXX=clang++ CC=clang cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSNAPNAV_LIBFUZZER=ON \
  "${launcher[@]}" >/dev/null
nice cmake --build "$BUILD" -j "${JOBS:-2}" --target libfuzzer-decoders libfuzzer-nodes libfuzzer-seeds
mkdir -p "$BUILD/corpus/decoders" "$BUILD/corpus/nodes" "$BUILD/findings"
"$BUILD/bin/libfuzzer-seeds" "$BUILD/corpus/decoders" "$BUILD/corpus/nodes"
export ASAN_OPTIONS="detect_leaks=0:halt_on_error=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
status=0
for t in decoders nodes; do
  echo "== libfuzzer-$t for $SECONDS_EACH s"
  (cd "$BUILD/findings" && "$BUILD/bin/libfuzzer-$t" -max_total_time="$SECONDS_EACH" -malloc_limit_mb=256 \
    -rss_limit_mb=2048 -print_final_stats=1 "$BUILD/corpus/$t") 2>&1 | grep -avE "^#[0-9]+.*(NEW|REDUCE|pulse)" || status=1
done
[ "$status" = 0 ] && echo "libfuzzer: no finding" || echo "libfuzzer: FINDINGS above (inputs in $BUILD/findings)"
exit "$status"
