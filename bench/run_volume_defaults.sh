#!/usr/bin/env bash
# Field volumes' defaults side by side (issue 16 outcome 3): the defaults until 2026-12-07
# (threshold 1e-5 T, margin 2 cm; emulated with --threshold 1e-5 --margin 0.02, which differ
# from them only in that the applied field no longer makes voxels active) against the auto
# threshold and margin, on one frame of each shot, interleaved, RUNS runs each (median time).
# Reports voxels, active share, file size and export time.
# Usage: bench/run_volume_defaults.sh [build dir] [results dir]      RUNS=3
set -euo pipefail
build=$(realpath "${1:-build}")
out=$(realpath -m "${2:-bench/results/volume_defaults}")
runs=${RUNS:-3}
here=$(cd "$(dirname "$0")/.." && pwd)
source "$here/bench/bench_lib.sh"
exe="$build/bake/magbake"
work=$(mktemp -d /tmp/magbake_volume_defaults.XXXX)
mkdir -p "$out"
md="$out/volume_defaults.md"
{
  echo "# Field volume defaults, side by side ($(date -u +%F), $(git -C "$here" rev-parse --short HEAD))"
  echo
  machine_line
  echo
  echo "| shot (frame) | defaults | voxels | active | file | export time (median of $runs) |"
  echo "| --- | --- | --- | --- | --- | --- |"
} > "$md"
# name scene frames frame
shots=(
  "compass_needle $here/bench/compass_needle.yaml 1-10 10"
  "demo $here/scenes/demo.yaml 1-60 60"
  "tst $here/scenes/paper/tst.yaml 1-3 3"
  "bowl_spheres $here/scenes/paper/bowl_spheres.yaml 1-3 3"
)
for s in "${shots[@]}"; do
  read -r name scene frames frame <<< "$s"
  "$exe" bake "$scene" -o "$work/$name" --frames "$frames" --cache-only --force -q > /dev/null 2>&1
  cache=$(ls "$work/$name"/*.h5)
  declare -A times=()
  for r in $(seq "$runs"); do
    for mode in old auto; do
      args="--threshold auto --margin auto"
      [ "$mode" = old ] && args="--threshold 1e-5 --margin 0.02"
      rm -rf "$work/vol_$mode"
      t0=$(date +%s.%N)
      "$exe" field "$cache" --frames "$frame-$frame" --every 1 $args -o "$work/vol_$mode/f.####.vdb" > "$work/log_$mode" 2>&1
      t1=$(date +%s.%N)
      times[$mode]="${times[$mode]:-} $(echo "$t1 - $t0" | bc)"
    done
  done
  for mode in old auto; do
    f=$(ls "$work/vol_$mode"/*.vdb)
    dims=$(grep -o "[0-9]* x [0-9]* x [0-9]*" "$work/log_$mode" | head -1)
    share=$(grep -o '[0-9.e+-]*% of their voxels active' "$work/log_$mode" | cut -d' ' -f1)
    size=$(du -k "$f" | cut -f1)
    label="1e-5 T, 2 cm"; [ "$mode" = auto ] && label="auto"
    echo "| $name ($frame) | $label | $dims | $share | $size KiB | $(printf %.2f "$(echo "${times[$mode]}" | median)") s |" >> "$md"
  done
  unset times
done
echo >> "$md"
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)" >> "$md"
rm -rf "$work"
cat "$md"
