#!/usr/bin/env bash
# The test suite under the sanitizers (README "Tests"; scripts/test.sh runs both steps).
#
#   scripts/sanitize.sh asan   build-san (clang, ASan + UBSan): every unit test (label `unit`,
#                              CLI tests included, running the sanitized binary) but the three
#                              SurveyBuffer ones (a 24-tree plot each, 2-4 minutes under ASan); not the
#                              `real` tests (minutes each, the normal build runs them)
#   scripts/sanitize.sh tsan   build-tsan (clang, ThreadSanitizer): only the test programs of the
#                              parallel code (kNN, neighbour graph and Dijkstra in reconstruct,
#                              JointBoost training and the evaluation splits in classify, scan
#                              simulation in synth, forest coding in encode), CLI tests left out,
#                              and a probe whose racing loop TSan must report (core/parallel.hpp
#                              tells TSan the fork/join edges of Debian's uninstrumented TBB)
#   scripts/sanitize.sh        both
# Any sanitizer report fails the test that triggered it.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/sanitizer_build.sh

export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:detect_stack_use_after_return=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export TSAN_OPTIONS=${TSAN_OPTIONS:-halt_on_error=1:second_deadlock_stack=1:suppressions=$PWD/scripts/tsan.supp}

TSAN_TESTS=(reconstruct_test classify_jointboost_test classify_evaluation_test synth_test encode_compression_test tsan_race_probe)

run_asan() {
  build_sanitized all
  ctest --test-dir "$SAN_BUILD_DIR" -L unit -E '^SurveyBuffer[.]' --output-on-failure -j "$(nproc)" --timeout 900
}

run_tsan() {
  configure_sanitized "$TSAN_BUILD_DIR" thread
  cmake --build "$TSAN_BUILD_DIR" -j "$(nproc)" --target "${TSAN_TESTS[@]}"
  ctest --test-dir "$TSAN_BUILD_DIR" -E '_NOT_BUILT|Cli' --output-on-failure -j "$(nproc)" --timeout 900
}

case "${1:-all}" in
  asan) run_asan ;;
  tsan) run_tsan ;;
  all) run_asan; run_tsan ;;
  *) sed -n '2,14p' "$0" >&2; exit 1 ;;
esac
