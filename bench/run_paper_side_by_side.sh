#!/usr/bin/env bash
# Two builds of paper_table timed side by side, in one run, on the same cached states: for each
# scene of scenes/paper, the window of run_paper_table.sh (DragonLow/High: its first frame only)
# is advanced from the same cached frame by the "before" binary, then by the "after" one, on
# 1 thread. Use it to show what a change does to T_mag, substeps and induction iterations
# without the machine's drift between separate runs.
#
# Usage: bench/run_paper_side_by_side.sh BEFORE_BUILD AFTER_BUILD BAKES_DIR OUT.md
#   BAKES_DIR holds <scene>/<scene>.h5 (run_paper_table.sh leaves them in BUILD/paper_bakes).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(dirname "$here")
before=$1 after=$2 bakes=$3 out=$4
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
rows=("TST|tst|72:6" "BowlSpheres|bowl_spheres|18:6" "Bowl2008|bowl_2008|24:6" "SuperCube|supercube|5:6"
      "DragonLow|dragon_low|10:1" "DragonHigh|dragon_high|10:1")
{
  echo "# Paper scenes, two builds side by side"
  echo
  echo "date: $(date -u +%Y-%m-%dT%H:%MZ); cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(nproc) cores;"
  echo "before: $before ($(git -C "$root" rev-parse --short HEAD 2>/dev/null) is the checkout running this script); after: $after;"
  echo "load before the run: $(cut -d' ' -f1-3 /proc/loadavg). 1 thread; per 1 ms of simulated time; same cached start state."
  echo
  echo "| scene | window (frame:frames) | T_mag ms before / after | T_mag per evaluation ms before / after | substeps per ms before / after | induction iterations per eval before / after | T_rbd ms before / after |"
  echo "| --- | --- | --- | --- | --- | --- | --- |"
} > "$out"
for row in "${rows[@]}"; do
  IFS='|' read -r label name window <<< "$row"
  for which in before after; do
    build=$before
    [ "$which" = after ] && build=$after
    mkdir -p "$tmp/$which"
    "$build/bench/paper_table" "$root/scenes/paper/$name.yaml" "$bakes/$name/$name.h5" "$tmp/$which" --label "$label" \
      --window "$window" --instants "${window%%:*}" --threads 1 --parts timing > "$tmp/$which.log" 2>&1
  done
  python3 - "$tmp" "$label" "$window" >> "$out" <<'PY'
import json, sys
tmp, label, window = sys.argv[1:]
t = [json.load(open(f"{tmp}/{w}/{label}.json"))["timing"][0] for w in ("before", "after")]
def pair(k, f="{:.3g}"):
    return f"{f.format(t[0][k])} / {f.format(t[1][k])}"
print(f"| {label} | {window} | {pair('t_mag_ms_per_ms')} | {pair('t_mag_ms_per_eval')} | {pair('substeps_per_ms')} | "
      f"{pair('induction_iterations_per_eval')} | {pair('t_rbd_ms_per_ms')} |")
PY
done
echo "" >> "$out"
echo "load after the run: $(cut -d' ' -f1-3 /proc/loadavg)" >> "$out"
cat "$out"
