"""Referee for vvgen's Gaussian splatting renders: the same views of a 3DGS PLY rendered by gsplat's pure-PyTorch
projection and spherical harmonics (`gsplat.cuda._torch_impl`, CPU), composited here as graphdeco-inria's
rasterizer composites (16 × 16 tiles reached by the 3σ square, opacity at most 0.99, contributions under 1/255
skipped, stop before transmittance falls under 1e-4), then scored against vvgen's images.

gsplat's rasterizing kernels are CUDA only; its projection (EWA with the 0.3 px² low-pass, the 1.3 × field of view
clamp) and its spherical harmonics (Sloan's evaluation, written apart from 3DGS's) are the parts taken from it.

    python -m venv /tmp/gsv && /tmp/gsv/bin/pip install torch gsplat numpy pillow
    vvgen inspect m.toml                       # prints the source → world matrix
    /tmp/gsv/bin/python benches/gaussians_reference.py --ply fused.ply --dataset out/x_dnerf \
        --matrix "r0c0 r0c1 ... r3c3" --views 4

Prints, per view, PSNR and the largest difference over RGB composited on white (as D-NeRF's loader reads an RGBA
image) and over alpha, in 8-bit levels.
"""

import argparse
import json
import math
import os

import numpy as np
import torch
from PIL import Image
from gsplat.cuda._torch_impl import _fully_fused_projection, _quat_scale_to_covar_preci, _spherical_harmonics


def read_ply(path):
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    head = data[:end].decode("ascii").splitlines()
    assert "format binary_little_endian 1.0" in head, "binary little-endian 3DGS files only"
    count, names = 0, []
    for line in head:
        parts = line.split()
        if parts[:2] == ["element", "vertex"]:
            count = int(parts[2])
        elif parts[:2] == ["property", "float"]:
            names.append(parts[2])
    rows = np.frombuffer(data[end:end + 4 * len(names) * count], dtype="<f4").reshape(count, len(names))
    col = {n: rows[:, i] for i, n in enumerate(names)}
    rest = sorted((n for n in names if n.startswith("f_rest_")), key=lambda n: int(n[7:]))
    degree = {0: 0, 9: 1, 24: 2, 45: 3}[len(rest)]
    k = (degree + 1) ** 2 - 1
    dc = np.stack([col["f_dc_%d" % c] for c in range(3)], -1)[:, None, :]
    # 3DGS's save_ply: features_rest (N, K, 3) transposed to (N, 3, K) and flattened, channel by channel.
    hi = np.stack([col[n] for n in rest], -1).reshape(count, 3, k).transpose(0, 2, 1) if k else np.zeros((count, 0, 3))
    return {
        "means": np.stack([col["x"], col["y"], col["z"]], -1),
        "scales": np.exp(np.stack([col["scale_%d" % i] for i in range(3)], -1)),
        "quats": np.stack([col["rot_%d" % i] for i in range(4)], -1),
        "opacities": 1 / (1 + np.exp(-col["opacity"])),
        "sh": np.concatenate([dc, hi], 1).astype(np.float32),
        "degree": degree,
    }


