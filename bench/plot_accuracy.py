#!/usr/bin/env python3
"""Plots bench/results/cube_pair_time_vs_error.csv: run time against force error for the cube
pair at each gap, with the Pareto front of all settings. Usage: plot_accuracy.py [results_dir]"""
import csv
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

results = sys.argv[1] if len(sys.argv) > 1 else "bench/results"
rows = list(csv.DictReader(open(f"{results}/cube_pair_time_vs_error.csv")))
gaps = sorted({float(r["gap_mm"]) for r in rows})
fig, axes = plt.subplots(1, len(gaps), figsize=(4.2 * len(gaps), 4.0), sharey=True)
styles = {"dipoles-uniform": ("o", "tab:red"), "nearfield-uniform": ("s", "tab:blue"),
          "nearfield-theta0.3": ("^", "tab:green"), "nearfield-theta0.5": ("v", "tab:olive"),
          "nearfield-theta0.7": ("D", "tab:purple")}
for ax, gap in zip(axes, gaps):
    by_method = defaultdict(list)
    pts = []
    for r in rows:
        if float(r["gap_mm"]) != gap:
            continue
        t, e = float(r["time_ms"]), max(float(r["rel_error"]), 1e-8)
        by_method[r["method"]].append((t, e, r["cell_mm"]))
        pts.append((t, e))
    for m, v in by_method.items():
        marker, color = styles.get(m, ("x", "k"))
        v.sort()
        ax.plot([p[0] for p in v], [p[1] for p in v], marker=marker, color=color, ls=":", lw=0.8, label=m)
    # Pareto front: lowest error reached for at most that much time.
    pts.sort()
    front, best = [], float("inf")
    for t, e in pts:
        if e < best:
            front.append((t, e))
            best = e
    ax.step([p[0] for p in front], [p[1] for p in front], where="post", color="k", lw=2, alpha=0.35,
            label="Pareto front")
    ax.axhline(0.01, color="gray", ls="--", lw=0.8)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_title(f"gap {gap:g} mm")
    ax.set_xlabel("time per evaluation (ms, 1 core)")
    ax.grid(True, which="both", alpha=0.2)
axes[0].set_ylabel("relative force error vs Akoun-Yonnet")
axes[-1].legend(fontsize=7, loc="upper right")
fig.suptitle("Two 1 cm cubes, J = 1 T: run time against error (dashed: 1%)")
fig.tight_layout()
fig.savefig(f"{results}/cube_pair_pareto.png", dpi=110)
print(f"wrote {results}/cube_pair_pareto.png")
