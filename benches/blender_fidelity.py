# Renders a vvgen D-NeRF dataset's cameras again in Blender (Workbench: flat texture colour, Standard view
# transform, no dither, 16 AA samples), so the two can be compared image for image (benches/fidelity.py).
# Blender is a peer here, never a test dependency.
#
#   blender -b -P benches/blender_fidelity.py -- --glb MODEL.glb --dataset OUT/…_dnerf --out DIR \
#       [--images train/0/0,train/3/12,…]
#
# The model is placed by the dataset's own `vvgen/dataset.json` (`world_from_source`), the cameras are its
# `c2w` (OpenGL axes, which are Blender's camera axes) with its intrinsics; frame f of the dataset is Blender
# frame f (the importer puts t = 0 at frame 0; the scene runs at the clip's fps).
import argparse
import json
import math
import os
import sys

import bpy
import numpy as np
from mathutils import Matrix

if "bool" not in np.__dict__:  # Blender 3.4's glTF importer with numpy ≥ 1.24
    np.bool = bool


def args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser()
    p.add_argument("--glb", required=True)
    p.add_argument("--dataset", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--images", default="", help="split/view/frame,… (default: every image)")
    p.add_argument("--fps", type=float, default=24.0)
    return p.parse_args(argv)


def main():
    a = args()
    meta = json.load(open(os.path.join(a.dataset, "vvgen", "dataset.json")))
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps = int(round(a.fps))
    bpy.ops.import_scene.gltf(filepath=a.glb)
    # glTF (x, y, z) arrives as Blender (x, -z, y); the dataset's matrix maps glTF coordinates to its world.
    to_blender = Matrix(((1, 0, 0, 0), (0, 0, -1, 0), (0, 1, 0, 0), (0, 0, 0, 1)))
    world = Matrix(meta["sources"][0]["world_from_source"]) @ to_blender.inverted()
    root = bpy.data.objects.new("vvgen_world", None)
    scene.collection.objects.link(root)
    root.matrix_world = world
    for o in list(scene.objects):
        if o.parent is None and o is not root:
            o.parent = root

    cam = meta["camera"]
    scene.render.resolution_x, scene.render.resolution_y = cam["w"], cam["h"]
    scene.render.resolution_percentage = 100
    scene.render.engine = "BLENDER_WORKBENCH"
    scene.display.shading.light = "FLAT"
    scene.display.shading.color_type = "TEXTURE"
    scene.display.render_aa = "16"
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.render.dither_intensity = 0.0
    scene.render.film_transparent = True
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "RGBA"
    data = bpy.data.cameras.new("vvgen_cam")
    data.sensor_fit = "HORIZONTAL"
    data.sensor_width = 36.0
    data.lens = cam["fl_x"] * 36.0 / cam["w"]
    data.shift_x = (cam["w"] / 2 - cam["cx"]) / cam["w"]
    data.shift_y = (cam["cy"] - cam["h"] / 2) / cam["w"]
    data.clip_start, data.clip_end = cam["near"], cam["far"]
    obj = bpy.data.objects.new("vvgen_cam", data)
    scene.collection.objects.link(obj)
    scene.camera = obj

    wanted = set(a.images.split(",")) if a.images else None
    os.makedirs(a.out, exist_ok=True)
    for im in meta["images"]:
        name = f'{im["split"]}/{im["view"]}/{im["frame"]}'
        if wanted is not None and name not in wanted:
            continue
        scene.frame_set(im["frame"])
        obj.matrix_world = Matrix(im["c2w"])
        scene.render.filepath = os.path.join(a.out, im["files"]["rgba"])
        bpy.ops.render.render(write_still=True)
        print("rendered", name, flush=True)


main()
