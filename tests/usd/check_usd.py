#!/usr/bin/env python3
"""Checks a stage written by `magbake export --usd` against its cache, with the reference USD
implementation (usd-core) and h5py: stage metadata (Z up, metres, time codes = frames at the
cache's fps), every body's world transform at every frame (translation and rotation, and a mesh
point carried by it), the custom attributes, the render meshes and their colours, the field
Volume's time-sampled OpenVDB assets, and USD's own validators (what usdchecker runs).

Usage: check_usd.py SHOT.usda CACHE.h5 VOLUME_FRAMES
"""
import math
import os
import sys

import h5py
import numpy as np
from pxr import Gf, Usd, UsdGeom, UsdValidation, UsdVol

usd_path, cache_path, volume_frames = sys.argv[1], sys.argv[2], int(sys.argv[3])
stage = Usd.Stage.Open(usd_path)
assert stage, "usd-core cannot open " + usd_path
cache = h5py.File(cache_path, "r", swmr=True)
fps = float(np.atleast_1d(cache["parameters"].attrs["fps"])[0])
steps = cache["frames/step"][:].astype(int)
names = [n.decode() if isinstance(n, bytes) else n for n in cache["bodies/name"][:]]
pos = cache["particles/bodies/position/value"][:]
ori = cache["particles/bodies/orientation/value"][:]  # w, x, y, z
force = cache["particles/bodies/magnetic_force/value"][:]
mass = cache["bodies/mass"][:]

# Stage metadata.
assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.z
assert UsdGeom.GetStageMetersPerUnit(stage) == 1.0
assert stage.GetTimeCodesPerSecond() == fps, (stage.GetTimeCodesPerSecond(), fps)
assert stage.GetFramesPerSecond() == fps
assert (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (steps[0], steps[-1])
shot = stage.GetDefaultPrim()
assert shot and shot.GetPath() == "/sphere_pickup", shot

# Bodies: found by their original names; transforms at every frame.
by_name = {}
for prim in stage.Traverse():
    n = prim.GetCustomDataByKey("magbake_name")
    if n is not None:
        by_name[n] = prim
assert sorted(by_name) == sorted(names), (sorted(by_name), names)
worst_t = worst_q = worst_p = 0.0
for i, name in enumerate(names):
    prim = by_name[name]
    xf = UsdGeom.Xformable(prim)
    meshes = [c for c in prim.GetChildren() if c.IsA(UsdGeom.Mesh)]
    assert meshes, name + " has no mesh"
    p_local = Gf.Vec3d(*UsdGeom.Mesh(meshes[0]).GetPointsAttr().Get()[0])
    assert prim.GetAttribute("magbake:mass").Get() == float(mass[i])
    for k, frame in enumerate(steps):
        m = xf.ComputeLocalToWorldTransform(Usd.TimeCode(int(frame)))
        t = np.array(m.ExtractTranslation())
        worst_t = max(worst_t, float(np.abs(t - pos[k, i]).max()))
        q = m.ExtractRotationQuat()
        qu = np.array([q.GetReal(), *q.GetImaginary()])
        qc = ori[k, i] / np.linalg.norm(ori[k, i])
        worst_q = max(worst_q, 1.0 - abs(float(np.dot(qu, qc))))
        # A mesh point carried by the cache's pose (x' = R x + t) and by USD's matrix.
        w, x, y, z = qc
        R = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                      [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                      [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
        want = R @ np.array(p_local) + pos[k, i]
        got = np.array(m.Transform(p_local))
        worst_p = max(worst_p, float(np.abs(got - want).max()))
        f = np.array(prim.GetAttribute("magbake:magneticForce").Get(Usd.TimeCode(int(frame))))
        assert np.array_equal(f, force[k, i]), (name, frame, f, force[k, i])
print(f"{len(names)} bodies x {len(steps)} frames: translation off by at most {worst_t:.3g} m, "
      f"rotation 1 - |q.q| {worst_q:.3g}, a mesh point {worst_p:.3g} m")
assert worst_t <= 1e-12 and worst_q <= 1e-12 and worst_p <= 1e-9

# The magnet's mesh has a north (red) and a south (blue) half.
magnet = by_name["magnet"]
colours = []
for c in magnet.GetChildren():
    if c.IsA(UsdGeom.Mesh):
        colours += list(UsdGeom.Gprim(c).GetDisplayColorAttr().Get())
reds = sum(1 for c in colours if c[0] > 0.5 and c[2] < 0.3)
blues = sum(1 for c in colours if c[2] > 0.5 and c[0] < 0.3)
assert reds > 0 and blues > 0, (reds, blues)
moment = magnet.GetAttribute("magbake:magneticMoment").Get(Usd.TimeCode(int(steps[0])))
assert moment is not None and Gf.Vec3d(moment).GetLength() > 0

# The field Volume: B and density fields whose files follow the frames.
vol = UsdVol.Volume(stage.GetPrimAtPath("/sphere_pickup/field"))
assert vol, "no Volume"
fields = vol.GetFieldPaths()
assert set(fields) == {"B", "density"}, fields
for field in ("B", "density"):
    asset = UsdVol.OpenVDBAsset(stage.GetPrimAtPath(fields[field]))
    assert asset.GetFieldNameAttr().Get() == field
    times = asset.GetFilePathAttr().GetTimeSamples()
    assert len(times) == volume_frames, times
    for t in times:
        p = asset.GetFilePathAttr().Get(t)
        assert p.resolvedPath and os.path.exists(p.resolvedPath), (t, p)
        assert p.resolvedPath.endswith("field.%04d.vdb" % int(t)), p.resolvedPath
print(f"field Volume: B and density over {volume_frames} frames, files resolved")

# USD's own validators (usd-core 26: UsdValidation, what usdchecker runs): no errors.
reg = UsdValidation.ValidationRegistry()
ctx = UsdValidation.ValidationContext(reg.GetOrLoadAllValidators())
found = ctx.Validate(stage)
errors = [e for e in found if e.GetType() == UsdValidation.ValidationErrorType.Error]
for e in found:
    print("validation:", e.GetType(), e.GetName(), e.GetMessage())
assert not errors, [e.GetMessage() for e in errors]
print(f"USD validators: {len(reg.GetAllValidatorMetadata())} run, no errors ({len(found)} findings in all)")
