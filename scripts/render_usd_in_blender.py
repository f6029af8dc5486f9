#!/usr/bin/env python3
"""Renders one frame of a magbake USD stage in Blender (bpy 5.0.1, Blender as a Python module):
the picture in docs/usd.md. Meshes get a material from their displayColor primvar (the preview
colours), the field Volume a Principled Volume driven by its density grid; a camera looks at the
bodies' bounding box from the front right.

Usage (the venv of tests/usd, with bpy):
  render_usd_in_blender.py SHOT.usda FRAME OUT.png [WxH [DENSITY_SCALE [EMISSION_STRENGTH]]]
"""
import sys

import bpy
import numpy as np

usd, frame, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
w, h = (int(v) for v in (sys.argv[4] if len(sys.argv) > 4 else "640x360").split("x"))
DENSITY_SCALE = float(sys.argv[5]) if len(sys.argv) > 5 else 60.0       # extinction per metre at density 1
EMISSION_STRENGTH = float(sys.argv[6]) if len(sys.argv) > 6 else 300.0  # emission per metre at density 1
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
# The field Volume: docs/field-volumes.md's recipe. density is 0 at the edge of the active
# region and 1 where |B| reaches the strongest remanence, so it drives a thin absorbing fog and an
# emission coloured by a ramp (dark blue where weak, through cyan, to white at the poles).
vmat = bpy.data.materials.new("field")
vn, vl = vmat.node_tree.nodes, vmat.node_tree.links
vn.remove(vn["Principled BSDF"])
pv = vn.new("ShaderNodeVolumePrincipled")
pv.inputs["Color"].default_value = (0.05, 0.2, 0.6, 1.0)
da = vn.new("ShaderNodeAttribute")
da.attribute_name = "density"
fog = vn.new("ShaderNodeMath")
fog.operation = "MULTIPLY"
fog.inputs[1].default_value = DENSITY_SCALE
vl.new(da.outputs["Fac"], fog.inputs[0])
vl.new(fog.outputs["Value"], pv.inputs["Density"])
ramp = vn.new("ShaderNodeValToRGB")
ramp.color_ramp.elements[0].color = (0.0, 0.02, 0.25, 1.0)
ramp.color_ramp.elements[1].color = (1.0, 0.95, 0.8, 1.0)
mid = ramp.color_ramp.elements.new(0.5)
mid.color = (0.0, 0.55, 1.0, 1.0)
vl.new(da.outputs["Fac"], ramp.inputs["Fac"])
vl.new(ramp.outputs["Color"], pv.inputs["Emission Color"])
glow = vn.new("ShaderNodeMath")
glow.operation = "POWER"
glow.inputs[1].default_value = 2.0
vl.new(da.outputs["Fac"], glow.inputs[0])
strength = vn.new("ShaderNodeMath")
strength.operation = "MULTIPLY"
strength.inputs[1].default_value = EMISSION_STRENGTH
vl.new(glow.outputs["Value"], strength.inputs[0])
vl.new(strength.outputs["Value"], pv.inputs["Emission Strength"])
vl.new(pv.outputs["Volume"], vn["Material Output"].inputs["Volume"])

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
