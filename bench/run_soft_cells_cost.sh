#!/usr/bin/env bash
# What the default preset's 8 cells across soft parts (magnetics.soft_cells_across, physics.md §7)
# costs against the 4 it had before 2026-12-07: the same binary bakes each scene's first frames
# with `soft_cells_across: 4` and `: 8`, interleaved, REPEAT times each, 1 thread; prints the
# median wall time of each bake, the ratio, the soft cell counts and the mean induction iterations
# per frame (from the caches). The paper scenes pin 4 (their Table 1 resolution); here the pin is
# replaced. SuperCube (a superconductor) and the dragons (cell_size) are not affected.
#   bench/run_soft_cells_cost.sh [BUILD_DIR] [REPEAT]     (default build, 3)
set -euo pipefail
cd "$(dirname "$0")/.."
source bench/bench_lib.sh
exe=${1:-build}/bake/magbake
repeat=${2:-3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
rows=("scenes/demo.yaml|1-30" "scenes/paper/tst.yaml|1-30" "scenes/paper/bowl_spheres.yaml|1-15")
machine_line
echo
echo "| scene | frames | 4 across: bake s (median of $repeat) | 8 across: bake s | ratio | cells 4 / 8 | induction iterations per frame 4 / 8 |"
echo "| --- | --- | --- | --- | --- | --- | --- |"
for row in "${rows[@]}"; do
  IFS='|' read -r file frames <<< "$row"
  name=$(basename "$file" .yaml)
  for k in 4 8; do
    # Outputs: the cache only (no previews or volumes), written under the work folder.
    sed -e "s|, soft_cells_across: 4||" -e "s|^magnetics: {|magnetics: {soft_cells_across: $k, |" \
      -e "s|^  quality: default|  quality: default\n  soft_cells_across: $k|" -e "s|\.\./meshes/|$PWD/scenes/meshes/|" \
      -e '/^outputs:/,$d' "$file" > "$work/${name}_$k.yaml"
    grep -q "soft_cells_across: $k" "$work/${name}_$k.yaml" || { echo "could not set soft_cells_across in $name" >&2; exit 1; }
  done
  declare -A t=()
  for r in $(seq "$repeat"); do
    for k in 4 8; do
      t[$k]+="$(timed_bake "$exe" "$work/${name}_$k.yaml" "$frames" "$work/out_$k") "
    done
  done
  its=() cells=()
  for k in 4 8; do
    cells+=("$("$exe" check "$work/${name}_$k.yaml" --trial 0 | sed -n 's/^cells .*(total \([0-9]*\)).*/\1/p')")
    its+=("$(cache_mean "$work/out_$k" induction_iterations)")
  done
  a=$(echo "${t[4]}" | median) b=$(echo "${t[8]}" | median)
  echo "| $name | $frames | $a | $b | $(echo "scale=2; $b / $a" | bc) | ${cells[0]} / ${cells[1]} | ${its[0]} / ${its[1]} |"
done
echo
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
