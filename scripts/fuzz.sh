#!/usr/bin/env bash
# libFuzzer runs of the targets in fuzz/ (docs/fuzzing.md).
#
#   scripts/fuzz.sh TARGET SECONDS [libFuzzer flags...]   one target, e.g. `scripts/fuzz.sh las 60`
#   scripts/fuzz.sh --all SECONDS                         every target in turn
#   scripts/fuzz.sh --list                                the target names
#   scripts/fuzz.sh --seeds                               regenerate fuzz/seeds from data/synthetic
#   --no-build (first argument)                           use the built binaries as they are (ctest -L fuzz)
#
# Build folder: $TREELOBES_SAN_BUILD_DIR (default build-san: clang, ASan + UBSan, libFuzzer
# coverage; the same folder as scripts/sanitize.sh). The corpus a run grows is kept in
# <build>/fuzz-corpus/TARGET (the committed seeds in fuzz/seeds/TARGET are only read), inputs
# that crash, hang or run out of memory go to <build>/fuzz-artifacts/TARGET/. A finding makes
# the script exit non-zero; reproduce it with `<build>/bin/fuzz_TARGET FILE`.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/sanitizer_build.sh

build=1
if [ "${1:-}" = "--no-build" ]; then build=0; shift; fi
targets=$(sed -n 's/^treelobes_add_fuzzer(\([a-z_0-9]*\) .*/\1/p' fuzz/CMakeLists.txt)

case "${1:-}" in
  --list) echo "$targets"; exit 0 ;;
  --seeds)
    [ $build -eq 1 ] && build_sanitized fuzz_make_seeds
    rm -rf fuzz/seeds && "$SAN_BUILD_DIR/bin/fuzz_make_seeds" . fuzz/seeds
    exit 0 ;;
  --all)
    seconds=${2:?usage: scripts/fuzz.sh --all SECONDS}
    [ $build -eq 1 ] && build_sanitized fuzzers
    failed=()
    for target in $targets; do scripts/fuzz.sh --no-build "$target" "$seconds" || failed+=("$target"); done
    [ ${#failed[@]} -eq 0 ] || { echo "fuzz.sh: findings in ${failed[*]}" >&2; exit 1; }
    exit 0 ;;
  ""|-*) sed -n '2,16p' "$0" >&2; exit 1 ;;
esac

target=$1
seconds=${2:?usage: scripts/fuzz.sh TARGET SECONDS}
shift 2
grep -qx "$target" <<< "$targets" || { echo "fuzz.sh: no target '$target' (scripts/fuzz.sh --list)" >&2; exit 1; }
[ $build -eq 1 ] && build_sanitized "fuzz_$target"

corpus=$SAN_BUILD_DIR/fuzz-corpus/$target
artifacts=$SAN_BUILD_DIR/fuzz-artifacts/$target
mkdir -p "$corpus" "$artifacts"
seeds=()
[ -d "fuzz/seeds/$target" ] && seeds+=(fuzz/seeds/"$target")
# Small real LAS tiles join the seeds when the data is there.
real=${TREELOBES_REAL_DATA:-$(cd .. && pwd)/shared/data}
if [ "$target" = las ] && [ -d "$real" ]; then
  mkdir -p "$corpus-real"
  # Not `| head -40`: under pipefail, sort's SIGPIPE once head has its 40 lines fails the run.
  mapfile -t small_tiles < <(find "$real" -name '*.las' -size -8k 2>/dev/null | sort)
  [ ${#small_tiles[@]} -eq 0 ] || cp -t "$corpus-real" "${small_tiles[@]:0:40}"
  seeds+=("$corpus-real")
fi
# The LAZ target has no committed seeds: the real LAZ/COPC files under 64 kB are its seeds.
if [ "$target" = laz ] && [ -d "$real" ]; then
  mkdir -p "$corpus-real"
  find "$real" -name '*.laz' -size -64k 2>/dev/null | sort | xargs -r cp -t "$corpus-real"
  seeds+=("$corpus-real")
fi
# The .tlobe file target also starts from the version 3 file the tests keep (the older mesh coding).
if [ "$target" = tlobe ]; then seeds+=(tests/data/tlobe); fi
flags=(-max_total_time="$seconds" -timeout=10 -rss_limit_mb=2560 -malloc_limit_mb=1024
       -artifact_prefix="$artifacts/" -print_final_stats=1)
[ -f "fuzz/dicts/$target.dict" ] && flags+=(-dict="fuzz/dicts/$target.dict")
log=$SAN_BUILD_DIR/fuzz-artifacts/$target.log
echo "fuzz.sh: $target for ${seconds}s (corpus $corpus, log $log)" >&2
status=0
"$SAN_BUILD_DIR/bin/fuzz_$target" "${flags[@]}" "$@" "$corpus" "${seeds[@]}" >"$log" 2>&1 || status=$?
grep -E '^#[0-9]+ +DONE|^Done [0-9]+ runs|stat::number_of_executed_units|stat::peak_rss_mb' "$log" | sed "s/^/$target: /" >&2 || true
if [ $status -ne 0 ]; then
  echo "fuzz.sh: $target FAILED (exit $status); the end of $log:" >&2
  tail -40 "$log" >&2
fi
exit $status
