#!/usr/bin/env bash
# Zen-magnet stress benchmark (issue 11): 216 ball magnets as a falling heap and a resting lattice,
# baked at the default preset; medians of substeps and wall time per frame.
# Usage: bench/run_zen_bench.sh BUILD_DIR OUT_DIR [FRAMES] [BASELINE_MAGBAKE]
#   BASELINE_MAGBAKE: another magbake binary baked side by side in the same run (before/after).
#   SLEEP_BASELINE=1: the baseline is this binary with `time.sleep: 0` (no body sleeps).
set -euo pipefail
build=${1:?build dir}; out=${2:?output dir}; frames=${3:-5}; baseline=${4:-}
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$out/zen"
python3 "$here/make_zen_magnets.py" "$out/zen" "$frames"
if [ -n "${SLEEP_BASELINE:-}" ]; then
  mkdir -p "$out/zen/nosleep"
  python3 "$here/make_zen_magnets.py" "$out/zen/nosleep" "$frames" 0
  baseline="$build/bake/magbake"
fi
{ echo "zen bench $(date -u +%FT%TZ) on $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"; uptime; } >> "$out/machine.txt"
args=()
for scene in zen_heap zen_lattice; do
  for run in after baseline; do
    exe="$build/bake/magbake"; [ "$run" = baseline ] && { [ -n "$baseline" ] || continue; exe=$baseline; }
    rm -rf "$out/zen/$run-$scene"
    yaml="$out/zen/$scene.yaml"
    [ "$run" = baseline ] && [ -n "${SLEEP_BASELINE:-}" ] && yaml="$out/zen/nosleep/$scene.yaml"
    echo "== $scene ($run: $exe $yaml), load $(cut -d' ' -f1-3 /proc/loadavg)"
    "$exe" -q bake "$yaml" -o "$out/zen/$run-$scene" || true
    args+=("$scene $run=$out/zen/$run-$scene/$scene.h5")
  done
done
/usr/bin/python3 "$here/zen_summary.py" "$out/zen_magnets.csv" "$out/zen_magnets.md" "${args[@]}"
