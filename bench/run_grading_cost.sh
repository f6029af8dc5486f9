#!/usr/bin/env bash
# What graded soft cells (magnetics.grading, physics.md §7) cost on the paper's scenes: the same
# binary bakes each scene's first frames with `grading: 0` (uniform cells, the code path before
# grading) and `grading: 1` (the default preset's), interleaved, REPEAT times each, 1 thread;
# prints the median wall time of each bake, the ratio, the induced cell counts and the mean
# induction iterations per evaluation (from the caches).
#   bench/run_grading_cost.sh [BUILD_DIR] [REPEAT]     (default build, 3)
set -euo pipefail
cd "$(dirname "$0")/.."
source bench/bench_lib.sh
exe=${1:-build}/bake/magbake
repeat=${2:-3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
rows=("tst|1-30" "bowl_spheres|1-15" "bowl_2008|1-15" "supercube|1-15" "dragon_low|1-2")
machine_line
echo
echo "| scene | preset | frames | grading 0: bake s (median of $repeat) | grading 1: bake s | ratio | induction iterations per frame (mean of the cache observable) 0 / 1 |"
echo "| --- | --- | --- | --- | --- | --- | --- |"
for row in "${rows[@]}"; do
  IFS='|' read -r name frames <<< "$row"
  for g in 0 1; do
    # Outputs: the cache only (no previews or volumes), written under the work folder.
    sed -e "s|^magnetics: {|magnetics: {grading: $g, |" -e "s|\.\./meshes/|$PWD/scenes/meshes/|" \
      -e '/^  preview:/,/camera:/d' scenes/paper/$name.yaml > "$work/${name}_$g.yaml"
    grep -q "grading: $g" "$work/${name}_$g.yaml" || { echo "could not set grading in $name" >&2; exit 1; }
  done
  preset=$(grep -o 'quality: [a-z]*' scenes/paper/$name.yaml | head -1 | cut -d' ' -f2)
  declare -A t=()
  for r in $(seq "$repeat"); do
    for g in 0 1; do
      t[$g]+="$(timed_bake "$exe" "$work/${name}_$g.yaml" "$frames" "$work/out_$g") "
    done
  done
  its=()
  for g in 0 1; do its+=("$(cache_mean "$work/out_$g" induction_iterations)"); done
  a=$(echo "${t[0]}" | median) b=$(echo "${t[1]}" | median)
  echo "| $name | $preset | $frames | $a | $b | $(echo "scale=2; $b / $a" | bc) | ${its[0]} / ${its[1]} |"
done
echo
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
