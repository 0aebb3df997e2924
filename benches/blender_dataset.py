# What benches/blender_fidelity.py and benches/blender_lit.py share: a vvgen dataset's model placed in Blender
# by its `vvgen/dataset.json`, its camera, and the loop that renders the dataset's images at their paths.
# Blender 3.4's own Python imports it (the scripts put their folder on sys.path).
import os
import time

import bpy
import numpy as np
from mathutils import Matrix

if "bool" not in np.__dict__:  # Blender 3.4's glTF importer with numpy ≥ 1.24
    np.bool = bool


def import_model(path, meta, fps):
    """Imports the glTF (or OBJ) at `path` into an empty scene at `fps`, placed by the dataset's first non-ground
    source's `world_from_source`; returns the scene."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps = int(round(fps))
    if path.lower().endswith(".obj"):
        # Blender's OBJ importer at its defaults (forward -Z, up Y), as a user imports one.
        bpy.ops.wm.obj_import(filepath=path)
    else:
        bpy.ops.import_scene.gltf(filepath=path)
    # glTF (x, y, z) arrives as Blender (x, -z, y), and so does an OBJ at the importer's default axes; the
    # dataset's matrix maps the file's coordinates to its world.
    to_blender = Matrix(((1, 0, 0, 0), (0, 0, -1, 0), (0, 1, 0, 0), (0, 0, 0, 1)))
    source = next(s for s in meta["sources"] if s["name"] != "ground")
    root = bpy.data.objects.new("vvgen_world", None)
    scene.collection.objects.link(root)
    root.matrix_world = Matrix(source["world_from_source"]) @ to_blender.inverted()
    for o in list(scene.objects):
        if o.parent is None and o is not root:
            o.parent = root
    return scene


def film(scene, cam):
    """The dataset's resolution, Standard view transform, no dither, transparent RGBA PNG."""
    r = scene.render
    r.resolution_x, r.resolution_y = cam["w"], cam["h"]
    r.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    r.dither_intensity = 0.0
    r.film_transparent = True
    r.image_settings.file_format = "PNG"
    r.image_settings.color_mode = "RGBA"


def render_images(scene, meta, out, images=""):
    """Renders every image of the dataset (or `images`, "split/view/frame,…") from its pinhole camera (Blender's
    camera axes are the dataset's OpenGL ones) into `out` at the dataset's relative paths."""
    cam = meta["camera"]
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
    wanted = set(images.split(",")) if images else None
    os.makedirs(out, exist_ok=True)
    for im in meta["images"]:
        name = f'{im["split"]}/{im["view"]}/{im["frame"]}'
        if wanted is not None and name not in wanted:
            continue
        scene.frame_set(im["frame"])
        obj.matrix_world = Matrix(im["c2w"])
        scene.render.filepath = os.path.join(out, im["files"]["rgba"])
        t0 = time.perf_counter()
        bpy.ops.render.render(write_still=True)
        print(f"rendered {name} in {time.perf_counter() - t0:.3f} s", flush=True)
