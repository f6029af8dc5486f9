#!/usr/bin/env bash
# Where the time goes on the paper's scenes: perf profiles of the Table 1 timing window
# (build/bench/paper_table --parts timing, 1 thread) of every scene of scenes/paper, as the
# share of samples per function (self time) and per top-level stage, into OUT/paper_profile.md.
#
# Usage: bench/run_paper_profile.sh [build dir] [out dir]
#   Reuses the shots that bench/run_paper_table.sh baked into BUILD/paper_bakes when they were
#   baked from the same scene file, else bakes them. Needs linux-perf (`perf`), run as root or
#   with kernel.perf_event_paranoid <= 1.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(dirname "$here")
build=${1:-build}
out=${2:-bench/results}
magbake="$build/bake/magbake"
driver="$build/bench/paper_table"
bakes="$build/paper_bakes"
work="$build/paper_profile"
mkdir -p "$bakes" "$work" "$out"
command -v perf > /dev/null || { echo "run_paper_profile.sh: perf not found (apt-get install linux-perf)" >&2; exit 1; }
# label | scene | window (first frame:frames), as in run_paper_table.sh
scenes=(
  "TST|tst.yaml|72:6"
  "BowlSpheres|bowl_spheres.yaml|18:6"
  "Bowl2008|bowl_2008.yaml|24:6"
  "SuperCube|supercube.yaml|5:6"
  "DragonLow|dragon_low.yaml|10:3"
  "DragonHigh|dragon_high.yaml|10:3"
)
md="$out/paper_profile.md"
{
  echo "# Where the time goes on the paper's scenes"
  echo
  echo "\`bench/run_paper_profile.sh\`: perf (sampling at 999 Hz, call graphs off) over"
  echo "\`paper_table --parts timing --threads 1\` on each scene's Table 1 window (the same frames"
  echo "as \`paper_table.md\`, replayed from the cached states). Self time per function, the"
  echo "functions above 2% of the samples; the rest of each run is setup (model build, cache read)."
  echo
  echo "- date: $(date -u +%Y-%m-%dT%H:%MZ); commit $(git -C "$root" rev-parse --short HEAD)$(git -C "$root" diff --quiet -- . ':!bench/results' || echo ' (with uncommitted changes)')"
  echo "- cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(nproc) cores; load before: $(cut -d' ' -f1-3 /proc/loadavg)"
  echo "- build: $(grep -E '^CMAKE_BUILD_TYPE' "$build/CMakeCache.txt" 2>/dev/null | cut -d= -f2)"
} > "$md"
for row in "${scenes[@]}"; do
  IFS='|' read -r label scene window <<< "$row"
  file="$root/scenes/paper/$scene"
  name=$(basename "$scene" .yaml)
  cache=$(ls "$bakes/$name"/*.h5 2>/dev/null | head -1 || true)
  if [ -z "$cache" ] || ! "$magbake" info "$cache" 2>/dev/null | grep -q "$(sha256sum "$file" | cut -c1-12)"; then
    rm -rf "${bakes:?}/$name"
    echo "== $label: baking $scene" >&2
    "$magbake" --quiet bake "$file" -o "$bakes/$name" > "$bakes/$name.log" 2>&1
    cache=$(ls "$bakes/$name"/*.h5 | head -1)
  fi
  echo "== $label: profiling" >&2
  perf record -q -F 999 -o "$work/$label.data" -- "$driver" "$file" "$cache" "$work/$label" --label "$label" \
    --window "$window" --instants 0 --threads 1 --parts timing > "$work/$label.log" 2>&1
  {
    echo
    echo "## $label ($scene, window $window)"
    echo
    echo "| self % | function |"
    echo "| ---: | --- |"
    perf report -i "$work/$label.data" --no-children --sort symbol --stdio 2> /dev/null |
      grep -E '^ +[0-9.]+%' | awk '{p=$1; sub(/%/,"",p); if (done || p+0 < 2.0) { done=1; next } $1=""; $2=""; s=$0; sub(/^ +/,"",s);
        gsub(/\|/,"\\|",s); if (length(s) > 110) s=substr(s,1,107) "..."; printf "| %s | `%s` |\n", p, s}'
  } >> "$md"
done
echo "wrote $md" >&2
