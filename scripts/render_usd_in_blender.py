#!/usr/bin/env python3
"""Renders one frame of a magbake USD stage in Blender (bpy 5.0.1, Blender as a Python module):
the picture in docs/usd.md. Meshes get a material from their displayColor primvar (the preview
colours), the field Volume a Principled Volume driven by its density grid; a camera looks at the
bodies' bounding box from the front right.

Usage (the venv of tests/usd, with bpy): render_usd_in_blender.py SHOT.usda FRAME OUT.png [WxH]
"""
import sys

import bpy
import numpy as np

usd, frame, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
w, h = (int(v) for v in (sys.argv[4] if len(sys.argv) > 4 else "640x360").split("x"))
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.wm.usd_import(filepath=usd)
scene = bpy.context.scene
scene.frame_set(frame)

mat = bpy.data.materials.new("displayColor")
nodes = mat.node_tree.nodes
attr = nodes.new("ShaderNodeAttribute")
attr.attribute_name = "displayColor"
mat.node_tree.links.new(attr.outputs["Color"], nodes["Principled BSDF"].inputs["Base Color"])
nodes["Principled BSDF"].inputs["Roughness"].default_value = 0.45
vmat = bpy.data.materials.new("field")
vn = vmat.node_tree.nodes
vn.remove(vn["Principled BSDF"])
pv = vn.new("ShaderNodeVolumePrincipled")
pv.inputs["Density"].default_value = 0.0
pv.inputs["Color"].default_value = (0.2, 0.6, 1.0, 1.0)
da = vn.new("ShaderNodeAttribute")
da.attribute_name = "density"
scale = vn.new("ShaderNodeMath")
scale.operation = "MULTIPLY"
scale.inputs[1].default_value = 60.0
vmat.node_tree.links.new(da.outputs["Fac"], scale.inputs[0])
vmat.node_tree.links.new(scale.outputs["Value"], pv.inputs["Density"])
vmat.node_tree.links.new(pv.outputs["Volume"], vn["Material Output"].inputs["Volume"])

lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
dg = bpy.context.evaluated_depsgraph_get()
for o in bpy.data.objects:
    if o.type == "MESH":
        o.data.materials.clear()
        o.data.materials.append(mat)
        e = o.evaluated_get(dg)
        for c in e.bound_box:
            p = np.array(e.matrix_world @ __import__("mathutils").Vector(c))
            lo, hi = np.minimum(lo, p), np.maximum(hi, p)
    elif o.type == "VOLUME":
        o.data.materials.clear()
        o.data.materials.append(vmat)
centre, size = (lo + hi) / 2, float(np.linalg.norm(hi - lo))
cam = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
scene.collection.objects.link(cam)
cam.location = centre + np.array([0.9, -1.3, 0.7]) * size
target = bpy.data.objects.new("target", None)
scene.collection.objects.link(target)
target.location = centre
cam.constraints.new("TRACK_TO").target = target
scene.camera = cam
sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
sun.data.energy = 3.0
sun.rotation_euler = (0.7, 0.1, 0.9)
scene.collection.objects.link(sun)
scene.world = bpy.data.worlds.new("world")
scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.30, 0.32, 0.36, 1.0)
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 32
scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = w, h, 100
scene.render.filepath = out
scene.render.image_settings.file_format = "PNG"
bpy.ops.render.render(write_still=True)
