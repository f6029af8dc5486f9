#!/usr/bin/env bash
# Preview rendering benchmark: 256 bodies of every shape and material (bench/make_many_bodies.py),
# baked once, then rendered by `magbake preview` at 960x540 with and without field lines, three
# runs each. Per-frame times come from magbake's own per-frame timing (-v), so cache reading and
# context creation are reported apart from the frame time.
# Usage: bench/run_preview_bench.sh [build dir] [results dir] [cache to reuse or create]
set -euo pipefail
build=$(realpath "${1:-build}")
out=$(realpath -m "${2:-bench/results}")
here=$(dirname "$(realpath "$0")")
work=$(mktemp -d /tmp/magbake_preview_bench.XXXXXX)
trap 'rm -rf "$work"' EXIT
mkdir -p "$out"
cache=${3:-$work/many_bodies.h5}
if [ ! -f "$cache" ]; then
  python3 "$here/make_many_bodies.py" "$work/many_bodies.yaml" 8
  echo "baking the 256-body scene (8 frames, a few minutes: magnets snapping together force small substeps)..." >&2
  (cd "$work" && "$build/bake/magbake" -q bake many_bodies.yaml >/dev/null 2>&1)
  mkdir -p "$(dirname "$cache")"
  [ "$cache" = "$work/many_bodies.h5" ] || cp "$work/many_bodies.h5" "$cache"
fi
log="$out/preview_bench.log"
: > "$log"
for lines in off on; do
  for run in 1 2 3; do
    flag=$([ "$lines" = on ] && echo --field-lines || echo --no-field-lines)
    start=$(date +%s.%N)
    "$build/bake/magbake" -v --threads 2 preview "$cache" --size 960x540 $flag \
      -o "$work/frames_$lines/f.####.png" 2>&1 | sed -n "s/.*preview frame \([0-9]*\) ms: /lines=$lines run=$run frame=\1 /p" >> "$log"
    end=$(date +%s.%N)
    echo "lines=$lines run=$run wall=$(echo "$end - $start" | bc)" >> "$log"
  done
done
cp "$work/frames_on/f.0008.png" "$out/preview_bench_frame.png"
python3 - "$log" "$out/preview_bench.csv" <<'PY'
import re, statistics, sys
rows = [l for l in open(sys.argv[1]) if "frame=" in l]
wall = [l for l in open(sys.argv[1]) if "wall=" in l]
with open(sys.argv[2], "w") as f:
    f.write("field_lines,frames,median_total_ms,median_draw_ms,median_lines_ms,median_png_ms,max_total_ms,median_wall_s_per_run\n")
    for mode in ("off", "on"):
        sel = [dict(re.findall(r"(\w+) ([0-9.]+)", l.split(" ", 3)[3])) for l in rows if f"lines={mode} " in l]
        med = lambda k: statistics.median(float(r[k]) for r in sel)
        w = statistics.median(float(l.split("wall=")[1]) for l in wall if f"lines={mode} " in l)
        mx = max(float(r["total"]) for r in sel)
        f.write(f"{mode},{len(sel)},{med('total'):.1f},{med('draw'):.1f},{med('lines'):.1f},{med('png'):.1f},{mx:.1f},{w:.2f}\n")
        print(f"field lines {mode}: median {med('total'):.1f} ms/frame (draw {med('draw'):.1f}, lines {med('lines'):.1f}, "
              f"png {med('png'):.1f}), worst {mx:.1f} ms, {len(sel)} frames; wall per 8-frame run {w:.2f} s")
PY
