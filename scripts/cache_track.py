#!/usr/bin/python3
"""Prints a table of body positions (mm), speeds and magnetic forces per frame from a magbake cache.

usage: cache_track.py CACHE.h5 [BODY ...] [--every N]
A quick look at what happened in a bake (which body moved where, and when), for checking a shot
without rendering it. Reads the cache with h5py (docs/cache-format.md).
"""
import sys

import h5py
import numpy as np


def main(argv):
    every = 1
    if "--every" in argv:
        i = argv.index("--every")
        every = int(argv[i + 1])
        del argv[i:i + 2]
    if not argv:
        print(__doc__, file=sys.stderr)
        return 2
    with h5py.File(argv[0], "r", swmr=True) as f:
        names = [n.decode() if isinstance(n, bytes) else str(n) for n in f["/bodies/name"][()]]
        pos = f["/particles/bodies/position/value"][()]
        vel = f["/particles/bodies/velocity/value"][()]
        force = f["/particles/bodies/magnetic_force/value"][()]
        frames = f["/frames/step"][()]
    pick = [names.index(b) for b in argv[1:]] if len(argv) > 1 else range(len(names))
    print("frame " + " ".join(f"{names[b]:>36s}" for b in pick))
    for k in range(0, len(frames), every):
        cols = []
        for b in pick:
            p = 1e3 * pos[k, b]
            cols.append(f"{p[0]:7.1f}{p[1]:7.1f}{p[2]:7.1f} v{np.linalg.norm(vel[k, b]):5.2f} F{np.linalg.norm(force[k, b]):6.2f}")
        print(f"{frames[k]:5d} " + " ".join(f"{c:>36s}" for c in cols))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
