#!/usr/bin/env bash
# Results do not depend on the build (issue 15): builds magbake as Release and as Debug (the
# program only, beside the main build), bakes the two golden scenes (and, except in Debug,
# where it takes minutes, the demo scene) with each, and requires caches bit for bit equal to
# those of the main build (RelWithDebInfo by default), and the goldens to match within `magbake
# diff`'s default tolerances (the Bake.GoldenCachesStillMatch check, from every build type).
# Measured 2026-12-06 (AMD EPYC, 2 cores): Release and Debug bit for bit equal on all three.
#   bash scripts/check-build-types.sh [MAIN_BUILD_DIR] [TYPES...]   (default: build Release Debug)
set -euo pipefail
cd "$(dirname "$0")/.."
main=${1:-build}
shift || true
types=("$@")
[ ${#types[@]} -gt 0 ] || types=(Release Debug)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# resume_saturation: the saturating law's Newton steps (scene 1.1), contacts included.
scenes=(tests/golden/magnets_in_space.yaml tests/golden/sphere_pickup.yaml scenes/demo.yaml tests/data/resume_saturation.yaml)
bake() {  # exe name scene
  "$1" -q --threads 2 bake "$3" -o "$work/$2" --cache-only >/dev/null
}
for s in "${scenes[@]}"; do bake "$main/bake/magbake" main "$s"; done
status=0
for t in "${types[@]}"; do
  dir="$main-$(echo "$t" | tr '[:upper:]' '[:lower:]')"
  [ -f "$dir/build.ninja" ] || cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE="$t" -DMAGBAKE_BUILD_TESTS=OFF \
    -DMAGBAKE_BUILD_BENCH=OFF >/dev/null
  cmake --build "$dir" --target magbake
  for s in "${scenes[@]}"; do
    [ "$t" = Debug ] && [ "$s" = scenes/demo.yaml ] && continue
    bake "$dir/bake/magbake" "$t" "$s"
  done
  for f in "$work/main"/*.h5; do
    b=$(basename "$f")
    [ -f "$work/$t/$b" ] || continue
    if "$dir/bake/magbake" diff "$f" "$work/$t/$b" --exact >/dev/null; then
      echo "check-build-types: $t $b: bit for bit equal to $main's"
    else
      echo "check-build-types: $t $b DIFFERS from $main's:" >&2
      "$dir/bake/magbake" diff "$f" "$work/$t/$b" >&2 || true
      status=1
    fi
  done
  for g in magnets_in_space sphere_pickup; do
    if "$dir/bake/magbake" diff "tests/golden/$g.h5" "$work/$t/$g.h5" >/dev/null; then
      echo "check-build-types: $t $g.h5 matches the golden cache"
    else
      echo "check-build-types: $t $g.h5 does not match tests/golden/$g.h5" >&2
      status=1
    fi
  done
done
exit $status
