#!/usr/bin/python3
"""Makes the paper's Table 1 side by side with magbake's from bench/run_paper_table.sh results.

usage: paper_table.py RESULTS_DIR
Reads RESULTS_DIR/paper/<label>.json and <label>_time_vs_error.csv; writes
RESULTS_DIR/paper_table.md, paper_table.csv and paper_pareto.png (time per evaluation against
relative force error, every scene, every setting).
"""
import csv
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

# Table 1 of Thomaszewski et al. 2008: #cells, T_mag, T_rbd (ms per 1 ms step), Gain;
# Intel Core2Duo 2.4 GHz, one core.
PAPER = {
    "TST": (48, 0.29, 0.09, 1.30),
    "BowlSpheres": (256, 3.9, 0.25, 3.76),
    "Bowl2008": (128, 1.65, 2.39, 1.97),
    "SuperCube": (142, 0.33, 0.02, 5.97),
    "DragonLow": (1824, 53.1, 2.76, 6.72),
    "DragonHigh": (3628, 57.6, 2.92, 11.1),
}


def fmt(x, digits=3):
    if x is None:
        return "-"
    if x == 0:
        return "0"
    if abs(x) >= 100:
        return f"{x:.0f}"
    return f"{x:.{digits}g}"


def speedup(s):
    return f"{s:.2g}x" if s >= 1 else f"{s:.2g} ({1 / s:.0f}x slower)"


def timing(res, threads_one):
    rows = res["timing"]
    if threads_one:
        return next((r for r in rows if r["threads"] == 1), None)
    return max(rows, key=lambda r: r["threads"])


def is_reference(src, k, e):
    """When the `high` preset's model is the reference's (the same cells: until 2026-12-07 high was
    the ladder's first level, and ladders that stopped there compared high with itself),
    comparing the two measures nothing."""
    path = os.path.join(src, k + ".json")
    if e["setting"] != "high" or not os.path.exists(path):
        return False
    res = json.load(open(path))
    for i in res.get("error", []):
        if str(i["frame"]) != e["frame"]:
            continue
        used = [r for r in i["reference"] if r["label"] == i["reference_label"]]
        return bool(used) and int(used[0]["cells"]) == int(e["cells"])
    return False


def errors(path):
    if not os.path.exists(path):
        return []
    return list(csv.DictReader(open(path)))


