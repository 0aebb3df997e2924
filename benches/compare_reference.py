"""The reference figures `vvgen compare` is held to: scikit-image's PSNR and SSIM of image pairs, and (with
--degrade) the degraded copies it scores.

Run in a venv with scikit-image (never a test dependency):

    python -m venv /tmp/skvenv && /tmp/skvenv/bin/pip install scikit-image
    /tmp/skvenv/bin/python benches/compare_reference.py --degrade GT_DIR TEST_DIR   # writes TEST_DIR
    /tmp/skvenv/bin/python benches/compare_reference.py GT_DIR TEST_DIR > expected.json

Both images are read as sRGB bytes / 255; an image with alpha is composited over white. SSIM is Wang et al.'s
(gaussian_weights=True, sigma=1.5, use_sample_covariance=False, data_range=1, channel_axis=-1); the masked
figures keep the pixels the ground truth covers (alpha > 0): PSNR over them, SSIM as the mean of skimage's full
SSIM map over them, inside the 5-pixel border skimage leaves out.
"""
import json
import sys
from pathlib import Path

import numpy as np
from PIL import Image
from skimage.metrics import peak_signal_noise_ratio, structural_similarity


def load(path):
    a = np.asarray(Image.open(path).convert("RGBA"), dtype=np.float64) / 255.0
    has_alpha = Image.open(path).mode in ("RGBA", "LA", "PA")
    rgb, alpha = a[..., :3], a[..., 3:]
    if has_alpha:
        rgb = rgb * alpha + 1.0 * (1.0 - alpha)
    return rgb, (alpha[..., 0] > 0) if has_alpha else None


def degrade(gt_dir, out_dir):
    """Noise, a one-pixel shift and a blur in turn, written as opaque RGB PNGs (as trainers write renders)."""
    from scipy.ndimage import gaussian_filter

    out_dir.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(7)
    for i, p in enumerate(sorted(gt_dir.glob("*.png"))):
        rgb, _ = load(p)
        kind = i % 3
        if kind == 0:
            rgb = rgb + rng.normal(0.0, 0.03, rgb.shape)
        elif kind == 1:
            rgb = np.roll(rgb, 1, axis=1)
        else:
            rgb = gaussian_filter(rgb, sigma=(1.0, 1.0, 0.0))
        Image.fromarray((np.clip(rgb, 0, 1) * 255 + 0.5).astype(np.uint8), "RGB").save(out_dir / p.name)


def main():
    args = sys.argv[1:]
    if args and args[0] == "--degrade":
        degrade(Path(args[1]), Path(args[2]))
        return
    gt_dir, test_dir = Path(args[0]), Path(args[1])
    out = []
    for p in sorted(gt_dir.glob("*.png")):
        a, mask = load(p)
        b, _ = load(test_dir / p.name)
        kw = dict(data_range=1.0, channel_axis=-1, gaussian_weights=True, sigma=1.5, use_sample_covariance=False)
        ssim, full = structural_similarity(a, b, full=True, **kw)
        row = {"name": p.name, "psnr": peak_signal_noise_ratio(a, b, data_range=1.0), "ssim": ssim}
        if mask is not None and mask.any():
            d = (a - b)[mask]
            row["psnr_masked"] = float(-10 * np.log10(np.mean(d * d)))
            inner = np.zeros_like(mask)
            inner[5:-5, 5:-5] = True
            keep = mask & inner
            row["ssim_masked"] = float(np.mean([full[..., c][keep].mean() for c in range(3)]))
        out.append(row)
    print(json.dumps(out, indent=1))


main()
