"""Blender's own FBX import as the reference for vvgen's FBX sources: posed vertices per mesh object.

    blender -b --factory-startup -P benches/blender_fbx.py -- FILE.fbx OUT.json [TIME_S ...]
    blender -b --factory-startup -P benches/blender_fbx.py -- --time FILE.fbx

Imports FILE.fbx with Blender's defaults but for `anim_offset = 0` (Blender shifts animation by one frame by
default; vvgen's frame 0 is the take's start), plays the first take, and for every TIME_S (seconds from the take's
start; default 0) writes each mesh object's evaluated vertices (modifiers: armature, shape keys) in world space,
in Blender's world (+Z up, metres as the importer's unit scale makes them). Vertex order is the FBX control
points' order, which Blender keeps, so vvgen's `FbxAsset::control_points` matches vertex for vertex.
"""
import json
import sys

import bpy

args = sys.argv[sys.argv.index("--") + 1:]
if args[0] == "--time":
    # Blender's import of the file alone, median of 5 after one untimed, in a fresh scene each time.
    import time
    runs = []
    for i in range(6):
        bpy.ops.wm.read_factory_settings(use_empty=True)
        t0 = time.perf_counter()
        bpy.ops.import_scene.fbx(filepath=args[1], anim_offset=0.0)
        runs.append(time.perf_counter() - t0)
    runs = sorted(runs[1:])
    print(f"{args[1]}: Blender import {runs[2] * 1e3:.1f} ms (median of 5)")
    sys.exit(0)
path, out = args[0], args[1]
times = [float(t) for t in args[2:]] or [0.0]

bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.fbx(filepath=path, anim_offset=0.0)
scene = bpy.context.scene
fps = scene.render.fps / scene.render.fps_base
result = {"file": path, "fps": fps, "frames": []}
for t in times:
    frame = t * fps
    scene.frame_set(int(frame), subframe=frame - int(frame))
    depsgraph = bpy.context.evaluated_depsgraph_get()
    objects = {}
    for obj in scene.objects:
        if obj.type != "MESH":
            continue
        ev = obj.evaluated_get(depsgraph)
        mesh = ev.to_mesh()
        m = ev.matrix_world
        objects[obj.name] = [list(m @ v.co) for v in mesh.vertices]
        ev.to_mesh_clear()
    result["frames"].append({"time": t, "objects": objects})
with open(out, "w") as f:
    json.dump(result, f)
print("wrote", out, "objects:", list(result["frames"][0]["objects"].keys()))
