#!/usr/bin/env python3
"""Run time against error for soft (induced) bodies (issue 14 outcome 3).

Every case of tests/data/soft_reference.json (a soft cube's moment in a uniform field, chi 10 /
700 / 2e4; a soft sphere's force 0.05-20 mm above a cube magnet, chi 700 / 2e4) is evaluated
with `magbake eval --json` at each preset, each `magnetics.grading` and each
`magnetics.soft_cells_across` asked for ("preset" = the preset's own), REPEAT times
(median wall time of the whole command, one evaluation, which includes building the model), and
compared with the reference. Prints a markdown table and writes CSV.

    python3 bench/run_soft_bench.py [--magbake build/bake/magbake] [--gradings preset,1] [--soft-cells preset,4]
        [--presets draft,default,high] [--repeat 3] [--threads 1] [--csv out.csv] [--cases cube,sphere_chi700]
"""
import argparse
import json
import os
import statistics
import subprocess
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

ap = argparse.ArgumentParser()
ap.add_argument("--magbake", default=os.path.join(ROOT, "build", "bake", "magbake"))
ap.add_argument("--gradings", default="preset")
ap.add_argument("--soft-cells", default="preset,4")
ap.add_argument("--presets", default="draft,default,high")
ap.add_argument("--repeat", type=int, default=3)
ap.add_argument("--threads", type=int, default=1)
ap.add_argument("--csv", default="")
ap.add_argument("--cases", default="", help="comma-separated name prefixes (default: all)")
args = ap.parse_args()

with open(os.path.join(ROOT, "tests", "data", "soft_reference.json")) as f:
    ref = json.load(f)
cases = [c for c in ref["cases"] if not args.cases or any(c["name"].startswith(p) for p in args.cases.split(","))]

with open("/proc/loadavg") as f:
    load_before = " ".join(f.read().split()[:3])
cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
print("machine: %d cores, %s; load before: %s; %d thread(s), median of %d" % (os.cpu_count(), cpu, load_before,
                                                                           args.threads, args.repeat))
print()
print("| case | reference | preset | grading | soft cells across | cells | iterations | error | time s |")
print("| --- | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: |")
rows = []
with tempfile.TemporaryDirectory() as work:
    for c in cases:
        for preset in args.presets.split(","):
            for g, k in [(g, k) for g in args.gradings.split(",") for k in args.soft_cells.split(",")]:
                keys = ("" if g == "preset" else ", grading: %s" % g) + ("" if k == "preset" else ", soft_cells_across: %s" % k)
                text = c["scene"].replace("QUALITY", preset).replace("CELL", keys)
                path = os.path.join(work, "case.yaml")
                with open(path, "w") as f:
                    f.write(text)
                times = []
                for _ in range(args.repeat):
                    t0 = time.perf_counter()
                    out = subprocess.run([args.magbake, "-q", "--threads", str(args.threads), "eval", path, "--json"],
                                         check=True, capture_output=True, text=True).stdout
                    times.append(time.perf_counter() - t0)
                j = json.loads(out[: out.rfind("}") + 1])
                b = j["bodies"][c["body"]]
                value = b["moment"][2] if c["quantity"] == "moment_z" else b["force"][2]
                err = value / c["reference"] - 1.0
                it = j["induction"]["iterations"]
                conv = j["induction"].get("converged", True)
                row = dict(case=c["name"], reference=c["reference"], preset=preset, grading=g, soft=k, cells=j["cells"],
                           iterations=it, converged=conv, value=value, error=err, time=statistics.median(times))
                rows.append(row)
                print("| %s | %.6g | %s | %s | %s | %d | %d%s | %+.2f%% | %.3f |" %
                      (c["name"], c["reference"], preset, g, k, j["cells"], it, "" if conv else " (not converged)",
                       100 * err, row["time"]), flush=True)
with open("/proc/loadavg") as f:
    print("\nload after: " + " ".join(f.read().split()[:3]))
if args.csv:
    with open(args.csv, "w") as f:
        f.write("case,reference,preset,grading,soft_cells_across,cells,iterations,converged,value,error,time_s\n")
        for r in rows:
            f.write("%s,%.10g,%s,%s,%s,%d,%d,%d,%.10g,%.6g,%.4f\n" % (r["case"], r["reference"], r["preset"], r["grading"], r["soft"],
                                                                 r["cells"], r["iterations"], r["converged"], r["value"],
                                                                 r["error"], r["time"]))
