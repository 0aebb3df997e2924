"""The reference figures `vvgen compare` is held to on point clouds: MPEG's pc_error (mpeg-pcc-dmetric) on
pairs of a vvgen cloud and degraded copies of it. Never a test dependency; the suite stores what this prints.

    benches/pc_error_build.sh /tmp/pcerr          # builds pc_error 0.14.1 from its public source
    python3 benches/pc_error_reference.py --degrade REF.ply OUT_DIR    # writes OUT_DIR/{quant,noise,sub}.ply
    python3 benches/pc_error_reference.py /tmp/pcerr/pc_error REF.ply TEST.ply [PEAK] > figures.json

The degraded copies stand in for codecs: `quant` halves the grid (positions rounded to even cells, so points
merge), `noise` moves 30 % of the points by a cell and shifts colours, `sub` keeps every other point.
"""
import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np

TYPES = {"float": "<f4", "float32": "<f4", "double": "<f8", "uchar": "u1", "uint8": "u1", "uint": "<u4",
         "uint32": "<u4", "int": "<i4", "int32": "<i4"}


def read_ply(path):
    data = Path(path).read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode().splitlines()
    n = int(next(l.split()[2] for l in header if l.startswith("element vertex")))
    # The vertex element's scalar properties (a face list after them is left alone).
    start = next(i for i, l in enumerate(header) if l.startswith("element vertex"))
    props = []
    for l in header[start + 1:]:
        if not l.startswith("property") or l.split()[1] == "list":
            break
        props.append((l.split()[2], TYPES[l.split()[1]]))
    comments = [l for l in header if l.startswith("comment")]
    if "format ascii 1.0" in header:
        rows = data[end:].decode().splitlines()[:n]
        table = np.array([r.split()[: len(props)] for r in rows], dtype=np.float64)
        out = np.zeros(n, dtype=np.dtype(props))
        for k, (name, _) in enumerate(props):
            out[name] = table[:, k]
        return out, comments
    assert "format binary_little_endian 1.0" in header, "ascii or binary little-endian"
    return np.frombuffer(data[end:], dtype=np.dtype(props), count=n), comments


def write_ply(path, rows):
    names = rows.dtype.names
    inv = {"<f4": "float", "u1": "uchar", "<u4": "uint", "<f8": "double", "<i4": "int"}
    head = ["ply", "format binary_little_endian 1.0", f"element vertex {len(rows)}"]
    head += [f"property {inv[rows.dtype[n].str.replace('|', '')]} {n}" for n in names]
    head += ["end_header"]
    Path(path).write_bytes(("\n".join(head) + "\n").encode() + rows.tobytes())


def degrade(ref, out):
    rows, _ = read_ply(ref)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(11)
    integer = np.all(np.mod(rows["x"], 1) == 0)
    cell = 1.0 if integer else float(np.median(np.abs(np.diff(np.sort(rows["x"])))[::50]) * 20 or 1e-3)
    q = rows.copy()
    for a in "xyz":
        q[a] = (np.round(q[a] / (2 * cell)) * 2 * cell).astype(np.float32)
    write_ply(out / "quant.ply", q)
    nz = rows.copy()
    moved = rng.random(len(nz)) < 0.3
    for a in "xyz":
        nz[a] = (nz[a] + moved * rng.integers(-1, 2, len(nz)) * cell).astype(np.float32)
    if "red" in nz.dtype.names:
        for c in ("red", "green", "blue"):
            nz[c] = np.clip(nz[c].astype(int) + rng.integers(-6, 7, len(nz)), 0, 255).astype(np.uint8)
    write_ply(out / "noise.ply", nz)
    write_ply(out / "sub.ply", rows[::2].copy())


def figures(pc_error, a, b, peak=None):
    cmd = [pc_error, "-a", a, "-b", b, "-c", "1"] + (["-r", str(peak)] if peak else [])
    text = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    grab = lambda key: [float(m) for m in re.findall(re.escape(key) + r"\s*:\s*(\S+)", text)]
    out = {"peak": grab("Peak distance for PSNR")[0] if not peak else float(peak),
           "d1_psnr": grab("mseF,PSNR (p2point)")[0]}
    if grab("mseF,PSNR (p2plane)"):
        out["d2_psnr"] = grab("mseF,PSNR (p2plane)")[0]
    if grab("c[0],PSNRF"):
        out["color_psnr"] = [grab(f"c[{k}],PSNRF")[0] for k in range(3)]
    return out


if __name__ == "__main__":
    args = sys.argv[1:]
    if args[0] == "--degrade":
        degrade(args[1], args[2])
    else:
        print(json.dumps(figures(*args[:3], *(args[3:4] or [None])), indent=1))
