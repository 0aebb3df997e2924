# A denser copy of a skinned FBX for the FBX speed bench: Blender imports FILE.fbx, subdivides every mesh once
# (Catmull-Clark; vertex groups, so the skin, interpolate with it) and exports OUT.fbx with its armature and
# animation. A triangle mesh of V vertices and F faces becomes about V + 2.5 F vertices: Mixamo's 9 112-vertex,
# 18 220-triangle characters come out near 54 000.
#
#   blender -b --factory-startup -P benches/blender_subdivide_fbx.py -- FILE.fbx OUT.fbx
import sys

import bpy

src, out = sys.argv[sys.argv.index("--") + 1:][:2]
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.fbx(filepath=src)
for ob in [o for o in bpy.context.scene.objects if o.type == "MESH"]:
    bpy.context.view_layer.objects.active = ob
    mod = ob.modifiers.new("subdivide", "SUBSURF")
    mod.levels = 1
    mod.render_levels = 1
    # Applied to the mesh itself, before the skin deforms it.
    bpy.ops.object.modifier_move_to_index(modifier=mod.name, index=0)
    bpy.ops.object.modifier_apply(modifier=mod.name)
    print(f"{ob.name}: {len(ob.data.vertices)} vertices, {len(ob.data.polygons)} faces")
# Textures go inside the file, as Mixamo ships them.
bpy.ops.export_scene.fbx(filepath=out, bake_anim=True, add_leaf_bones=False, path_mode="COPY", embed_textures=True)
