#!/usr/bin/env bash
# Per-island substeps benchmark (issue 11, outcome 2): a snapping ball-magnet pair beside 100 resting
# cube magnets and 100 wooden blocks (make_islands_scene.py), baked by two magbake binaries
# alternately in one run, REPEATS times each, 1 thread; medians of wall time, magnetics and
# Bullet time per frame, Bullet steps and body steps.
# Usage: bench/run_islands_bench.sh AFTER_MAGBAKE BEFORE_MAGBAKE OUT_DIR [FRAMES] [REPEATS]
set -euo pipefail
after=$1 before=$2 out=$3 frames=${4:-10} repeats=${5:-3}
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$out/islands"
python3 "$here/make_islands_scene.py" "$out/islands/islands.yaml" "$frames"
{ echo "islands bench $(date -u +%FT%TZ) on $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"; uptime; } >> "$out/machine.txt"
args=()
for r in $(seq 1 "$repeats"); do
  for run in after before; do
    exe=$after; [ "$run" = before ] && exe=$before
    dir="$out/islands/$run-$r"
    rm -rf "$dir"
    echo "== $run $r ($exe), load $(cut -d' ' -f1-3 /proc/loadavg)"
    start=$(date +%s.%N)
    "$exe" --threads 1 -q bake "$out/islands/islands.yaml" -o "$dir" > "$dir.log" 2>&1
    end=$(date +%s.%N)
    args+=("$run=$dir/islands.h5=$(echo "$end - $start" | bc)")
  done
done
/usr/bin/python3 - "$out/islands.md" "$frames" "${args[@]}" <<'PY'
import statistics as st, sys
import h5py
md, frames = sys.argv[1], int(sys.argv[2])
runs = {}
for a in sys.argv[3:]:
    name, path, wall = a.split("=")
    o = h5py.File(path, "r")["observables"]
    v = lambda n: float(o[n]["value"][1:].sum())
    bs = v("body_steps") if "body_steps" in o else float("nan")
    runs.setdefault(name, []).append((float(wall) / frames, v("magnetics_seconds") / frames, v("rigid_seconds") / frames,
                                      v("substeps") / frames, bs / frames, float(o["energy_drift"]["value"][1:].max())))
rows = ["| run | bakes | wall s per frame (median, whole process) | magnetics s per frame | Bullet s per frame | Bullet steps per frame (nominal 10) | body steps per frame (202 dynamic bodies) | largest energy rise per frame J |",
        "| --- | --- | --- | --- | --- | --- | --- | --- |"]
for name in ("before", "after"):
    r = runs.get(name, [])
    if not r: continue
    med = lambda k: st.median(x[k] for x in r)
    bsteps = "n/a (not recorded)" if med(4) != med(4) else f"{med(4):.0f}"
    rows.append(f"| {name} | {len(r)} | {med(0):.3f} | {med(1):.3f} | {med(2):.3f} | {med(3):.0f} | {bsteps} | {max(x[5] for x in r):.2e} |")
open(md, "w").write("\n".join(rows) + "\n")
print("\n".join(rows))
PY
