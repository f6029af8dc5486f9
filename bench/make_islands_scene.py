#!/usr/bin/env python3
"""Per-island substeps benchmark scene (issue 11, outcome 2): two N42 ball magnets (radius 5 mm)
snapping on a table, beside a 10 x 10 grid of 1 cm N42 cubes resting 80 mm apart (magnetized
up; their mutual pull, at most ~0.01 N, is far below what friction holds) and 100 wooden
blocks. Only the snapping pair needs short pieces; a whole-world split refines all 202 bodies
with it.

Usage: make_islands_scene.py OUT.yaml [FRAMES]
"""
import sys

out = sys.argv[1]
frames = int(sys.argv[2]) if len(sys.argv) > 2 else 10
lines = [
    "magbake: 1",
    "name: islands",
    "units: {length: mm, angle: deg}",
    f"time: {{fps: 100, frames: [1, {frames + 1}], dt: 0.001}}",
    "gravity: [0, 0, -9810]",
    "materials:",
    "  N42: {kind: permanent, remanence: 1.3, density: 7500}",
    "  wood: {kind: none, density: 700}",
    "outputs: {cache: islands.h5}",
    "bodies:",
    "  - {name: table, shape: {box: [1400, 1400, 10]}, material: wood, motion: static, position: [0, 0, -5]}",
    "  - {name: a, shape: {sphere: {radius: 5}}, material: N42, magnetization: [1, 0, 0], position: [-7.5, -500, 5], friction: 0.5}",
    "  - {name: b, shape: {sphere: {radius: 5}}, material: N42, magnetization: [1, 0, 0], position: [7.5, -500, 5], friction: 0.5}",
]
for i in range(10):
    for j in range(10):
        x, y = -360 + 80 * i, -360 + 80 * j
        lines.append(f"  - {{name: cube_{i}_{j}, shape: {{box: [10, 10, 10]}}, material: N42, magnetization: [0, 0, 1], "
                     f"position: [{x}, {y}, 5.001], friction: 0.5}}")
        lines.append(f"  - {{name: block_{i}_{j}, shape: {{box: [10, 10, 10]}}, material: wood, "
                     f"position: [{x + 40}, {y + 40}, 5.001], friction: 0.5}}")
open(out, "w").write("\n".join(lines) + "\n")
