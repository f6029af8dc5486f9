#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz/) with clang, ASan and UBSan, and fuzzes each for a while.
#   scripts/fuzz.sh [SECONDS_PER_TARGET] [BUILD_DIR]     default: 60 s, build-fuzz
# Corpora grow in BUILD_DIR/corpus/<target> (seeded from the repository's scenes and small
# caches); crashes, leaks and timeouts are written to BUILD_DIR/findings/ and make the script
# exit 1. A one-hour run: scripts/fuzz.sh 3600 (fuzz/README.md).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
build=${2:-build-fuzz}
command -v clang++ >/dev/null || bash scripts/install-deps.sh
if [ ! -f "$build/build.ninja" ]; then
  CC=clang CXX=clang++ cmake -S . -B "$build" -G Ninja -DMAGBAKE_FUZZ=ON >/dev/null
fi
cmake --build "$build" --target scene_fuzzer cache_fuzzer
mkdir -p "$build/findings" "$build/corpus/scene" "$build/corpus/cache"
# Seeds: every scene file in the repository; the small golden caches.
find scenes tests fuzz -name '*.yaml' -exec cp -n {} "$build/corpus/scene/" \;
cp -n tests/golden/*.h5 "$build/corpus/cache/"
status=0
export LSAN_OPTIONS="suppressions=$PWD/fuzz/lsan.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
for target in scene_fuzzer cache_fuzzer; do
  corpus="$build/corpus/${target%_fuzzer}"
  echo "fuzz: $target for ${seconds} s on $(ls "$corpus" | wc -l) corpus files"
  log="$build/findings/$target.log"
  # The cache target runs without leak checks: HDF5 itself leaks metadata-cache entries on
  # nearly every corrupt file, and a leak scan after each such input cut the rate to 3 runs/s.
  # Leaks of our reader code are caught by the sanitizer suite (scripts/sanitize.sh).
  leaks=1
  [ "$target" = cache_fuzzer ] && leaks=0
  if ! "$build/fuzz/$target" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=4096 -print_final_stats=1 \
      -detect_leaks=$leaks \
      -artifact_prefix="$build/findings/$target-" "$corpus" >"$log" 2>&1; then
    status=1
    echo "fuzz: $target FOUND A PROBLEM (see $log and $build/findings/):" >&2
    grep -E "ERROR|SUMMARY|Test unit written" "$log" | head -5 >&2
  fi
  grep -E "^#[0-9]+ +DONE|stat::number_of_executed_units|stat::average_exec_per_sec|stat::new_units_added" "$log" | tail -4
done
exit $status
