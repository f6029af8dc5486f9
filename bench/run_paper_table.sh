#!/usr/bin/env bash
# The paper's Table 1, its "Gain", and run time against error for every scene of scenes/paper.
# Bakes each shot (magbake bake, all cores), then runs build/bench/paper_table on a window of the
# shot's close-contact part (1 thread and all cores) and at two instants where bodies touch or
# nearly touch, then writes the table, the per-scene CSVs and the Pareto plot.
#
# Usage: bench/run_paper_table.sh [build dir] [results dir] [--reuse] [--only LABEL ...] [--parts P]
#   --reuse   keep a shot's cache from an earlier run if it was baked from the same scene file
#   --only    run only these labels (the table is still made from every result in the folder)
#   --parts   timing,gain,error (default all): e.g. the slow error references first, then the
#             timings alone on a quiet machine; results of separate runs are merged
# Writes RESULTS/paper/<label>.json, <label>_time_vs_error.csv, bakes.txt, machine.txt, and
# RESULTS/paper_table.md, paper_table.csv, paper_pareto.png (bench/paper_table.py).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(dirname "$here")
build=${1:-build}
results=${2:-bench/results}
shift $(( $# > 2 ? 2 : $# ))
reuse=0
only=()
parts=timing,gain,error
while [ $# -gt 0 ]; do
  case "$1" in
    --reuse) reuse=1 ;;
    --only) shift; only+=("$1") ;;
    --parts) shift; parts=$1 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
  shift
done
magbake="$build/bake/magbake"
driver="$build/bench/paper_table"
bakes="$build/paper_bakes"
out="$results/paper"
mkdir -p "$out" "$bakes"

# label | scene | window start frame : frames | instants (frames where bodies touch or nearly
# touch) | largest reference model (cells) the convergence ladder may build
scenes=(
  "TST|tst.yaml|72:6|73,80|250000"
  "BowlSpheres|bowl_spheres.yaml|18:6|20,50|6000"
  "Bowl2008|bowl_2008.yaml|24:6|26,60|40000"
  "SuperCube|supercube.yaml|5:6|7,34|250000"
  "DragonLow|dragon_low.yaml|10:3|8,15|60000"
  "DragonHigh|dragon_high.yaml|10:3|8,15|60000"
)

{
  echo "== run of parts=$parts"
  echo "date: $(date -u +%Y-%m-%dT%H:%MZ)"
  echo "commit: $(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)$(git -C "$root" diff --quiet -- . ":!bench/results" 2>/dev/null || echo ' (with uncommitted changes)')"
  echo "cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(nproc) cores"
  echo "memory: $(free -g | awk '/Mem:/{print $2}') GiB"
  echo "compiler: $(c++ --version | head -1)"
  echo "build: $(grep -E '^CMAKE_BUILD_TYPE' "$build/CMakeCache.txt" 2>/dev/null | cut -d= -f2)"
  echo "load before the run: $(cut -d' ' -f1-3 /proc/loadavg)"
} >> "$out/machine.txt"

for row in "${scenes[@]}"; do
  IFS='|' read -r label scene window instants max_ref <<< "$row"
  if [ ${#only[@]} -gt 0 ] && [[ ! " ${only[*]} " =~ " $label " ]]; then continue; fi
  file="$root/scenes/paper/$scene"
  name=$(basename "$scene" .yaml)
  cache=$(ls "$bakes/$name"/*.h5 2>/dev/null | head -1 || true)
  if [ $reuse -eq 0 ] || [ -z "$cache" ] || ! "$magbake" info "$cache" 2>/dev/null | grep -q "$(sha256sum "$file" | cut -c1-12)"; then
    rm -rf "${bakes:?}/$name"
    echo "== $label: baking $scene" >&2
    start=$(date +%s)
    "$magbake" --quiet bake "$file" -o "$bakes/$name" > "$bakes/$name.log" 2>&1
    echo "$label: baked $scene in $(( $(date +%s) - start )) s on $(nproc) threads" >> "$out/bakes.txt"
    cache=$(ls "$bakes/$name"/*.h5 | head -1)
  fi
  echo "== $label: measuring" >&2
  "$driver" "$file" "$cache" "$out" --label "$label" --window "$window" --instants "$instants" --threads 1,0 \
    --max-ref-cells "$max_ref" --parts "$parts"
done
echo "load after the run: $(cut -d' ' -f1-3 /proc/loadavg)" >> "$out/machine.txt"
/usr/bin/python3 "$here/paper_table.py" "$results"
