#!/usr/bin/env bash
# Field export benchmark: tree code vs direct summation at 128³ and 256³ (each case in its own
# process for peak memory), then the RMS error of the tree against direct summation.
# Usage: bench/run_field_bench.sh [build dir] [results dir]
set -euo pipefail
build=${1:-build}
out=${2:-bench/results}
mkdir -p "$out"
csv="$out/field_bench.csv"
echo "resolution,mode,theta,nx,ny,nz,voxels_evaluated,seconds,voxels_per_second,peak_rss_mib" > "$csv"
for res in 128 256; do
  for mode in tree direct; do
    "$build/bench/field_bench" "$res" "$mode" >> "$csv"
  done
done
/usr/bin/python3 - "$csv" "$out/field_bench_error.csv" <<'PY'
import csv, sys
import numpy as np
rows = list(csv.DictReader(open(sys.argv[1])))
with open(sys.argv[2], "w") as out:
    out.write("resolution,rms_relative_error,p99_relative_error_strong,speedup\n")
    for res in (128, 256):
        t = np.fromfile(f"/tmp/magbake_field_bench_{res}_tree.f32", dtype=np.float32).reshape(-1, 3)
        d = np.fromfile(f"/tmp/magbake_field_bench_{res}_direct.f32", dtype=np.float32).reshape(-1, 3)
        m = ~np.isnan(d[:, 0]) & (np.linalg.norm(d, axis=1) >= 1e-5)   # the active region
        err = np.linalg.norm(t[m] - d[m], axis=1)
        mag = np.linalg.norm(d[m], axis=1)
        rms = np.sqrt((err ** 2).sum() / (mag ** 2).sum())
        strong = mag > 1e-3
        worst = np.percentile(err[strong] / mag[strong], 99)
        tt = [float(r["seconds"]) for r in rows if r["resolution"] == str(res) and r["mode"] == "tree"][0]
        td = [float(r["seconds"]) for r in rows if r["resolution"] == str(res) and r["mode"] == "direct"][0]
        out.write(f"{res},{rms:.3e},{worst:.3e},{td / tt:.1f}\n")
        print(f"{res}^3: RMS relative error {rms:.2e}, 99th percentile where |B| > 1 mT {worst:.2e}, speed-up {td / tt:.1f}x")
PY
