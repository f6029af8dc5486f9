#!/usr/bin/env bash
# What restarting every frame from its state costs (physics.md §8 item 12): two magbake
# binaries bake the same shots side by side, interleaved (before, after, before, after), on 1
# thread: the paper's scenes over their first frames, 1000 spheres, and the Zen heap and
# lattice (216 ball magnets, stuck contacts and sleep). Reported per shot: median wall time of
# the bake, Bullet steps (substeps), and the largest rise of the total energy from one frame to
# the next (J; kinetic + gravity + magnetic, from the cache).
#
# Usage: bench/run_restart_cost.sh BEFORE_MAGBAKE AFTER_MAGBAKE OUT_DIR [REPEAT]
#   ONLY="TST,Zen heap" runs those shots alone (labels as in the table).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(dirname "$here")
source "$here/bench_lib.sh"
before=$1 after=$2 out=$3 repeat=${4:-2}
mkdir -p "$out/scenes"
python3 "$here/make_many_bodies.py" "$out/scenes/many_bodies.yaml" 10 > /dev/null
python3 "$here/make_zen_magnets.py" "$out/scenes" 40 > /dev/null
# label|scene|frames
shots=("TST|$root/scenes/paper/tst.yaml|1-30" "BowlSpheres|$root/scenes/paper/bowl_spheres.yaml|1-8"
       "Bowl2008|$root/scenes/paper/bowl_2008.yaml|1-4" "SuperCube|$root/scenes/paper/supercube.yaml|1-15"
       "DragonLow|$root/scenes/paper/dragon_low.yaml|1-3" "1000 spheres|$out/scenes/many_bodies.yaml|1-2"
       "Zen heap|$out/scenes/zen_heap.yaml|1-40" "Zen lattice|$out/scenes/zen_lattice.yaml|1-40")
report="$out/restart_cost.md"
{
  echo "# Restarting every frame: cost, side by side"
  echo
  echo "date: $(date -u +%Y-%m-%dT%H:%MZ); $(machine_line)"
  echo "before: $before; after: $after; 1 thread, $repeat runs each, interleaved; wall time of the whole bake (median)."
  echo
  echo "| shot | frames | wall s before / after | Bullet steps before / after | largest energy rise per frame J before / after |"
  echo "| --- | --- | --- | --- | --- |"
} > "$report"
for shot in "${shots[@]}"; do
  IFS='|' read -r label scene frames <<< "$shot"
  if [ -n "${ONLY:-}" ] && [[ ",$ONLY," != *",$label,"* ]]; then continue; fi
  declare -A wall=()
  for r in $(seq "$repeat"); do
    for which in before after; do
      exe=$before
      [ "$which" = after ] && exe=$after
      dir="$out/$which/$(echo "$label" | tr ' ' '_')"
      rm -rf "$dir"
      mkdir -p "$(dirname "$dir")"
      t0=$(date +%s.%N)
      "$exe" -q --threads 1 bake "$scene" --cache-only --frames "$frames" -o "$dir" > "$dir.log" 2>&1 || true
      t1=$(date +%s.%N)
      wall[$which]="${wall[$which]:-} $(echo "$t1 - $t0" | bc)"
    done
  done
  stats() {
    /usr/bin/python3 - "$1" <<'PY'
import glob, sys
import h5py, numpy as np
files = glob.glob(sys.argv[1] + "/*.h5")
if not files:
    print("- -"); sys.exit()
f = h5py.File(files[0], "r", swmr=True)
o = f["observables"]
e = o["kinetic_energy/value"][:] + o["gravity_energy/value"][:] + o["magnetic_energy/value"][:]
rise = np.diff(e).max() if len(e) > 1 else 0.0
print(int(o["substeps/value"][:].sum()), "%.3g" % rise)
PY
  }
  read -r sb eb <<< "$(stats "$out/before/$(echo "$label" | tr ' ' '_')")"
  read -r sa ea <<< "$(stats "$out/after/$(echo "$label" | tr ' ' '_')")"
  wb=$(echo "${wall[before]}" | median)
  wa=$(echo "${wall[after]}" | median)
  printf '| %s | %s | %.2f / %.2f | %s / %s | %s / %s |\n' "$label" "$frames" "$wb" "$wa" "$sb" "$sa" "$eb" "$ea" >> "$report"
  unset wall
done
echo >> "$report"
echo "load after the run: $(cut -d' ' -f1-3 /proc/loadavg)" >> "$report"
cat "$report"
