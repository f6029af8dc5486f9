#!/usr/bin/env bash
# Two magbake binaries side by side on the paper's scenes' first frames (1 thread, interleaved,
# REPEAT times; cache only): the median bake time of each and their ratio. Each binary bakes the
# scene file of its own commit (OLD_REV for the old one), so a key that only the new one knows
# does not stop the old one.
#   bench/run_change_side_by_side.sh OLD_EXE OLD_REV NEW_EXE [REPEAT]
set -euo pipefail
cd "$(dirname "$0")/.."
source bench/bench_lib.sh
old=$1 rev=$2 new=$3 repeat=${4:-3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
machine_line
echo "old: $old ($rev); new: $new ($(git rev-parse --short HEAD) + working tree)"
echo
echo "| scene | frames | old: bake s (median of $repeat) | new: bake s | new / old | magbake diff |"
echo "| --- | --- | --- | --- | --- | --- |"
for row in "tst|1-30" "bowl_spheres|1-15" "bowl_2008|1-15" "supercube|1-15" "dragon_low|1-2"; do
  IFS='|' read -r name frames <<< "$row"
  git show "$rev:scenes/paper/$name.yaml" > "$work/old_$name.yaml"
  cp "scenes/paper/$name.yaml" "$work/new_$name.yaml"
  for v in old new; do
    sed -i -e "s|\.\./meshes/|$PWD/scenes/meshes/|" -e '/^outputs:/,$d' "$work/${v}_$name.yaml"
  done
  declare -A t=()
  for r in $(seq "$repeat"); do
    for v in old new; do
      exe=$old; [ $v = new ] && exe=$new
      t[$v]+="$(timed_bake "$exe" "$work/${v}_$name.yaml" "$frames" "$work/out_$v") "
    done
  done
  # magbake diff exits 1 when the caches differ; its first line after the notes says how.
  d=$({ "$new" diff "$work"/out_old/*.h5 "$work"/out_new/*.h5 2>&1 || true; } | grep -v '^note' | sed -n '1p;2p' | tr -s ' ' | tr '\n' ';' | cut -c1-90)
  a=$(echo "${t[old]}" | median) b=$(echo "${t[new]}" | median)
  echo "| $name | $frames | $a | $b | $(echo "scale=2; $b / $a" | bc) | $d |"
done
echo
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
