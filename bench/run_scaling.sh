#!/usr/bin/env bash
# Cost against body count (issue 13): bakes the scaling scene (bench/make_scaling_scene.py: N
# spheres of 2 mm, magnets and steel alternating, 8 mm apart in a walled box) for the first
# FRAMES ms at each N, and reads from each cache the magnetics and rigid-body seconds per substep
# (the simulator's own timers, per frame: seconds / substeps), substeps and induction iterations;
# peak memory from /usr/bin/time. Then 1 against 2 threads at N = 1000. Writes OUT/scaling.csv,
# OUT/scaling.md and OUT/scaling.png (log axes, with N^1 and N^1.2 guides).
#
# Usage: bench/run_scaling.sh [BUILD] [OUT] [N ...]     (default: build bench/results/scaling 100 300 1000 3000 10000)
#   FRAMES=1 (default) ms simulated per N, at least 5 below N = 1000 (one ms of 100 bodies is 9
#   substeps and 50 ms of work, mostly warm-up: 15% run-to-run noise); THREADS=2; REPEAT=3 bakes per row for N <= 1000 (the
#   row is the one with the median magnetics time: small shots take well under a second, and
#   one run's noise moved the N^x exponent by 0.02).
#   BASELINE=path/to/other/magbake: also bakes each N up to BASELINE_MAX_N (default 1000) with
#   that binary right after this build's bake (side by side, same load), rows marked "baseline".
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build=${1:-build}
out=${2:-bench/results/scaling}
shift $(( $# > 2 ? 2 : $# ))
sizes=("$@")
[ ${#sizes[@]} -eq 0 ] && sizes=(100 300 1000 3000 10000)
frames=${FRAMES:-1}
threads=${THREADS:-2}
mkdir -p "$out"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
csv="$out/scaling.csv"
echo "build,n,threads,substeps,magnetics_ms_per_substep,rigid_ms_per_substep,induction_iterations_per_substep,peak_rss_mb,wall_s" > "$csv"
{
  echo "date: $(date -u +%Y-%m-%dT%H:%MZ); commit $(git -C "$here/.." rev-parse --short HEAD)$(git -C "$here/.." diff --quiet || echo ' (with uncommitted changes)')"
  echo "cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(nproc) cores; load before: $(cut -d' ' -f1-3 /proc/loadavg)"
} > "$out/machine.txt"

run() {  # n threads [binary label]
  local n=$1 t=$2 exe=${3:-$build/bake/magbake} label=${4:-this}
  local f=$frames
  [ "$n" -lt 1000 ] && [ "$f" -lt 5 ] && f=5
  python3 "$here/make_scaling_scene.py" "$tmp/s$n.yaml" "$n" "$f"
  rm -rf "$tmp/o"
  /usr/bin/time -f "%M %e" -o "$tmp/time" "$exe" -q --threads "$t" bake "$tmp/s$n.yaml" -o "$tmp/o" \
    > "$tmp/log" 2>&1 || { echo "bake of N=$n failed:"; tail -5 "$tmp/log"; exit 1; }
  read -r rss wall < "$tmp/time"
  /usr/bin/python3 - "$tmp/o/scaling_$n.h5" "$n" "$t" "$rss" "$wall" "$label" >> "$tmp/rows" <<'PY'
import sys, h5py
path, n, t, rss, wall, label = sys.argv[1:]
o = h5py.File(path, "r")["observables"]
sub = o["substeps"]["value"][1:].sum()
mag = o["magnetics_seconds"]["value"][1:].sum()
rbd = o["rigid_seconds"]["value"][1:].sum()
ind = o["induction_iterations"]["value"][1:].sum()
print(f"{label},{n},{t},{int(sub)},{1e3 * mag / sub:.3f},{1e3 * rbd / sub:.3f},{ind / sub:.2f},{int(rss) / 1024:.0f},{float(wall):.1f}")
PY
}

row() {  # n threads [binary label]: one row, the median of REPEAT bakes for small N
  local reps=1
  [ "$1" -le 1000 ] && reps=${REPEAT:-3}
  : > "$tmp/rows"
  for _ in $(seq "$reps"); do run "$@"; done
  sort -t, -k5 -g "$tmp/rows" | sed -n "$(( (reps + 1) / 2 ))p" >> "$csv"
  tail -1 "$csv"
}

for n in "${sizes[@]}"; do
  row "$n" "$threads"
  if [ -n "${BASELINE:-}" ] && [ "$n" -le "${BASELINE_MAX_N:-1000}" ]; then row "$n" "$threads" "$BASELINE" baseline; fi
done
row 1000 1

/usr/bin/python3 - "$csv" "$out" <<'PY'
import csv, math, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
rows = list(csv.DictReader(open(sys.argv[1])))
out = sys.argv[2]
base = [r for r in rows if r["build"] == "baseline"]
rows = [r for r in rows if r["build"] != "baseline"] + base
main = [r for r in rows if r["threads"] != "1" and r["build"] != "baseline"]
one = [r for r in rows if r["threads"] == "1" and r["build"] != "baseline"]
def slope(key):
    pts = [(math.log(float(r["n"])), math.log(float(r[key]))) for r in main if float(r[key]) > 0]
    if len(pts) < 2: return float("nan")
    (x0, y0), (x1, y1) = pts[0], pts[-1]
    return (y1 - y0) / (x1 - x0)
def fit(key):  # least-squares slope of log cost against log N over every size
    pts = [(math.log(float(r["n"])), math.log(float(r[key]))) for r in main if float(r[key]) > 0]
    if len(pts) < 2: return float("nan")
    mx, my = sum(x for x, _ in pts) / len(pts), sum(y for _, y in pts) / len(pts)
    return sum((x - mx) * (y - my) for x, y in pts) / sum((x - mx) ** 2 for x, _ in pts)
with open(f"{out}/scaling.md", "w") as f:
    f.write(open(f"{out}/machine.txt").read() + "\n")
    f.write("| build | N | threads | substeps | magnetics ms / substep | rigid ms / substep | induction iterations / substep | peak memory MB | wall s |\n")
    f.write("| --- | --- | --- | --- | --- | --- | --- | --- | --- |\n")
    for r in rows:
        f.write(f"| {r['build']} | {r['n']} | {r['threads']} | {r['substeps']} | {r['magnetics_ms_per_substep']} | {r['rigid_ms_per_substep']} | "
                f"{r['induction_iterations_per_substep']} | {r['peak_rss_mb']} | {r['wall_s']} |\n")
    f.write(f"\nExponent from the smallest to the largest N: magnetics N^{slope('magnetics_ms_per_substep'):.2f}, "
            f"rigid N^{slope('rigid_ms_per_substep'):.2f}, memory N^{slope('peak_rss_mb'):.2f}.\n")
    f.write(f"Least-squares exponent over every N: magnetics N^{fit('magnetics_ms_per_substep'):.2f}, "
            f"rigid N^{fit('rigid_ms_per_substep'):.2f}.\n")
    two = [r for r in main if r["n"] == "1000"]
    if one and two:
        a, b = float(one[0]["magnetics_ms_per_substep"]) + float(one[0]["rigid_ms_per_substep"]), \
               float(two[0]["magnetics_ms_per_substep"]) + float(two[0]["rigid_ms_per_substep"])
        f.write(f"N = 1000, magnetics + rigid per substep: 1 thread {a:.1f} ms, {two[0]['threads']} threads {b:.1f} ms "
                f"({a / b:.2f}x).\n")
fig, ax = plt.subplots(figsize=(6, 4.5))
n = [float(r["n"]) for r in main]
for key, label in (("magnetics_ms_per_substep", "magnetics"), ("rigid_ms_per_substep", "rigid (Bullet)"), ("peak_rss_mb", "peak memory (MB)")):
    ax.loglog(n, [float(r[key]) for r in main], "o-", label=label)
    if base and key != "peak_rss_mb":
        ax.loglog([float(r["n"]) for r in base], [float(r[key]) for r in base], "x--", label=label + ", baseline")
ref = float(main[0]["magnetics_ms_per_substep"])
ax.loglog(n, [ref * (x / n[0]) for x in n], "k:", lw=0.8, label="N^1")
ax.loglog(n, [ref * (x / n[0]) ** 1.2 for x in n], "k--", lw=0.8, label="N^1.2")
ax.set_xlabel("bodies N"); ax.set_ylabel("ms per substep / MB"); ax.grid(True, which="both", alpha=0.3); ax.legend()
ax.set_title("magbake cost against body count (bench/run_scaling.sh)")
fig.tight_layout(); fig.savefig(f"{out}/scaling.png", dpi=120)
print(open(f"{out}/scaling.md").read())
PY
