"""Compares vvgen's lit renders with Blender Cycles' (benches/blender_lit.py), image by image.

    python benches/lit_metrics.py VV_SUN VV_ENV REF_SUN REF_ENV --plane-z Z --sun DX,DY,DZ,STRENGTH --grey G

VV_SUN / VV_ENV: vvgen D-NeRF datasets of the same scene and cameras, with and without the sun (the second
also writes `depth`); REF_SUN / REF_ENV: Cycles' renders of their cameras, or several folders joined by commas
(renders that differ only in Cycles' seed), averaged in linear light. For every image:
- silhouette IoU (alpha ≥ 128);
- PSNR and SSIM (Gaussian window, σ = 1.5, per channel, averaged over the pixels both cover fully) of the lit
  RGBA with the sun;
- shadow-region IoU on the ground: ground pixels come from vvgen's depth (world z within 1 cm of the plane);
  a pixel is in shadow where the sun adds less than half of what it adds to open ground (grey · E · cos / π),
  the sun's share being the with-sun image minus the environment-only one, in linear light;
- the subject's brightness as a ratio to Cycles' (linear luminance over the pixels above the ground), with the
  sun and under the environment alone.
Needs numpy and Pillow (a venv outside the repo).
"""
import argparse
import json
import os

import numpy as np
from PIL import Image


def load(path):
    return np.asarray(Image.open(path).convert("RGBA")).astype(np.float64)


def load_ref(dirs, rel):
    """The reference image: the mean of the seeds' renders in linear light (alpha averaged as is), back to 8-bit
    sRGB as the renders are."""
    imgs = [load(os.path.join(d, rel)) for d in dirs.split(",")]
    lin = np.mean([linear(i[..., :3]) for i in imgs], axis=0)
    srgb = np.where(lin <= 0.0031308, lin * 12.92, 1.055 * np.power(lin, 1 / 2.4) - 0.055)
    out = np.empty_like(imgs[0])
    out[..., :3] = np.round(np.clip(srgb, 0, 1) * 255.0)
    out[..., 3] = np.round(np.mean([i[..., 3] for i in imgs], axis=0))
    return out


def linear(srgb8):
    c = srgb8 / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def gaussian_blur(img, sigma=1.5, radius=5):
    x = np.arange(-radius, radius + 1)
    k = np.exp(-(x * x) / (2 * sigma * sigma))
    k /= k.sum()
    out = img
    for axis in (0, 1):
        out = np.apply_along_axis(lambda v: np.convolve(v, k, mode="same"), axis, out)
    return out


def ssim_map(a, b):
    c1, c2 = (0.01 * 255) ** 2, (0.03 * 255) ** 2
    mu_a, mu_b = gaussian_blur(a), gaussian_blur(b)
    saa = gaussian_blur(a * a) - mu_a ** 2
    sbb = gaussian_blur(b * b) - mu_b ** 2
    sab = gaussian_blur(a * b) - mu_a * mu_b
    return ((2 * mu_a * mu_b + c1) * (2 * sab + c2)) / ((mu_a ** 2 + mu_b ** 2 + c1) * (saa + sbb + c2))


def main():
    p = argparse.ArgumentParser()
    p.add_argument("vv_sun")
    p.add_argument("vv_env")
    p.add_argument("ref_sun")
    p.add_argument("ref_env")
    p.add_argument("--plane-z", type=float, required=True)
    p.add_argument("--sun", required=True)
    p.add_argument("--grey", type=float, required=True)
    a = p.parse_args()
    dx, dy, dz, strength = [float(v) for v in a.sun.split(",")]
    d = np.array([dx, dy, dz]) / np.linalg.norm([dx, dy, dz])
    open_sun = a.grey * strength * max(0.0, -d[2]) / np.pi
    meta = json.load(open(os.path.join(a.vv_env, "vvgen", "dataset.json")))
    cam = meta["camera"]
    rows = []
    for im in meta["images"]:
        rel = im["files"]["rgba"]
        vs, ve = load(os.path.join(a.vv_sun, rel)), load(os.path.join(a.vv_env, rel))
        rs, re = load_ref(a.ref_sun, rel), load_ref(a.ref_env, rel)
        sil_v, sil_r = vs[..., 3] >= 128, rs[..., 3] >= 128
        iou = (sil_v & sil_r).sum() / max(1, (sil_v | sil_r).sum())
        full = (vs[..., 3] >= 254) & (rs[..., 3] >= 254)
        mse = ((vs[..., :3] - rs[..., :3])[full] ** 2).mean()
        psnr = 10 * np.log10(255.0 ** 2 / max(mse, 1e-12))
        ssim = np.mean([ssim_map(vs[..., c], rs[..., c])[full].mean() for c in range(3)])
        # Ground pixels, from vvgen's planar depth (millimetres) and the camera.
        depth = np.asarray(Image.open(os.path.join(a.vv_env, im["files"]["depth"]))).astype(np.float64) / 1000.0
        h, w = depth.shape
        u, v = np.meshgrid(np.arange(w) + 0.5, np.arange(h) + 0.5)
        pc = np.stack([(u - cam["cx"]) / cam["fl_x"] * depth, -(v - cam["cy"]) / cam["fl_y"] * depth, -depth], -1)
        c2w = np.array(im["c2w"])
        world_z = pc @ c2w[2, :3] + c2w[2, 3]
        ground = (depth > 0) & (np.abs(world_z - a.plane_z) < 0.01) & full & (ve[..., 3] >= 254) & (re[..., 3] >= 254)
        sun_v = (linear(vs[..., :3]) - linear(ve[..., :3])).mean(-1)
        sun_r = (linear(rs[..., :3]) - linear(re[..., :3])).mean(-1)
        sh_v, sh_r = ground & (sun_v < 0.5 * open_sun), ground & (sun_r < 0.5 * open_sun)
        shadow_iou = (sh_v & sh_r).sum() / max(1, (sh_v | sh_r).sum())
        # The subject's brightness against Cycles' (linear luminance summed over its fully covered pixels), with
        # the sun and under the environment alone: where a missing bounce or a wrong light shows first.
        subject = (depth > 0) & (world_z > a.plane_z + 0.01) & full & (ve[..., 3] >= 254) & (re[..., 3] >= 254)
        lum = np.array([0.2126, 0.7152, 0.0722])
        ratio = lambda x, y: (linear(x[..., :3])[subject] @ lum).sum() / max(1e-9, (linear(y[..., :3])[subject] @ lum).sum())
        rows.append((rel, iou, psnr, ssim, shadow_iou, int(sh_r.sum())))
        print(f"  {rel:20} silhouette IoU {iou:.4f}  PSNR {psnr:5.2f} dB  SSIM {ssim:.4f}  "
              f"shadow IoU {shadow_iou:.4f} ({sh_r.sum()} px in Cycles' shadow)  "
              f"subject ×{ratio(vs, rs):.3f} (environment alone ×{ratio(ve, re):.3f})", flush=True)
    m = np.array([r[1:5] for r in rows])
    print(f"  mean: silhouette IoU {m[:, 0].mean():.4f}  PSNR {m[:, 1].mean():.2f} dB  SSIM {m[:, 2].mean():.4f}  "
          f"shadow IoU {m[:, 3].mean():.4f}")
    print(f"  worst: silhouette IoU {m[:, 0].min():.4f}  PSNR {m[:, 1].min():.2f} dB  SSIM {m[:, 2].min():.4f}")


main()
