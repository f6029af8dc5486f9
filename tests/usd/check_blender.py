#!/usr/bin/env python3
"""Blender (PyPI's bpy 5.0.1, Blender as a Python module) opens a stage written by `magbake export
--usd`: every body's object has the cache's world transform at several frames, the field Volume
loads its B and density grids, and a small Cycles render of the shot is not blank.

The stage's field lines (BasisCurves) come in as a Curves object with the curves and points
usd-core reads at frame 1.

Usage: check_blender.py SHOT.usd[ac] CACHE.h5 PNG CURVES POINTS
"""
import sys

import bpy
import h5py
import numpy as np
from mathutils import Quaternion

usd_path, cache_path, png = sys.argv[1], sys.argv[2], sys.argv[3]
want_curves, want_points = int(sys.argv[4]), int(sys.argv[5])
cache = h5py.File(cache_path, "r", swmr=True)
steps = cache["frames/step"][:].astype(int)
names = [n.decode() if isinstance(n, bytes) else n for n in cache["bodies/name"][:]]
pos = cache["particles/bodies/position/value"][:]
ori = cache["particles/bodies/orientation/value"][:]

bpy.ops.wm.read_factory_settings(use_empty=True)
assert bpy.ops.wm.usd_import(filepath=usd_path) == {"FINISHED"}
scene = bpy.context.scene
worst_t = worst_q = 0.0
checked = 0
for k in (0, len(steps) // 2, len(steps) - 1):
    scene.frame_set(int(steps[k]))
    dg = bpy.context.evaluated_depsgraph_get()
    for i, name in enumerate(names):
        obj = bpy.data.objects[name]  # the body's prim name (these names are valid prim names)
        m = obj.evaluated_get(dg).matrix_world
        worst_t = max(worst_t, float(np.abs(np.array(m.translation) - pos[k, i]).max()))
        q = m.to_quaternion()
        qc = Quaternion(ori[k, i]).normalized()
        worst_q = max(worst_q, 1.0 - abs(q.dot(qc)))
        checked += 1
print(f"Blender {bpy.app.version_string}: {checked} body transforms at frames "
      f"{steps[0]}, {steps[len(steps) // 2]}, {steps[-1]}: translation off by {worst_t:.3g} m, 1 - |q.q| {worst_q:.3g}")
assert worst_t < 1e-6 and worst_q < 1e-6  # Blender's matrices are single precision

# The field volume: a Volume object whose file has the B and density grids.
vol = bpy.data.objects["field"]
assert vol.type == "VOLUME", vol.type
scene.frame_set(int(steps[0]))
vol.data.grids.load()
grids = sorted(g.name for g in vol.data.grids)
assert grids == ["B", "density"], grids
print("field volume:", vol.data.filepath, grids)

# The field lines: a Curves object, at frame 1 the stage's curves and points.
lines = bpy.data.objects["field_lines"]
assert lines.type == "CURVES", lines.type
scene.frame_set(int(steps[0]))
data = lines.evaluated_get(bpy.context.evaluated_depsgraph_get()).data
assert (len(data.curves), len(data.points)) == (want_curves, want_points), (len(data.curves), len(data.points))
print(f"field lines: a Curves object, {len(data.curves)} curves of {len(data.points)} points at frame {steps[0]}")

# A small Cycles frame: a camera looking at the bodies, a lit world; not blank.
lo = np.min(pos[0], axis=0) - 0.03
hi = np.max(pos[0], axis=0) + 0.03
centre = (lo + hi) / 2
cam = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
scene.collection.objects.link(cam)
cam.location = centre + np.array([1.0, -1.2, 0.8]) * float(np.linalg.norm(hi - lo))
target = bpy.data.objects.new("target", None)
scene.collection.objects.link(target)
target.location = centre
track = cam.constraints.new("TRACK_TO")
track.target = target
scene.camera = cam
scene.world = bpy.data.worlds.new("world")
scene.world.use_nodes = True
scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.35, 0.38, 0.42, 1.0)
sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
sun.data.energy = 4.0
sun.rotation_euler = (0.6, 0.2, 0.8)
scene.collection.objects.link(sun)
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 8
scene.render.resolution_x, scene.render.resolution_y = 128, 96
scene.render.resolution_percentage = 100
scene.render.filepath = png
scene.render.image_settings.file_format = "PNG"
bpy.ops.render.render(write_still=True)
img = bpy.data.images.load(png)
px = np.array(img.pixels[:]).reshape(-1, 4)[:, :3]
spread = float(px.std(axis=0).max())
print(f"Cycles {scene.render.resolution_x}x{scene.render.resolution_y}: pixel spread {spread:.3g}")
assert spread > 0.03, "the render is blank"
