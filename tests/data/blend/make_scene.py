# Writes the .blend the `.blend` source tests import, and Blender's own posed vertices of it (the reference):
#   blender -b --factory-startup --python make_scene.py -- OUT_DIR
# The scene: a keyframed cube (location and rotation, a texture it names beside the file), and a cylinder
# skinned to a two-bone armature whose upper bone bends, with a shape key animated from 0 to 1; and a box linked
# from a second file (`library.blend`, written first) whose own animated shape key stretches it: linked data is
# read-only, so vvgen's import cannot give it the modifier that makes Blender's exporter mix its shape keys
# without making it local first. Its frame range is 1-24 at 24 fps. The reference (`posed.json`) holds, for frames 1, 9, 17 and 24, every mesh object's
# evaluated vertices in world space: what Blender's viewport and renders show.
import json
import os
import sys

import bpy

out = sys.argv[sys.argv.index("--") + 1]
try:
    import numpy  # noqa: F401  (vvgen's import uses Blender's glTF exporter, which needs it)
except ImportError:
    sys.stderr.write("numpy missing\n")
    os._exit(5)



def animated_key(obj, name, axis, scale):
    """A shape key of `obj` that scales its `axis` coordinate (0, 1, 2) by `scale`, from 0 at frame 1 to 1 at 24."""
    obj.shape_key_add(name="Basis")
    key = obj.shape_key_add(name=name)
    for v in key.data:
        v.co[axis] *= scale
    key.value = 0.0
    key.keyframe_insert("value", frame=1)
    key.value = 1.0
    key.keyframe_insert("value", frame=24)


# The library: a box whose shape key, animated from 0 to 1, makes it three times as tall.
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.mesh.primitive_cube_add(size=0.5, location=(0, 1.5, 0.25))
box = bpy.context.object
box.name = "Linked"
animated_key(box, "Tall", 2, 3.0)
bpy.ops.wm.save_as_mainfile(filepath=os.path.join(out, "library.blend"))

bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
scene.frame_start, scene.frame_end, scene.render.fps = 1, 24, 24

# A textured cube, keyframed.
img = bpy.data.images.new("checker", 8, 8)
img.pixels = [v for i in range(64) for v in ((1, 1, 1, 1) if (i + i // 8) % 2 else (0.1, 0.3, 0.8, 1))]
img.filepath_raw = os.path.join(out, "checker.png")
img.file_format = "PNG"
img.save()
img.filepath = "//checker.png"
mat = bpy.data.materials.new("Checker")
mat.use_nodes = True
tex = mat.node_tree.nodes.new("ShaderNodeTexImage")
tex.image = img
mat.node_tree.links.new(tex.outputs["Color"], mat.node_tree.nodes["Principled BSDF"].inputs["Base Color"])
bpy.ops.mesh.primitive_cube_add(size=1, location=(1, 0, 0.5))
cube = bpy.context.object
cube.name = "Cube"
cube.data.materials.append(mat)
cube.keyframe_insert("location", frame=1)
cube.keyframe_insert("rotation_euler", frame=1)
cube.location = (1.5, 0.5, 1.0)
cube.rotation_euler = (0.3, 0, 1.0)
cube.keyframe_insert("location", frame=24)
cube.keyframe_insert("rotation_euler", frame=24)

# A cylinder skinned to two bones, with a shape key.
bpy.ops.mesh.primitive_cylinder_add(vertices=12, radius=0.25, depth=2, location=(-1, 0, 1))
arm = bpy.context.object
arm.name = "Arm"
bpy.ops.object.mode_set(mode="EDIT")
bpy.ops.mesh.subdivide(number_cuts=6)
bpy.ops.object.mode_set(mode="OBJECT")
bpy.ops.object.armature_add(location=(-1, 0, 0))
rig = bpy.context.object
rig.name = "Rig"
bpy.ops.object.mode_set(mode="EDIT")
lower = rig.data.edit_bones[0]
lower.head, lower.tail = (0, 0, 0), (0, 0, 1)
upper = rig.data.edit_bones.new("Upper")
upper.head, upper.tail, upper.parent = (0, 0, 1), (0, 0, 2), lower
bpy.ops.object.mode_set(mode="OBJECT")
arm.select_set(True)
rig.select_set(True)
bpy.context.view_layer.objects.active = rig
bpy.ops.object.parent_set(type="ARMATURE_AUTO")
animated_key(arm, "Bulge", 0, 1.6)
bone = rig.pose.bones["Upper"]
bone.rotation_mode = "XYZ"
bone.keyframe_insert("rotation_euler", frame=1)
bone.rotation_euler = (0.9, 0, 0)
bone.keyframe_insert("rotation_euler", frame=24)

# The box, linked (not appended) from the library.
with bpy.data.libraries.load(os.path.join(out, "library.blend"), link=True, relative=True) as (src, dst):
    dst.objects = ["Linked"]
for o in dst.objects:
    scene.collection.objects.link(o)

bpy.ops.wm.save_as_mainfile(filepath=os.path.join(out, "scene.blend"), relative_remap=True)

posed = {}
for f in (1, 9, 17, 24):
    scene.frame_set(f)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    points = []
    for o in scene.objects:
        if o.type != "MESH":
            continue
        e = o.evaluated_get(depsgraph)
        m = e.to_mesh()
        points += [list(e.matrix_world @ v.co) for v in m.vertices]
        e.to_mesh_clear()
    posed[str(f)] = points
with open(os.path.join(out, "posed.json"), "w") as fh:
    json.dump(posed, fh)
