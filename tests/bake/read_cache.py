#!/usr/bin/env python3
"""Reads a magbake cache with h5py (an independent reader) and checks its layout and units."""
import sys

import h5py
import numpy as np

path = sys.argv[1]
with h5py.File(path, "r", swmr=True) as f:
    assert f.attrs["format"] == b"magbake-cache", f.attrs["format"]
    assert list(f["h5md"].attrs["version"]) == [1, 1]
    assert f["h5md/creator"].attrs["name"] == b"magbake"
    names = [n.decode() for n in f["bodies/name"][()]]
    n = len(names)
    frames = int(f["bake/frames_done"][0])
    assert int(f["bake/status"][0]) == 1, "complete"
    pos = f["particles/bodies/position/value"]
    assert pos.shape == (frames, n, 3), pos.shape
    assert pos.attrs["unit"] == b"m"
    q = f["particles/bodies/orientation/value"][()]
    assert q.shape == (frames, n, 4)
    assert np.allclose(np.linalg.norm(q, axis=2), 1.0, atol=1e-12), "unit quaternions (w, x, y, z)"
    assert f["particles/bodies/magnetic_force/value"].attrs["unit"] == b"kg m s-2"
    step = f["particles/bodies/position/step"][()]
    assert step[0] == f["parameters"].attrs["first_frame"] and len(step) == frames
    time = f["particles/bodies/position/time"][()]
    assert np.allclose(np.diff(time), 1.0 / f["parameters"].attrs["fps"])
    text = f["parameters/scene_text"][0].decode()
    assert "magbake: 1" in text
    assert len(f["parameters"].attrs["scene_hash"]) == 64
    for obs in ("kinetic_energy", "magnetic_energy", "momentum", "angular_momentum", "magnetics_seconds"):
        assert f[f"observables/{obs}/value"].shape[0] == frames, obs
    cells = f["magnetics/cells/position"]
    assert cells.shape[1] == 3 and cells.shape[0] == f["magnetics/cells/body"].shape[0]
    if "induced_moment" in f["magnetics"]:
        assert f["magnetics/induced_moment/value"].shape == (frames, f["magnetics/induced_cells"].shape[0], 3)
    verts = f["geometry/vertices"][()]
    tris = f["geometry/triangles"][()]
    assert tris.max() < len(verts)
print(f"ok: {path}: {n} bodies, {frames} frames")