def render(g, c2w_gl, width, height, fx, fy, cx, cy, near):
    """One view: c2w in the file's axes, OpenGL convention. Straight RGBA in 0..1."""
    c2w = c2w_gl @ np.diag([1.0, -1.0, -1.0, 1.0])
    view = np.linalg.inv(c2w)
    means = torch.tensor(g["means"], dtype=torch.float32)
    covars, _ = _quat_scale_to_covar_preci(
        torch.tensor(g["quats"], dtype=torch.float32), torch.tensor(g["scales"], dtype=torch.float32),
        compute_covar=True, compute_preci=False, triu=False)
    K = torch.tensor([[fx, 0, cx], [0, fy, cy], [0, 0, 1]], dtype=torch.float32)[None]
    radii, means2d, depths, conics, _ = _fully_fused_projection(
        means, covars, torch.tensor(view, dtype=torch.float32)[None], K, width, height, eps2d=0.3, near_plane=near)
    dirs = means - torch.tensor(c2w[:3, 3], dtype=torch.float32)
    colors = torch.clamp_min(_spherical_harmonics(g["degree"], dirs, torch.tensor(g["sh"])) + 0.5, 0.0).numpy()
    m2, dep, con = means2d[0].numpy(), depths[0].numpy(), conics[0].numpy()
    ok = (dep > near) & np.isfinite(con).all(-1)
    # 3DGS's radius (3σ of the larger eigenvalue of the dilated covariance) and its tiles.
    det = 1 / (con[:, 0] * con[:, 2] - con[:, 1] ** 2)
    a, c = con[:, 2] * det, con[:, 0] * det
    mid = 0.5 * (a + c)
    lam = mid + np.sqrt(np.maximum(0.1, mid * mid - (a * c - (con[:, 1] * -det) ** 2)))
    r = np.ceil(3 * np.sqrt(lam))
    px, py = m2[:, 0] - 0.5, m2[:, 1] - 0.5
    gx, gy = (width + 15) // 16, (height + 15) // 16
    trunc = lambda v, n: np.clip(np.trunc(v / 16), 0, n).astype(int)
    x0, x1 = trunc(px - r, gx), trunc(px + r + 15, gx)
    y0, y1 = trunc(py - r, gy), trunc(py + r + 15, gy)
    ok &= (x1 > x0) & (y1 > y0)
    idx = np.nonzero(ok)[0]
    idx = idx[np.lexsort((idx, dep[idx]))]
    out = np.zeros((height, width, 4))
    for ty in range(gy):
        for tx in range(gx):
            sel = idx[(x0[idx] <= tx) & (tx < x1[idx]) & (y0[idx] <= ty) & (ty < y1[idx])]
            if len(sel) == 0:
                continue
            ys, xs = np.mgrid[ty * 16:min(height, ty * 16 + 16), tx * 16:min(width, tx * 16 + 16)]
            pix = np.stack([xs.ravel() + 0.5, ys.ravel() + 0.5], -1)
            d = m2[sel][None, :, :] - pix[:, None, :]
            cc = con[sel]
            power = -0.5 * (cc[:, 0] * d[..., 0] ** 2 + cc[:, 2] * d[..., 1] ** 2) - cc[:, 1] * d[..., 0] * d[..., 1]
            alpha = np.minimum(0.99, g["opacities"][sel] * np.exp(np.minimum(power, 0)))
            alpha[(power > 0) | (alpha < 1 / 255)] = 0
            trans = np.cumprod(1 - alpha, 1)
            stopped = np.cumsum(trans < 1e-4, 1) > 0
            alpha[stopped] = 0
            before = np.concatenate([np.ones((len(pix), 1)), np.cumprod(1 - alpha, 1)[:, :-1]], 1)
            w = alpha * before
            rgb = w @ colors[sel]
            acc = w.sum(1)
            straight = np.where(acc[:, None] > 0, rgb / np.maximum(acc[:, None], 1e-12), 0)
            out[ys.ravel(), xs.ravel(), :3] = straight
            out[ys.ravel(), xs.ravel(), 3] = acc
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--ply", required=True)
    ap.add_argument("--dataset", required=True, help="a D-NeRF dataset vvgen wrote")
    ap.add_argument("--matrix", required=True, help="source → world, 16 numbers row by row (vvgen inspect)")
    ap.add_argument("--split", default="train")
    ap.add_argument("--views", type=int, default=4)
    ap.add_argument("--near", type=float, default=0.05, help="world units")
    ap.add_argument("--save", help="folder for the reference images")
    a = ap.parse_args()
    g = read_ply(a.ply)
    M = np.array([float(v) for v in a.matrix.replace(",", " ").split()]).reshape(4, 4)
    scale = np.cbrt(abs(np.linalg.det(M[:3, :3])))
    Minv = np.linalg.inv(M)
    meta = json.load(open(os.path.join(a.dataset, "transforms_%s.json" % a.split)))
    worst = math.inf
    for i, fr in enumerate(meta["frames"][:a.views]):
        ours = np.asarray(Image.open(os.path.join(a.dataset, fr["file_path"] + ".png")).convert("RGBA")) / 255.0
        h, w = ours.shape[:2]
        f = 0.5 * w / math.tan(0.5 * meta["camera_angle_x"])
        c2w = Minv @ np.array(fr["transform_matrix"])
        c2w[:3, :3] /= np.linalg.norm(c2w[:3, :3], axis=0)  # the similarity's scale leaves the image as it is
        ref = render(g, c2w, w, h, f, f, w / 2, h / 2, a.near / scale)
        if a.save:
            os.makedirs(a.save, exist_ok=True)
            Image.fromarray((np.clip(ref, 0, 1) * 255 + 0.5).astype(np.uint8)).save(os.path.join(a.save, "%03d.png" % i))
        white = lambda im: im[..., :3] * im[..., 3:] + (1 - im[..., 3:])
        diff = np.abs(white(np.clip(ref, 0, 1)) - white(ours))
        psnr = 10 * math.log10(1 / max(np.mean(diff ** 2), 1e-12))
        worst = min(worst, psnr)
        print("view %d: PSNR %.2f dB over white, largest %d levels; alpha largest %d levels" % (
            i, psnr, round(diff.max() * 255), round(np.abs(np.clip(ref[..., 3], 0, 1) - ours[..., 3]).max() * 255)))
    print("worst %.2f dB" % worst)


if __name__ == "__main__":
    main()
