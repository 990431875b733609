# Sourced by scripts/fuzz.sh and scripts/sanitize.sh: the sanitizer build folders.
#   build-san   clang, ASan + UBSan (-O1, line tables, assertions on), libFuzzer coverage on every
#               library: the unit tests under the sanitizers and the fuzz targets share it; a unity
#               build like build/ (scripts/setup.sh)
#   build-tsan  clang, ThreadSanitizer: only the tests of the parallel code; compiled file by file,
#               so that a source which does not include what it uses fails here even when its
#               unity batch hides it
# Both build only the targets asked for, never the whole project.
SAN_BUILD_DIR=${TREELOBES_SAN_BUILD_DIR:-build-san}
TSAN_BUILD_DIR=${TREELOBES_TSAN_BUILD_DIR:-build-tsan}

configure_sanitized() {  # DIR SANITIZER [cmake args...]
  local dir=$1 sanitizer=$2
  shift 2
  [ -f "$dir/build.ninja" ] && return 0
  cmake -S . -B "$dir" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=Sanitize \
    -DCMAKE_CXX_FLAGS_SANITIZE="-O1 -gline-tables-only" -DTREELOBES_SANITIZER="$sanitizer" \
    -DTREELOBES_BUILD_BENCH=OFF "$@" >/dev/null
}

build_sanitized() {  # TARGET... in the ASan + UBSan + fuzz folder
  configure_sanitized "$SAN_BUILD_DIR" address,undefined -DTREELOBES_FUZZ=ON -DCMAKE_UNITY_BUILD=ON
  cmake --build "$SAN_BUILD_DIR" -j "$(nproc)" --target "$@"
}
