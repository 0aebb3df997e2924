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
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_dataset  # noqa: E402  (Blender's Python: the folder is put on the path first)


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
    scene = blender_dataset.import_model(a.glb, meta, a.fps)
    blender_dataset.film(scene, meta["camera"])
    scene.render.engine = "BLENDER_WORKBENCH"
    scene.display.shading.light = "FLAT"
    scene.display.shading.color_type = "TEXTURE"
    scene.display.render_aa = "16"
    blender_dataset.render_images(scene, meta, a.out, a.images)


main()
