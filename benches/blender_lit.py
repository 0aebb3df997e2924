# Renders a lit vvgen D-NeRF dataset's cameras again in Blender Cycles, as the reference for lit rendering
# (benches/lit_fidelity.sh runs it; benches/lit_metrics.py compares). Blender is a peer, never a test dependency.
#
#   BPY benches/blender_lit.py -- --model MODEL.gl(b|tf) --dataset OUT/…_dnerf --out DIR \
#       --sun DX,DY,DZ,STRENGTH,ANGLE_DEG --env MAP.exr,STRENGTH [--plane W,D,Z,GREY] [--no-sun] [--samples 512]
#
# BPY: a Python with Blender 4.5 LTS's `bpy` module (`pip install "bpy==4.5.*"` in a venv outside the repo), the
# reference: its Principled BSDF's diffuse is Lambert's (3.4's added a roughness-driven retro-reflection, 6–16 %
# brighter at grazing views). `blender -b -P benches/blender_lit.py -- …` still runs it in Blender 3.4.
#
# The scene is the manifest's, built the way Blender users build it: the model through Blender's glTF importer,
# placed by the dataset's `world_from_source`; a Sun lamp (Strength, Angle) whose −Z travels along DIR; the map
# in an Environment Texture node at Background Strength; a Lambertian ground (Diffuse BSDF) that casts no shadow
# (vvgen's plane receives only); Standard view transform, transparent film, no denoising. Frame f of the dataset
# is Blender frame f (the importer puts t = 0 at frame 0).
import argparse
import json
import os
import sys

import bpy
from mathutils import Vector

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_dataset  # noqa: E402  (Blender's Python: the folder is put on the path first)


def floats(s):
    return [float(v) for v in s.split(",")]


def args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser()
    p.add_argument("--model", required=True)
    p.add_argument("--dataset", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--sun", type=floats, required=True)
    p.add_argument("--env", required=True)
    p.add_argument("--plane", type=floats, default=None, help="W,D,Z,GREY (default: no ground)")
    p.add_argument("--no-sun", action="store_true")
    p.add_argument("--samples", type=int, default=256)
    p.add_argument("--direct", action="store_true", help="direct light only (no bounces): a diagnostic")
    p.add_argument("--seed", type=int, default=0, help="Cycles' noise seed (two seeds give the reference's noise floor)")
    p.add_argument("--engine", default="cycles", choices=["cycles", "eevee"], help="eevee: for timing")
    p.add_argument("--fps", type=float, default=24.0)
    p.add_argument("--images", default="", help="split/view/frame,… (default: every image)")
    return p.parse_args(argv)


def ground(spec):
    """The ground: Lambertian, receives shadows, casts none."""
    w, d, z, grey = spec
    bpy.ops.mesh.primitive_plane_add(size=1.0, location=(0.0, 0.0, z))
    plane = bpy.context.active_object
    plane.scale = (w, d, 1.0)
    plane.visible_shadow = False
    mat = bpy.data.materials.new("ground")
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    diffuse = nt.nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (grey, grey, grey, 1.0)
    diffuse.inputs["Roughness"].default_value = 0.0
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    nt.links.new(diffuse.outputs["BSDF"], out.inputs["Surface"])
    plane.data.materials.append(mat)


def main():
    a = args()
    meta = json.load(open(os.path.join(a.dataset, "vvgen", "dataset.json")))
    scene = blender_dataset.import_model(a.model, meta, a.fps)

    if a.plane:
        ground(a.plane)

    if not a.no_sun:
        dx, dy, dz, strength, angle = a.sun
        sun = bpy.data.lights.new("sun", "SUN")
        sun.energy = strength
        sun.angle = angle * 3.141592653589793 / 180.0
        obj = bpy.data.objects.new("sun", sun)
        obj.rotation_euler = Vector((dx, dy, dz)).to_track_quat("-Z", "Y").to_euler()
        scene.collection.objects.link(obj)

    env_path, env_strength = a.env.split(",")
    world = bpy.data.worlds.new("world")
    scene.world = world
    world.use_nodes = True
    wn = world.node_tree
    tex = wn.nodes.new("ShaderNodeTexEnvironment")
    tex.image = bpy.data.images.load(os.path.abspath(env_path))
    bg = wn.nodes["Background"]
    bg.inputs["Strength"].default_value = float(env_strength)
    wn.links.new(tex.outputs["Color"], bg.inputs["Color"])

    blender_dataset.film(scene, meta["camera"])
    # Blender 4.2 renamed Eevee and dropped its soft-shadow and AO switches (always on).
    eevee = "BLENDER_EEVEE_NEXT" if bpy.app.version >= (4, 2, 0) else "BLENDER_EEVEE"
    scene.render.engine = "CYCLES" if a.engine == "cycles" else eevee
    scene.cycles.samples = a.samples
    scene.cycles.seed = a.seed
    scene.eevee.taa_render_samples = a.samples
    for flag in ("use_soft_shadows", "use_gtao"):
        if hasattr(scene.eevee, flag):
            setattr(scene.eevee, flag, True)
    scene.cycles.use_denoising = False
    scene.cycles.device = "CPU"
    if a.direct:
        scene.cycles.max_bounces = 0
    blender_dataset.render_images(scene, meta, a.out, a.images)


main()
