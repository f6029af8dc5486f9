#!/usr/bin/env bash
# What exact surfaces (physics.md §12) cost: the same binary bakes TST (4 cylinder magnets, two
# frames with preview field lines) and exports its field volume, with the preset's surfaces and
# with `surface_tolerance: 0` (cells only), interleaved, REPEAT times each; prints medians.
#   bench/run_surface_bench.sh [BUILD_DIR] [REPEAT]     (default build, 5)
set -euo pipefail
cd "$(dirname "$0")/.."
source bench/bench_lib.sh
exe=${1:-build}/bake/magbake
repeat=${2:-5}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
sed 's|^magnetics: {|magnetics: {surface_tolerance: 0, |; s|^magnetics:$|magnetics:\n  surface_tolerance: 0|' \
  scenes/paper/tst.yaml > "$work/tst_cells.yaml"
grep -q "surface_tolerance: 0" "$work/tst_cells.yaml" || { echo "could not turn surfaces off" >&2; exit 1; }
cp scenes/paper/tst.yaml "$work/tst_surfaces.yaml"
echo "machine: $(nproc) cores, load before: $(cut -d' ' -f1-3 /proc/loadavg)"
declare -A bake field
for r in $(seq "$repeat"); do
  for v in surfaces cells; do
    t0=$(date +%s.%N)
    "$exe" -q bake "$work/tst_$v.yaml" --frames 1-2 -o "$work/out_$v" >/dev/null 2>&1
    t1=$(date +%s.%N)
    rm -rf "$work/vol_$v"
    "$exe" -q field "$work/out_$v/tst.h5" --frames 1-1 --voxel 0.001 -o "$work/vol_$v/f.####.vdb" >/dev/null 2>&1
    t2=$(date +%s.%N)
    bake[$v]+="$(echo "$t1 - $t0" | bc) "
    field[$v]+="$(echo "$t2 - $t1" | bc) "
  done
done
echo "| variant | bake 2 frames + previews, s (median of $repeat) | field volume 1 mm voxels, frame 1, s |"
echo "| --- | --- | --- |"
for v in surfaces cells; do
  echo "| $v | $(echo "${bake[$v]}" | median) | $(echo "${field[$v]}" | median) |"
done
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
