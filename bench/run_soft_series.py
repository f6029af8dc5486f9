#!/usr/bin/env python3
"""Soft balls against exact series: magbake eval's force at draft, default, default with 4 cells
across soft parts (the paper scenes' resolution) and high, with each evaluation's wall time (one
process per case, including loading the scene and building the cells). References:
tests/data/soft_sphere_series.json (a soft ball next to a ball magnet,
scripts/make_soft_sphere_series.py; the default) or tests/data/two_ball_series.json (two soft
balls in a uniform field, scripts/make_two_ball_series.py).

Usage: bench/run_soft_series.py [build dir] [results dir] [reference json]
"""
import json
import os
import subprocess
import sys
import tempfile
import time

here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
build = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "build")
out = sys.argv[2] if len(sys.argv) > 2 else os.path.join(here, "bench/results/soft_series")
exe = os.path.join(build, "bake/magbake")
ref_path = sys.argv[3] if len(sys.argv) > 3 else os.path.join(here, "tests/data/soft_sphere_series.json")
ref = json.load(open(ref_path))
stem = os.path.splitext(os.path.basename(ref_path))[0]
presets = [("draft", ""), ("default", ""), ("default+soft4", ", soft_cells_across: 4"), ("high", "")]
os.makedirs(out, exist_ok=True)
cpu = next(l.split(":")[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name"))
lines = [f"# {stem}: magbake against the exact series", "", f"reference: {ref['method']}", "",
         f"machine: {os.cpu_count()} cores, {cpu}; load before: {open('/proc/loadavg').read().split()[:3]}", "",
         "Relative error of the force on the case's body and wall time of `magbake eval` per case.", "",
         "| case | exact force | " + " | ".join(p for p, _ in presets) + " |",
         "| --- | ---: | " + " | ".join("---" for _ in presets) + " |"]
with tempfile.TemporaryDirectory() as tmp:
    scene = os.path.join(tmp, "s.yaml")
    for c in ref["cases"]:
        row = [c["name"], f"{c['reference']:.5g} N"]
        for name, cell in presets:
            with open(scene, "w") as f:
                f.write(c["scene"].replace("QUALITY", name.split("+")[0]).replace("CELL", cell))
            t0 = time.time()
            r = subprocess.run([exe, "eval", scene, "--json"], capture_output=True, text=True, check=True)
            dt = time.time() - t0
            axis = "xyz".index(c["quantity"][-1])
            force = json.loads(r.stdout[: r.stdout.rfind("}") + 1])["bodies"][c["body"]]["force"][axis]
            row.append(f"{100 * (force / c['reference'] - 1):+.2f}% ({dt:.2f} s)")
        lines.append("| " + " | ".join(row) + " |")
        print(lines[-1], flush=True)
lines += ["", f"load after: {open('/proc/loadavg').read().split()[:3]}"]
open(os.path.join(out, "soft_series.md" if stem == "soft_sphere_series" else stem + ".md"), "w").write("\n".join(lines) + "\n")