def main(results):
    src = os.path.join(results, "paper")
    labels = [k for k in PAPER if os.path.exists(os.path.join(src, k + ".json"))]
    table = []
    for k in labels:
        res = json.load(open(os.path.join(src, k + ".json")))
        if "timing" not in res or "gain" not in res or "error" not in res:
            print(f"{k}: incomplete results (run the missing --parts), left out of the table", file=sys.stderr)
            continue
        one, many = timing(res, True), timing(res, False)
        errs = errors(os.path.join(src, k + "_time_vs_error.csv"))
        default_err = [float(e["max_rel_force_error"]) for e in errs if e["setting"] == "default"]
        default_norm = [float(e["max_error_over_largest_force"]) for e in errs if e["setting"] == "default"]
        ref_ok = all(i["reference_converged"] for i in res["error"])
        p_cells, p_mag, p_rbd, p_gain = PAPER[k]
        table.append({
            "scene": k, "paper_cells": p_cells, "paper_t_mag": p_mag, "paper_t_rbd": p_rbd, "paper_gain": p_gain,
            "cells": res["cells"], "bodies": res["bodies"],
            "t_mag_1": one["t_mag_ms_per_ms"], "t_rbd_1": one["t_rbd_ms_per_ms"],
            "t_mag_n": many["t_mag_ms_per_ms"], "t_rbd_n": many["t_rbd_ms_per_ms"], "threads_n": many["threads"],
            "substeps_per_ms": one["substeps_per_ms"], "nominal_substeps_per_ms": one["nominal_substeps_per_ms"],
            "induction_it": one["induction_iterations_per_eval"],
            "cell_pairs": one["cell_pairs_per_eval"], "node_pairs": one["node_pairs_per_eval"],
            "near_pairs": one["near_pairs_per_eval"], "t_mag_per_eval": one["t_mag_ms_per_eval"],
            "gain": res["gain"]["median_gain"], "speedup": p_mag / one["t_mag_ms_per_ms"],
            "default_error": max(default_err) if default_err else None,
            "default_error_norm": max(default_norm) if default_norm else None, "reference_converged": ref_ok,
            "window": res["window"],
        })

    with open(os.path.join(results, "paper_table.csv"), "w", newline="") as f:
        if table:
            w = csv.DictWriter(f, fieldnames=[c for c in table[0] if c != "window"])
            w.writeheader()
            for r in table:
                w.writerow({c: v for c, v in r.items() if c != "window"})

    md = []
    md.append("| scene | cells (paper / ours) | T_mag ms (paper / ours 1 thread / ours all cores) | "
              "T_rbd ms (paper / ours 1 / all) | speed-up T_mag (paper / ours, 1 thread) | substeps per 1 ms "
              "(nominal) | induction iterations per eval | cell + node pairs per eval | Gain (paper / ours) | "
              "force error at default, max over 2 instants: per body / over the largest force |")
    md.append("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for r in table:
        md.append(
            f"| {r['scene']} | {r['paper_cells']} / {r['cells']} | {fmt(r['paper_t_mag'])} / {fmt(r['t_mag_1'])} / "
            f"{fmt(r['t_mag_n'])} | {fmt(r['paper_t_rbd'])} / {fmt(r['t_rbd_1'])} / {fmt(r['t_rbd_n'])} | "
            f"{speedup(r['speedup'])} | {fmt(r['substeps_per_ms'])} ({fmt(r['nominal_substeps_per_ms'])}) | "
            f"{fmt(r['induction_it'])} | {fmt(r['cell_pairs'] + r['node_pairs'])} | {fmt(r['paper_gain'])} / "
            f"{fmt(r['gain'])} | "
            + (f"{100 * r['default_error']:.2g}% / {100 * r['default_error_norm']:.2g}%"
               if r["default_error"] is not None else "-")
            + ("" if r["reference_converged"] else " (reference not converged)") + " |")
    md.append("")
    md.append("Times are per 1 ms of simulated time (the paper's Table 1 is per 1 ms step). T_mag is the "
              "magnetics library, T_rbd Bullet; 'all cores' = "
              + (str(table[0]["threads_n"]) if table else "-") + " threads. Speed-up = paper T_mag / ours on "
              "one thread (below 1: slower than the paper). Window: the frames timed, in the close-contact "
              "part of each shot.")
    md.append("")
    md.append("| scene | window (first frame, frames) | T_mag per evaluation, 1 thread (ms) | near (exact cuboid) pairs per eval |")
    md.append("| --- | --- | --- | --- |")
    for r in table:
        md.append(f"| {r['scene']} | {r['window']['frame']}, {r['window']['frames']} | {fmt(r['t_mag_per_eval'])} | "
                  f"{fmt(r['near_pairs'])} |")
    md.append("")
    md.append("Run time against error (force on every body with |F| >= 1% of the largest, against the "
              "converged reference; 1 thread, each evaluation from a cold start):")
    md.append("")
    md.append("| scene | frame | setting | cells | ms per evaluation | max relative force error (per body) | RMS | "
              "max error over the largest force |")
    md.append("| --- | --- | --- | --- | --- | --- | --- | --- |")
    # Error results stand on their own (--parts error), with or without timings.
    labels = [k for k in PAPER if os.path.exists(os.path.join(src, k + "_time_vs_error.csv"))]
    for k in labels:
        for e in errors(os.path.join(src, k + "_time_vs_error.csv")):
            same = " (= the reference)" if is_reference(src, k, e) else ""
            md.append(f"| {k} | {e['frame']} | {e['setting']}{same} | {e['cells']} | {fmt(float(e['ms_per_eval_1thread']))} | "
                      f"{100 * float(e['max_rel_force_error']):.3g}% | {100 * float(e['rms_rel_force_error']):.3g}% | "
                      f"{100 * float(e['max_error_over_largest_force']):.3g}% |")
    md.append("")
    md.append("References (refined until the largest force changes by < 0.5% between two refinements, "
              "induction solved to 1e-10):")
    md.append("")
    md.append("| scene | frame | reference used | finest level tried | its cells | its change from the level before | "
              "error estimate (first order in h) | its induction iterations, residual | converged (< 0.5%) |")
    md.append("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for k in labels:
        path = os.path.join(src, k + ".json")
        res = json.load(open(path)) if os.path.exists(path) else {}
        for inst in res.get("error", []):
            last = inst["reference"][-1]
            ch = last["change_from_previous"]
            md.append(f"| {k} | {inst['frame']} | {inst['reference_label']} | {last['label']} | {last['cells']} | "
                      + (f"{100 * ch:.2g}%" if ch is not None else "-") + " | "
                      + (f"{100 * inst['reference_error_estimate_first_order']:.2g}%"
                         if inst.get("reference_error_estimate_first_order") is not None else "-")
                      + f" | {last['induction_iterations']}, {last['induction_residual']:.1e} | "
                      + ("yes" if inst["reference_converged"] else "no") + " |")
    open(os.path.join(results, "paper_table.md"), "w").write("\n".join(md) + "\n")
    print("\n".join(md))

    # Pareto plot: every scene, every setting, both instants.
    fig, ax = plt.subplots(figsize=(8, 5.5))
    markers = "osD^v<>"
    for i, k in enumerate(labels):
        errs = [e for e in errors(os.path.join(src, k + "_time_vs_error.csv")) if not is_reference(src, k, e)]
        xs = [float(e["ms_per_eval_1thread"]) for e in errs]
        ys = [max(float(e["max_rel_force_error"]), 1e-6) for e in errs]
        line = ax.scatter(xs, ys, marker=markers[i % len(markers)], label=k, alpha=0.8)
        for e, x, y in zip(errs, xs, ys):
            if e["setting"] == "default":
                ax.annotate("default", (x, y), fontsize=6, color=line.get_facecolor()[0],
                            xytext=(3, 3), textcoords="offset points")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.axhline(0.03, color="grey", lw=0.8, ls="--")
    ax.text(0.02, 0.031, "3% (the design target at default)", fontsize=7, color="grey", va="bottom",
            transform=ax.get_yaxis_transform())
    ax.set_xlabel("time per magnetics evaluation, 1 thread (ms)")
    ax.set_ylabel("max relative force error vs converged reference")
    ax.set_title("magbake on the paper's scenes: run time against force error")
    ax.grid(True, which="both", lw=0.3)
    ax.legend(fontsize=8)
    fig.subplots_adjust(left=0.11, right=0.97, top=0.93, bottom=0.1)
    fig.savefig(os.path.join(results, "paper_pareto.png"), dpi=110)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else "bench/results"))
