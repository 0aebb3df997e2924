# Blender's own posed vertices of a .blend, for `benches/blend_fidelity.sh` to compare vvgen's `blend = …`
# import against:
#   blender -b --factory-startup --disable-autoexec FILE.blend --python benches/blender_blend.py -- OUT.json [FRAMES…]
# For each frame (default: the scene's first, middle and last), every vertex of every mesh object the scene
# renders, evaluated (modifiers, shape keys, armatures, constraints, drivers) and in world space: what Blender's
# viewport and renders show. Writes {"frames": {"N": [[x, y, z], …]}, "height": h}.
import json
import sys

import bpy

args = sys.argv[sys.argv.index("--") + 1:]
out = args[0]
scene = bpy.context.scene
frames = [int(a) for a in args[1:]] or sorted({scene.frame_start, (scene.frame_start + scene.frame_end) // 2,
                                                scene.frame_end})
result = {}
for f in frames:
    scene.frame_set(f)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    points = []
    for o in scene.objects:
        if o.type != "MESH" or o.hide_render:
            continue
        e = o.evaluated_get(depsgraph)
        m = e.to_mesh()
        points += [list(e.matrix_world @ v.co) for v in m.vertices]
        e.to_mesh_clear()
    result[str(f)] = points
zs = [p[2] for pts in result.values() for p in pts]
with open(out, "w") as fh:
    json.dump({"frames": result, "height": (max(zs) - min(zs)) if zs else 0.0,
               "range": [scene.frame_start, scene.frame_end]}, fh)
