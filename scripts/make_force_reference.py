#!/usr/bin/env python3
"""Reference forces and torques between uniformly magnetized bodies, for
tests/scene/force_reference_test.cpp.

The force on a uniformly magnetized body in the field B of another is the surface integral of
its charge density sigma = M . n times B, and the torque about a point c the integral of
sigma (r - c) x B (physics.md §12): B comes from magpylib 6.1 (PyPI: exact fields of cuboids,
cylinders and triangle meshes), the integral from Gauss-Legendre quadrature on the target's
charged faces, refined until two levels agree (the agreement is stored as `quadrature_error`).
A ball target is a point dipole for any field whose sources lie outside it (mean-value
property): its force is the gradient of m . B at its centre, by central differences.

Each case holds a two-body magbake scene (millimetres; QUALITY stands for the preset), the
gaps (m), and per gap the force (N) and torque (N m, about the target's
centre) on the target body; TX, TY, TZ stand for the target centre in mm. Run from the repository root:

    python3 -m venv build/pyref && build/pyref/bin/pip install magpylib==6.1.0
    build/pyref/bin/python scripts/make_force_reference.py   # writes tests/data/force_reference.json
"""
import json
import math
import os

import numpy as np
import magpylib as magpy

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
J = 1.3  # N42 polarization, T
MU0 = 4e-7 * math.pi
GAPS_MM = [0.5, 1, 2, 5, 20]


def unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


def scene(source, source_dir, target, target_dir, target_pos):
    return ("magbake: 1\nname: force_ref\nunits: {length: mm, angle: deg}\n"
            "time: {fps: 30, frames: [1, 2], dt: 0.001}\n"
            "magnetics: {quality: QUALITY, induction: off}\n"
            "materials:\n  N42: {kind: permanent, remanence: %g, density: 7500}\n"
            "bodies:\n"
            "  - {name: source, shape: %s, material: N42, magnetization: [%g, %g, %g], position: [0, 0, 0], motion: static}\n"
            "  - {name: target, shape: %s, material: N42, magnetization: [%g, %g, %g], position: [%s, %s, %s], motion: static}\n"
            % (J, source, *source_dir, target, *target_dir, *target_pos))


def gauss(n):
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (x + 1), 0.5 * w


def rect_points(origin, u, v, panels, order=4):
    """Quadrature points and weights (area) on the rectangle origin + s u + t v, s, t in [0, 1],
    graded towards every edge (panel edges follow a cosine map)."""
    x, w = gauss(order)
    edges = 0.5 - 0.5 * np.cos(np.linspace(0, math.pi, panels + 1))
    s, ws = [], []
    for a, b in zip(edges[:-1], edges[1:]):
        s.extend(a + (b - a) * x), ws.extend((b - a) * w)
    s, ws = np.array(s), np.array(ws)
    S, T = np.meshgrid(s, s, indexing="ij")
    W = np.outer(ws, ws)
    area = np.linalg.norm(np.cross(u, v))
    P = origin + S.reshape(-1, 1) * u + T.reshape(-1, 1) * v
    return P, (W * area).reshape(-1)


def disk_points(center, radius, panels, nphi, order=4):
    x, w = gauss(order)
    edges = radius * np.sin(0.5 * math.pi * np.linspace(0, 1, panels + 1))  # graded to the rim
    rho, wr = [], []
    for a, b in zip(edges[:-1], edges[1:]):
        rho.extend(a + (b - a) * x), wr.extend((b - a) * w)
    rho, wr = np.array(rho), np.array(wr)
    phi = 2 * math.pi * (np.arange(nphi) + 0.5) / nphi
    R, P = np.meshgrid(rho, phi, indexing="ij")
    W = np.outer(wr * rho, np.full(nphi, 2 * math.pi / nphi))
    pts = np.stack([R.reshape(-1) * np.cos(P.reshape(-1)), R.reshape(-1) * np.sin(P.reshape(-1)),
                    np.zeros(R.size)], axis=1) + center
    return pts, W.reshape(-1)


def charge_integral(src, faces, center):
    """Force and torque about `center` of charged faces [(points, weights, sigma)] in src's field."""
    F, T = np.zeros(3), np.zeros(3)
    for pts, w, sigma in faces:
        if sigma == 0:
            continue
        B = src.getB(pts)
        F += sigma * (w[:, None] * B).sum(axis=0)
        T += sigma * (w[:, None] * np.cross(pts - center, B)).sum(axis=0)
    return F, T


def cube_faces(center, a, M, panels):
    faces = []
    h = a / 2
    for axis in range(3):
        for sgn in (1, -1):
            n = np.zeros(3)
            n[axis] = sgn
            u, v = np.zeros(3), np.zeros(3)
            u[(axis + 1) % 3], v[(axis + 2) % 3] = a, a
            origin = center + h * n - 0.5 * u - 0.5 * v
            pts, w = rect_points(origin, u, v, panels)
            faces.append((pts, w, M.dot(n)))
    return faces


