#!/usr/bin/env python3
"""Reference fields of uniformly magnetized bodies for tests/scene/field_reference_test.cpp.

magpylib 6.1 (PyPI) evaluates the exact B of a uniformly magnetized cuboid, cylinder and closed
triangle mesh, inside and outside; a sphere uses its closed form (dipole outside, 2/3 J inside).
Each case holds a one-body magbake scene (millimetres), points (m) at given distances from the
surface or inside, and B there (T). Run from the repository root:

    python3 -m venv build/pyref && build/pyref/bin/pip install magpylib==6.1.0
    build/pyref/bin/python scripts/make_field_reference.py   # writes tests/data/field_reference.json
"""
import json
import math
import os

import numpy as np
import magpylib as magpy

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
J = 1.3  # N42 polarization, T
DIST_MM = [0.5, 1, 2, 5, 20, 200]
rng = np.random.default_rng(14)


def scene(shape, direction):
    return ("magbake: 1\nname: ref\nunits: {length: mm, angle: deg}\n"
            "time: {fps: 30, frames: [1, 2], dt: 0.001}\n"
            "magnetics: {quality: QUALITY, induction: off}\n"
            "materials:\n  N42: {kind: permanent, remanence: %g, density: 7500}\n"
            "bodies:\n  - name: magnet\n    shape: %s\n    material: N42\n"
            "    magnetization: [%g, %g, %g]\n    position: [0, 0, 0]\n    motion: static\n"
            % (J, shape, *direction))


def unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


def cube_case():
    a = 0.010
    d = unit([1, 1, 1])
    src = magpy.magnet.Cuboid(polarization=J * d, dimension=(a, a, a))
    pts, dist = [], []
    for dm in DIST_MM:
        for _ in range(4):  # off a face, off an edge
            face = rng.integers(3)
            p = rng.uniform(-0.45 * a, 0.45 * a, 3)
            p[face] = (a / 2 + dm * 1e-3) * (1 if rng.random() < 0.5 else -1)
            pts.append(p), dist.append(dm * 1e-3)
    inside = [rng.uniform(-0.45 * a, 0.45 * a, 3) for _ in range(6)]
    return "cube", scene("{box: [10, 10, 10]}", d), src, pts, dist, inside


def cylinder_case(name, d):
    r, h = 0.005, 0.010
    src = magpy.magnet.Cylinder(polarization=J * unit(d), dimension=(2 * r, h))
    pts, dist = [], []
    for dm in DIST_MM:
        for _ in range(3):  # off the curved side
            phi, z = rng.uniform(0, 2 * math.pi), rng.uniform(-0.45 * h, 0.45 * h)
            pts.append([(r + dm * 1e-3) * math.cos(phi), (r + dm * 1e-3) * math.sin(phi), z]), dist.append(dm * 1e-3)
        for s in (1, -1):  # off the flat ends
            rho, phi = rng.uniform(0, 0.9 * r), rng.uniform(0, 2 * math.pi)
            pts.append([rho * math.cos(phi), rho * math.sin(phi), s * (h / 2 + dm * 1e-3)]), dist.append(dm * 1e-3)
    inside = []
    for _ in range(6):
        rho, phi, z = r * math.sqrt(rng.uniform(0, 0.8)), rng.uniform(0, 2 * math.pi), rng.uniform(-0.45 * h, 0.45 * h)
        inside.append([rho * math.cos(phi), rho * math.sin(phi), z])
    return name, scene("{cylinder: {radius: 5, height: 10}}", d), src, pts, dist, inside


def sphere_case():
    r = 0.005
    d = unit([0.3, -0.5, 0.8])
    m = J / (4e-7 * math.pi) * d * 4 / 3 * math.pi * r ** 3

    class Ball:  # closed form: a point dipole outside, 2/3 J inside
        def getB(self, p):
            p = np.atleast_2d(p)
            out = []
            for x in p:
                n = np.linalg.norm(x)
                if n < r:
                    out.append(2 / 3 * J * d)
                else:
                    out.append(1e-7 * (3 * x * x.dot(m) / n ** 5 - m / n ** 3))
            return np.array(out)
    pts, dist = [], []
    for dm in DIST_MM:
        for _ in range(4):
            pts.append((r + dm * 1e-3) * unit(rng.normal(size=3))), dist.append(dm * 1e-3)
    inside = [r * rng.uniform(0, 0.9) * unit(rng.normal(size=3)) for _ in range(6)]
    return "sphere", scene("{sphere: {radius: 5}}", d), Ball(), pts, dist, inside


def mesh_case():
    # The horseshoe of scenes/meshes (mm), magnetized along x (from leg to leg).
    V, F = [], []
    for line in open(os.path.join(ROOT, "scenes/meshes/horseshoe.obj")):
        t = line.split()
        if t and t[0] == "v":
            V.append([float(x) * 1e-3 for x in t[1:4]])
        elif t and t[0] == "f":
            F.append([int(x.split("/")[0]) - 1 for x in t[1:4]])
    V, F = np.array(V), np.array(F)
    d = unit([1, 0, 0.2])
    src = magpy.magnet.TriangularMesh(polarization=J * d, vertices=V, faces=F, reorient_faces=True)
    # Points off the middle of faces along their outward normals, kept where no other face is
    # closer than the offset (the horseshoe is concave).
    tri = V[F]
    cen = tri.mean(axis=1)
    nrm = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    nrm /= np.linalg.norm(nrm, axis=1)[:, None]
    if np.mean(np.einsum("ij,ij->i", nrm, cen - V.mean(axis=0))) < 0:
        nrm = -nrm
    pts, dist = [], []
    for dm in DIST_MM:
        got = 0
        for i in rng.permutation(len(F)):
            area = 0.5 * np.linalg.norm(np.cross(tri[i, 1] - tri[i, 0], tri[i, 2] - tri[i, 0]))
            if area < 4e-6:  # faces of at least 2 x 2 mm, so the point is well off their edges
                continue
            p = cen[i] + dm * 1e-3 * nrm[i]
            if np.min(np.linalg.norm(cen - p, axis=1)) < 0.999 * dm * 1e-3 - 1e-12:
                continue
            if np.linalg.norm(src.getB(p)) == 0:
                continue
            pts.append(p), dist.append(dm * 1e-3)
            got += 1
            if got == 4:
                break
    inside = [cen[i] - 0.001 * nrm[i] for i in rng.choice(len(F), 6, replace=False)]
    # MESH: the test puts the path of scenes/meshes/horseshoe.obj there.
    return "horseshoe", scene("{mesh: {file: MESH}}", d), src, pts, dist, inside


cases = []
for name, text, src, pts, dist, inside in [cube_case(), cylinder_case("cylinder_tilted", [1, 0, 1]),
                                          cylinder_case("cylinder_axial", [0, 0, 1]), sphere_case(), mesh_case()]:
    pts = np.array(list(pts) + list(inside), float)
    dist = list(dist) + [-1.0] * len(inside)  # -1: inside the magnet
    B = src.getB(pts)
    cases.append({"name": name, "scene": text, "points": pts.tolist(), "distance": dist, "B": np.asarray(B).tolist()})

out = {"generator": "scripts/make_field_reference.py", "magpylib": magpy.__version__, "polarization_T": J,
       "cases": cases}
path = os.path.join(ROOT, "tests/data/field_reference.json")
with open(path, "w") as f:
    json.dump(out, f, indent=1)
print("wrote", path, sum(len(c["points"]) for c in cases), "points")
