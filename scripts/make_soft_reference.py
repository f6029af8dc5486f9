#!/usr/bin/env python3
"""Reference values for soft (induced) bodies, for tests/scene/soft_reference_test.cpp.

No closed form exists for a soft cube, or for a soft sphere in a magnet's non-uniform field, so
each reference is magbake's own coupled solve converged in the cell size: the high preset with
`cell_size` = edge / n for two fine n, extrapolated to zero cell size with an h^2 error model and
averaged with the finer value (the h^1 extrapolation and the finer value bracket it; the spread
is stored as the reference's own uncertainty). For the cube at chi 2e4 the result is close to a
perfectly conducting cube's normalized polarizability (about 3.644 V H0), an independent check.
bench/results/soft_cube_2026-12-06 and soft_sphere_2026-12-06 have the convergence runs.

Run from the repository root after building (about 15 minutes on 2 cores):
    python3 scripts/make_soft_reference.py [build/bake/magbake]   # writes tests/data/soft_reference.json
"""
import json
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MAGBAKE = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "build", "bake", "magbake")


def cube_scene(chi):
    return ("magbake: 1\nname: soft_cube\nunits: {length: mm, angle: deg}\n"
            "magnetics: {quality: QUALITY, induction: coupled, external_field: [0, 0, 0.01]CELL}\n"
            "materials:\n  steel: {kind: soft, chi: %g, density: 7850}\n"
            "bodies:\n  - {name: cube, shape: {box: [10, 10, 10]}, material: steel, motion: static}\n" % chi)


def sphere_scene(chi, gap):
    return ("magbake: 1\nname: soft_sphere\nunits: {length: mm, angle: deg}\n"
            "magnetics: {quality: QUALITY, induction: coupledCELL}\n"
            "materials:\n  N42: {kind: permanent, remanence: 1.3, density: 7500}\n"
            "  steel: {kind: soft, chi: %g, density: 7850}\n"
            "bodies:\n  - {name: magnet, shape: {box: [10, 10, 10]}, material: N42, magnetization: [0, 0, 1], motion: static}\n"
            "  - {name: ball, shape: {sphere: {radius: 5}}, material: steel, motion: static, position: [0, 0, %g]}\n"
            % (chi, 10 + gap))


def evaluate(text, cell_mm):
    scene = text.replace("QUALITY", "high").replace("CELL", ", cell_size: %.10g, grading: 0" % cell_mm)
    path = os.path.join(ROOT, "build", "soft_reference_scene.yaml")
    with open(path, "w") as f:
        f.write(scene)
    out = subprocess.run([MAGBAKE, "-q", "eval", path, "--json"], check=True, capture_output=True, text=True).stdout
    return json.loads(out[: out.rfind("}") + 1])


def converged(text, quantity, n_fine):
    """quantity(eval json) at edge/n for the two n, extrapolated: (value, uncertainty, runs)."""
    runs = []
    for n in n_fine:
        j = evaluate(text, 10.0 / n)
        runs.append({"n": n, "cells": j["cells"], "value": quantity(j), "iterations": j["induction"]["iterations"],
                     "residual": j["induction"]["residual"]})
    (h1, v1), (h2, v2) = [(10.0 / r["n"], r["value"]) for r in runs]
    p1 = v2 + (v2 - v1) * h2 / (h1 - h2)
    p2 = v2 + (v2 - v1) * h2 ** 2 / (h1 ** 2 - h2 ** 2)
    ref = 0.5 * (v2 + p2)
    spread = max(abs(x - ref) for x in (v2, p1, p2))
    return ref, spread, runs


cases = []
for chi in (10, 700, 2e4):
    text = cube_scene(chi)
    ref, unc, runs = converged(text, lambda j: j["bodies"][0]["moment"][2], (32, 40))
    cases.append({"name": "cube_chi%g" % chi, "scene": text, "quantity": "moment_z", "body": 0,
                  "reference": ref, "uncertainty": unc, "runs": runs})
    print(cases[-1]["name"], ref, unc, flush=True)
for chi in (700, 2e4):
    for gap in (0.05, 1, 5, 20):
        text = sphere_scene(chi, gap)
        ref, unc, runs = converged(text, lambda j: j["bodies"][1]["force"][2], (20, 24))
        cases.append({"name": "sphere_chi%g_gap%gmm" % (chi, gap), "scene": text, "quantity": "force_z", "body": 1,
                      "reference": ref, "uncertainty": unc, "runs": runs})
        print(cases[-1]["name"], ref, unc, flush=True)

with open(os.path.join(ROOT, "tests", "data", "soft_reference.json"), "w") as f:
    json.dump({"generator": "scripts/make_soft_reference.py",
               "method": "high preset with uniform cells (grading 0), cell_size edge/n at two fine n, h^2 extrapolation averaged with the finer value",
               "cases": cases}, f, indent=1)
