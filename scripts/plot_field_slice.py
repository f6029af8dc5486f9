#!/usr/bin/env python3
"""Renders a slice of |B| from a magbake field volume to a PNG (log colour scale), with the
in-plane field direction as streamlines. Reads the .vdb with pyopenvdb (Debian python3-openvdb).

  plot_field_slice.py field.0070.vdb out.png [--axis y] [--at 0.0]
"""
import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pyopenvdb as vdb  # noqa: E402

ap = argparse.ArgumentParser()
ap.add_argument("vdb")
ap.add_argument("png")
ap.add_argument("--axis", default="y", choices="xyz", help="slice normal")
ap.add_argument("--at", type=float, default=0.0, help="slice position, metres")
args = ap.parse_args()

grids, meta = vdb.readAll(args.vdb)
B = [g for g in grids if g.name == "B"][0]
voxel = B.transform.voxelSize()[0]
(lo, hi) = B.evalActiveVoxelBoundingBox()
lo, hi = np.array(lo), np.array(hi)
dense = np.zeros((hi[0] - lo[0] + 1, hi[1] - lo[1] + 1, hi[2] - lo[2] + 1, 3), dtype=np.float32)
B.copyToArray(dense, ijk=tuple(int(v) for v in lo))
ax_i = "xyz".index(args.axis)
k = int(round(args.at / voxel)) - lo[ax_i]
k = max(0, min(dense.shape[ax_i] - 1, k))
plane = np.take(dense, k, axis=ax_i)                 # (u, v, 3)
u_i, v_i = [i for i in range(3) if i != ax_i]
mag = np.linalg.norm(plane, axis=2)
u = (lo[u_i] + np.arange(plane.shape[0])) * voxel * 1e3
v = (lo[v_i] + np.arange(plane.shape[1])) * voxel * 1e3
fig, ax = plt.subplots(figsize=(5.2, 6.4))
img = ax.pcolormesh(u, v, np.log10(np.maximum(mag.T, 1e-6)), cmap="inferno", shading="auto", vmin=-4.5, vmax=0)
ax.streamplot(u, v, plane[:, :, u_i].T, plane[:, :, v_i].T, color=(0.7, 0.85, 1.0, 0.6), density=1.4, linewidth=0.6,
              arrowsize=0.6)
ax.set_aspect("equal")
ax.set_xlabel(f"{'xyz'[u_i]} (mm)")
ax.set_ylabel(f"{'xyz'[v_i]} (mm)")
ax.set_title(f"|B| on {args.axis} = {args.at * 1e3:g} mm, frame {meta.get('frame')}", fontsize=10)
cb = fig.colorbar(img, ax=ax, shrink=0.8)
cb.set_label("log10 |B| (T)")
fig.tight_layout()
fig.savefig(args.png, dpi=110)
print(f"wrote {args.png}")
