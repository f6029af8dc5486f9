#!/usr/bin/env python3
"""Summarizes Zen-magnet stress bakes: per-frame substeps and wall time (magnetics + rigid
bodies, from the cache's observables), medians over the baked frames.

Usage: zen_summary.py OUT.csv OUT.md LABEL=CACHE.h5 [LABEL=CACHE.h5 ...]
"""
import statistics
import sys

import h5py

rows = []
for arg in sys.argv[3:]:
    label, path = arg.split("=", 1)
    with h5py.File(path, "r") as f:
        o = f["observables"]
        sub = o["substeps/value"][1:]
        mag = o["magnetics_seconds/value"][1:]
        rig = o["rigid_seconds/value"][1:]
        # Caches of builds before issue 11 lack these two observables: penetration unknown, drift
        # from the energies.
        pen = o["max_penetration/value"][1:] if "max_penetration" in o else [float("nan")]
        if "energy_drift" in o:
            drift = o["energy_drift/value"][1:]
        else:
            e = o["kinetic_energy/value"][()] + o["magnetic_energy/value"][()] + o["gravity_energy/value"][()]
            drift = e[1:] - e[:-1]
        sleeping = o["sleeping/value"][1:] if "sleeping" in o else [0]
    wall = [m + r for m, r in zip(mag, rig)]
    rows.append({
        "run": label,
        "frames": len(sub),
        "substeps_per_frame": statistics.median(sub),
        "wall_s_per_frame": statistics.median(wall),
        "mean_wall_s_per_frame": sum(wall) / len(wall),
        "total_wall_s": sum(wall),
        "asleep_at_end": int(sleeping[-1]),
        "magnetics_s_per_frame": statistics.median(mag),
        "rigid_s_per_frame": statistics.median(rig),
        "max_penetration_mm": 1e3 * max(pen),
        "largest_energy_rise_J": max(drift),
    })
keys = list(rows[0].keys())
with open(sys.argv[1], "w") as f:
    f.write(",".join(keys) + "\n")
    for r in rows:
        f.write(",".join(str(r[k]) for k in keys) + "\n")
with open(sys.argv[2], "w") as f:
    f.write("| run | frames | substeps per frame | wall s per frame (median) | mean | total s | asleep at end | magnetics s | rigid s | deepest penetration mm | largest energy rise per frame J |\n")
    f.write("|---|---|---|---|---|---|---|---|---|---|---|\n")
    for r in rows:
        f.write(f"| {r['run']} | {r['frames']} | {r['substeps_per_frame']:.0f} | {r['wall_s_per_frame']:.3g} | "
                f"{r['mean_wall_s_per_frame']:.3g} | {r['total_wall_s']:.4g} | {r['asleep_at_end']} | "
                f"{r['magnetics_s_per_frame']:.3g} | {r['rigid_s_per_frame']:.3g} | {r['max_penetration_mm']:.3f} | "
                f"{r['largest_energy_rise_J']:.2e} |\n")
print(open(sys.argv[2]).read())