def converged(fn, levels):
    """fn(level) -> (F, T) at increasing resolution until the last two agree to 1e-6."""
    prev = None
    for lv in levels:
        F, T = fn(lv)
        if prev is not None:
            err = np.linalg.norm(F - prev[0]) / np.linalg.norm(F)
            if err < 1e-6:
                return F, T, err
        prev = (F, T)
    return F, T, err


def cube_over_cylinder():
    # An N42 cylinder (r 5, h 10, axial) and above its top a 10 mm N42 cube magnetized mostly up
    # and a little sideways, 3 mm off the axis: the cube feels a force and a torque.
    r, hc, a = 0.005, 0.010, 0.010
    src = magpy.magnet.Cylinder(polarization=(0, 0, J), dimension=(2 * r, hc))
    d = unit([0.3, 0, 1])
    M = J / MU0 * d
    out = []
    for g in GAPS_MM:
        c = np.array([0.003, 0.0, hc / 2 + g * 1e-3 + a / 2])
        F, T, err = converged(lambda p: charge_integral(src, cube_faces(c, a, M, p), c), [16, 32, 64, 128])
        out.append((g, c, F, T, err))
    text = scene("{cylinder: {radius: 5, height: 10}}", (0, 0, 1), "{box: [10, 10, 10]}", d, ("TX", "TY", "TZ"))
    return "cube_over_cylinder", text, out


def cylinder_over_cylinder():
    # Two axial N42 cylinders (r 5, h 10), the upper one 2 mm off the common axis: only the caps
    # of the target carry charge.
    r, hc = 0.005, 0.010
    src = magpy.magnet.Cylinder(polarization=(0, 0, J), dimension=(2 * r, hc))
    M = J / MU0
    out = []
    for g in GAPS_MM:
        c = np.array([0.002, 0.0, hc + g * 1e-3])

        def fn(p):
            top = disk_points(c + [0, 0, hc / 2], r, p, 8 * p)
            bot = disk_points(c - [0, 0, hc / 2], r, p, 8 * p)
            return charge_integral(src, [(top[0], top[1], M), (bot[0], bot[1], -M)], c)
        F, T, err = converged(fn, [16, 32, 64, 128])
        out.append((g, c, F, T, err))
    text = scene("{cylinder: {radius: 5, height: 10}}", (0, 0, 1), "{cylinder: {radius: 5, height: 10}}", (0, 0, 1),
                 ("TX", "TY", "TZ"))
    return "cylinder_over_cylinder", text, out


def ball_beside_cylinder():
    # A 4 mm N42 ball beside the curved side of an axial N42 cylinder, magnetized across: the
    # side's field gradient. The ball is a dipole at its centre in the cylinder's field.
    r, hc, rb = 0.005, 0.010, 0.002
    src = magpy.magnet.Cylinder(polarization=(0, 0, J), dimension=(2 * r, hc))
    d = unit([1, 0, -0.5])
    m = J / MU0 * d * 4 / 3 * math.pi * rb ** 3
    out = []
    for g in GAPS_MM:
        c = np.array([r + g * 1e-3 + rb, 0.0, 0.003])
        h = 1e-7
        F = np.zeros(3)
        for k in range(3):
            e = np.zeros(3)
            e[k] = h
            F[k] = (m.dot(src.getB(c + e)) - m.dot(src.getB(c - e))) / (2 * h)
        T = np.cross(m, src.getB(c))
        out.append((g, c, F, T, 1e-7))
    text = scene("{cylinder: {radius: 5, height: 10}}", (0, 0, 1), "{sphere: {radius: 2}}", d, ("TX", "TY", "TZ"))
    return "ball_beside_cylinder", text, out


cases = []
for name, text, rows in [cube_over_cylinder(), cylinder_over_cylinder(), ball_beside_cylinder()]:
    cases.append({"name": name, "scene": text, "gap": [g * 1e-3 for g, *_ in rows],
                  "target_center": [c.tolist() for _, c, *_ in rows],
                  "force": [F.tolist() for _, _, F, _, _ in rows], "torque": [T.tolist() for *_, T, _ in rows],
                  "quadrature_error": [e for *_, e in rows]})
    for g, c, F, T, e in rows:
        print(f"{name:24s} gap {g:5.1f} mm  F {F}  T {T}  quad {e:.1e}")

out = {"generator": "scripts/make_force_reference.py", "magpylib": magpy.__version__, "polarization_T": J,
       "cases": cases}
path = os.path.join(ROOT, "tests/data/force_reference.json")
with open(path, "w") as f:
    json.dump(out, f, indent=1)
print("wrote", path)
