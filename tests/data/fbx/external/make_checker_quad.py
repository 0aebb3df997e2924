# Writes checker_quad.fbx and textures/checker.png into the folder given after `--` (Blender 3.4.1):
#   blender -b --python make_checker_quad.py -- OUT
# A 1 m quad with an 8 × 8 checker image texture, exported with its texture kept as a file beside it (relative
# path, not embedded), as most FBX downloads come.
import os
import sys

import bpy

out = os.path.abspath(sys.argv[sys.argv.index("--") + 1])
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.mesh.primitive_plane_add(size=1.0)
obj = bpy.context.active_object
obj.name = "Quad"
img = bpy.data.images.new("checker", 8, 8)
px = []
for y in range(8):
    for x in range(8):
        c = 1.0 if (x + y) % 2 else 0.1
        px += [c, c * 0.5, 0.2, 1.0]
img.pixels = px
img.filepath_raw = os.path.join(out, "textures", "checker.png")
os.makedirs(os.path.join(out, "textures"), exist_ok=True)
img.file_format = 'PNG'
img.save()
mat = bpy.data.materials.new("Checker")
mat.use_nodes = True
nt = mat.node_tree
bsdf = nt.nodes["Principled BSDF"]
tex = nt.nodes.new("ShaderNodeTexImage")
tex.image = img
nt.links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
obj.data.materials.append(mat)
bpy.ops.export_scene.fbx(filepath=os.path.join(out, "checker_quad.fbx"), path_mode='RELATIVE', embed_textures=False)
