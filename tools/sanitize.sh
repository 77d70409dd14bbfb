#!/usr/bin/env bash
# The fuzz tests (decoders, process nodes, log reader, log tools, replay) built with
# AddressSanitizer and UndefinedBehaviorSanitizer (cmake -DSNAPNAV_SANITIZE=ON) in
# build-sanitize/, then run: any heap overflow, use after free, leak, signed overflow, bad shift
# or misaligned access stops the run with a report. Not part of CI (the build takes a while).
#   tools/sanitize.sh [BUILD_DIR]       (./snapnav sanitize)
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
BUILD="${1:-$ROOT/build-sanitize}"
JOBS="${JOBS:-2}"
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSNAPNAV_SANITIZE=ON "${launcher[@]}" >/dev/null
targets=(fuzz_decoders_tests fuzz_nodes_tests replay_tests log_tools_tests snapnav_tests replay log-report)
nice cmake --build "$BUILD" -j "$JOBS" --target "${targets[@]}"
export ASAN_OPTIONS="detect_leaks=1:halt_on_error=1:abort_on_error=0:strict_string_checks=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
# LeakSanitizer: what OpenCV's and glib's one-time initialisations keep for the process lifetime.
supp="$BUILD/lsan.supp"
printf 'leak:libglib\nleak:libgobject\nleak:libopencv\nleak:libtbb\nleak:libgomp\n' >"$supp"
export LSAN_OPTIONS="suppressions=$supp"
status=0
run() {
  echo "== $*"
  "$@" || status=1
}
run "$BUILD/bin/fuzz_decoders_tests"
run "$BUILD/bin/fuzz_nodes_tests"
run "$BUILD/bin/snapnav_tests" --gtest_filter='LogReader*:LcmTypes*:DeadReckoning*:Bus*'
run "$BUILD/bin/log_tools_tests"
run "$BUILD/bin/replay_tests"
[ "$status" = 0 ] && echo "sanitize: no finding" || echo "sanitize: FINDINGS above"
exit "$status"
