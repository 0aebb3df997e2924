"""Blender's AgX view transform on known colours: what `benches/agx_reference.rs --ramp` compares vvgen's with.

    /tmp/bpy45/bin/python benches/blender_agx.py -- OUT.json

Writes a float image of scene-linear Rec.709 colours (a grey ramp from 1e-4 to 1000 in log steps, ramps of the
primaries and secondaries, and random colours up to 16), saves it through the scene's colour management (view
transform AgX, look None, exposure 0, sRGB display, no dither) as an 8-bit PNG, reads the codes back and writes
them beside the colours. Needs `bpy` (4.5 LTS from PyPI, in a venv outside the repo); never a test dependency.
"""
import json
import os
import random
import sys
import tempfile

import bpy

out = sys.argv[sys.argv.index("--") + 1]
colours = [[10 ** (-4 + 7 * i / 400)] * 3 for i in range(401)]
for hue in ([1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0], [0, 1, 1], [1, 0, 1], [1, 0.5, 0.1], [0.2, 0.4, 1]):
    colours += [[c * 10 ** (-3 + 5 * i / 100) for c in hue] for i in range(101)]
rng = random.Random(0)
colours += [[16 * rng.random() ** 3 for _ in range(3)] for _ in range(1000)]

w = len(colours)
img = bpy.data.images.new("ramp", width=w, height=1, float_buffer=True, alpha=True)
img.pixels = [v for c in colours for v in (*c, 1.0)]
scene = bpy.context.scene
scene.display_settings.display_device = "sRGB"
scene.view_settings.view_transform = "AgX"
scene.view_settings.look = "None"
scene.view_settings.exposure = 0.0
scene.view_settings.gamma = 1.0
scene.render.dither_intensity = 0.0
scene.render.image_settings.file_format = "PNG"
scene.render.image_settings.color_mode = "RGB"
scene.render.image_settings.color_depth = "8"
path = os.path.join(tempfile.mkdtemp(), "ramp.png")
img.save_render(path, scene=scene)
back = bpy.data.images.load(path)
back.colorspace_settings.name = "Non-Color"  # the stored codes, not decoded
px = list(back.pixels)
samples = [{"linear": c, "srgb8": [round(px[4 * i + k] * 255) for k in range(3)]} for i, c in enumerate(colours)]
json.dump({"blender": bpy.app.version_string, "view": "AgX", "samples": samples}, open(out, "w"))
print(f"wrote {len(samples)} colours ({bpy.app.version_string}) to {out}")
