#!/usr/bin/env bash
# Field export benchmark (bench/field_bench: the horseshoe magnet and 24 steel balls, 7356 cells):
# run time against error of the tree code at several opening angles, against direct summation
# (theta 0), at 128³ and 256³ voxels, each case in its own process (peak memory per case); then
# the sparsity threshold's cost (threshold 0, the default 1e-5 T, 1e-3 T at the default theta).
# Errors: RMS relative to |B| over the active voxels, and the 99th / 99.9th percentile and the
# maximum of the relative error where |B| > 1 mT (issue 14: the 99.9th percentile under 1%).
# Usage: bench/run_field_bench.sh [build dir] [results dir]     THETAS="0.25 0.2 0.15 0.1"
set -euo pipefail
build=${1:-build}
out=${2:-bench/results}
thetas=${THETAS:-0.25 0.2 0.15 0.1}
mkdir -p "$out"
csv="$out/field_bench.csv"
echo "resolution,mode,theta,threshold,nx,ny,nz,voxels_evaluated,seconds,voxels_per_second,peak_rss_mib" > "$csv"
for res in 128 256; do
  "$build/bench/field_bench" "$res" direct 0 >> "$csv"
  for theta in $thetas; do "$build/bench/field_bench" "$res" tree "$theta" >> "$csv"; done
  for threshold in 0 1e-3; do "$build/bench/field_bench" "$res" tree 0.15 "$threshold" >> "$csv"; done
done
/usr/bin/python3 - "$csv" "$out/field_bench_error.csv" <<'PY'
import csv, sys
import numpy as np
rows = list(csv.DictReader(open(sys.argv[1])))
def load(res, mode, theta):
    return np.fromfile(f"/tmp/magbake_field_bench_{res}_{mode}_{theta}.f32", dtype=np.float32).reshape(-1, 3)
with open(sys.argv[2], "w") as out:
    out.write("resolution,theta,seconds,speedup,rms_relative_error,p99_relative_error_strong,p999_relative_error_strong,max_relative_error_strong\n")
    for res in (128, 256):
        d = load(res, "direct", 0)
        td = [float(r["seconds"]) for r in rows if r["resolution"] == str(res) and r["mode"] == "direct"][0]
        for r in rows:
            if r["resolution"] != str(res) or r["mode"] != "tree" or r["threshold"] != "1e-05":
                continue
            t = load(res, "tree", r["theta"])
            m = ~np.isnan(d[:, 0]) & (np.linalg.norm(d, axis=1) >= 1e-5)   # the active region
            err = np.linalg.norm(t[m] - d[m], axis=1)
            mag = np.linalg.norm(d[m], axis=1)
            rms = np.sqrt((err ** 2).sum() / (mag ** 2).sum())
            strong = mag > 1e-3
            rel = err[strong] / mag[strong]
            p99, p999, worst = np.percentile(rel, 99), np.percentile(rel, 99.9), rel.max()
            tt = float(r["seconds"])
            out.write(f"{res},{r['theta']},{tt:.3f},{td / tt:.1f},{rms:.3e},{p99:.3e},{p999:.3e},{worst:.3e}\n")
            print(f"{res}^3 theta {r['theta']}: {tt:.2f} s ({td / tt:.1f}x direct), RMS {rms:.2e}, "
                  f"where |B| > 1 mT: p99 {p99:.2e}, p99.9 {p999:.2e}, max {worst:.2e}")
    for r in rows:
        if r["mode"] == "tree" and r["theta"] == "0.15":
            print(f"{r['resolution']}^3 theta 0.15 threshold {r['threshold']} T: {r['seconds']} s, {r['voxels_evaluated']} voxels evaluated")
PY
