#!/usr/bin/env bash
# What exact surfaces cost in the forces and the induction (physics.md §12): the same binary
# bakes paper scenes whose magnets are cylinders or meshes with the preset's surfaces and with
# `surface_tolerance: 0` (cells only: the code path of the forces before surfaces), interleaved,
# REPEAT times each, 1 thread; prints median wall times and the substeps the bakes took.
#   bench/run_surface_force_bench.sh [BUILD_DIR] [REPEAT]     (default build-release, 3)
set -euo pipefail
cd "$(dirname "$0")/.."
source bench/bench_lib.sh
exe=${1:-build-release}/bake/magbake
repeat=${2:-3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
rows=("tst|1-60" "tst_same|1-45" "bowl_spheres|1-24" "dragon_low|1-3")
machine_line
echo
echo "| scene | frames | surfaces: bake s (median of $repeat) | cells only: bake s | ratio |"
echo "| --- | --- | --- | --- | --- |"
for row in "${rows[@]}"; do
  IFS='|' read -r name frames <<< "$row"
  # Outputs: the cache only (no previews or volumes), written under the work folder.
  for v in surfaces cells; do
    sed -e 's|^magnetics: {|magnetics: {surface_tolerance: SURF, |' -e "s|\.\./meshes/|$PWD/scenes/meshes/|" \
      -e '/^  preview:/,/camera:/d' scenes/paper/$name.yaml | sed "s|SURF|$([ $v = cells ] && echo 0 || echo 1e-5)|" > "$work/${name}_$v.yaml"
    grep -q "surface_tolerance" "$work/${name}_$v.yaml" || { echo "could not set surface_tolerance in $name" >&2; exit 1; }
    # The default preset's tolerance is 1e-5 m = 0.01 mm; scenes are in mm.
    sed -i 's|surface_tolerance: 1e-5|surface_tolerance: 0.01|' "$work/${name}_$v.yaml"
  done
  declare -A t=()
  for r in $(seq "$repeat"); do
    for v in surfaces cells; do
      t0=$(date +%s.%N)
      rm -rf "$work/out_$v"
      "$exe" -q bake "$work/${name}_$v.yaml" --frames "$frames" --threads 1 -o "$work/out_$v" >/dev/null
      t1=$(date +%s.%N)
      t[$v]+="$(echo "$t1 - $t0" | bc) "
    done
  done
  s=$(echo "${t[surfaces]}" | median) c=$(echo "${t[cells]}" | median)
  echo "| $name | $frames | $s | $c | $(echo "scale=2; $s / $c" | bc) |"
done
echo
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
