"""Compares vvgen renders with Blender's renders of the same cameras (benches/blender_fidelity.py).

    python benches/fidelity.py BLENDER_DIR DATASET_DIR [DATASET_DIR …]

For each PNG under BLENDER_DIR, the file at the same relative path in each dataset: silhouette IoU (alpha ≥ 128)
and mean / 99th-percentile absolute colour difference over pixels both cover fully (alpha ≥ 254: Blender's
Workbench writes 254 for full coverage), in /255.
Needs numpy and Pillow (a venv outside the repo).
"""
import glob
import os
import sys

import numpy as np
from PIL import Image


def main():
    ref, datasets = sys.argv[1], sys.argv[2:]
    files = sorted(glob.glob(os.path.join(ref, "**", "*.png"), recursive=True))
    for d in datasets:
        print(d)
        for f in files:
            rel = os.path.relpath(f, ref)
            a = np.asarray(Image.open(f).convert("RGBA")).astype(int)
            b = np.asarray(Image.open(os.path.join(d, rel)).convert("RGBA")).astype(int)
            sa, sb = a[..., 3] >= 128, b[..., 3] >= 128
            iou = (sa & sb).sum() / max(1, (sa | sb).sum())
            full = (a[..., 3] >= 254) & (b[..., 3] >= 254)
            diff = np.abs(a[..., :3] - b[..., :3])[full]
            print(f"  {rel:24} IoU {iou:.4f}  MAD {diff.mean():.2f}  p99 {np.percentile(diff, 99):.0f}  ({full.sum()} px)")


main()
