#!/usr/bin/env python3
"""Reads a magbake field volume with Debian's pyopenvdb (an independent reader)."""
import sys

import pyopenvdb as vdb

path = sys.argv[1]
grids, meta = vdb.readAll(path)
names = [g.name for g in grids]
assert names == ["B", "density"], names
assert meta["creator"] == "magbake", meta
B = [g for g in grids if g.name == "B"][0]
assert B.valueTypeName == "vec3s", B.valueTypeName
assert B.metadata.get("vector_type") == "contravariant relative", B.metadata
assert abs(B.transform.voxelSize()[0] - 0.002) < 1e-12
assert B.activeVoxelCount() > 100
# One active value, and the magnitude's display density on the same voxel.
(lo, hi) = B.evalActiveVoxelBoundingBox()
acc = B.getConstAccessor()
d_acc = [g for g in grids if g.name == "density"][0].getConstAccessor()
found = 0
for x in range(lo[0], hi[0] + 1, 3):
    for y in range(lo[1], hi[1] + 1, 3):
        for z in range(lo[2], hi[2] + 1, 3):
            v, on = acc.probeValue((x, y, z))
            if on:
                dv, don = d_acc.probeValue((x, y, z))
                assert don and 0.0 <= dv <= 1.0
                found += 1
assert found > 0
print(f"ok: {path}: {B.activeVoxelCount()} active voxels, {found} checked")
