#!/usr/bin/env python3
"""Writes the wide test subjects (standard library only; run from this folder to remake them):

- longbox/longbox.gltf + longbox.bin: a long low box (4 x 0.5 x 1, glTF's +Y up) with a head, walking: clip
  `Walk` (1 s) moves it along +X by 2 and bobs it, and swings the head; clip `Idle` (0.5 s) only swings the head.
  A .gltf with a side-car buffer, as exporters write them.
- plate/plate.ply: a flat wide plate (3 x 2 x 0.05, +Z up) far off the origin (centre at (10, 5, 0)), with vertex
  colours: a static scan-like mesh.
- flap/flap_000.obj ... flap_002.obj: a wide thin strip (3 x 0.6, Y up) whose ends bend up further each frame:
  an OBJ mesh sequence.
"""
import json
import math
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))


def box(cx, cy, cz, sx, sy, sz):
    """24 vertices (position, normal) and 36 indices of an axis-aligned box."""
    pos, nrm, idx = [], [], []
    for axis in range(3):
        for sign in (-1, 1):
            n = [0, 0, 0]
            n[axis] = sign
            u, v = [a for a in range(3) if a != axis]
            base = len(pos)
            for du, dv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                p = [0.0, 0.0, 0.0]
                p[axis] = sign * 0.5
                p[u] = du * 0.5
                p[v] = dv * 0.5
                pos.append((cx + p[0] * sx, cy + p[1] * sy, cz + p[2] * sz))
                nrm.append(tuple(float(x) for x in n))
            # Counter-clockwise seen from outside.
            quad = [0, 1, 2, 0, 2, 3]
            if (sign > 0) != ((u, v) in ((0, 1), (1, 2), (2, 0))):
                quad = [0, 2, 1, 0, 3, 2]
            idx += [base + q for q in quad]
    return pos, nrm, idx


def longbox():
    out = os.path.join(HERE, "longbox")
    os.makedirs(out, exist_ok=True)
    blob = bytearray()
    views, accessors = [], []

    def add(data, fmt, count, kind, comp, target=None, minmax=None):
        while len(blob) % 4:
            blob.append(0)
        off = len(blob)
        blob.extend(struct.pack("<" + fmt * count, *data) if fmt else data)
        view = {"buffer": 0, "byteOffset": off, "byteLength": len(blob) - off}
        if target:
            view["target"] = target
        views.append(view)
        acc = {"bufferView": len(views) - 1, "componentType": comp, "count": count // {"SCALAR": 1, "VEC3": 3, "VEC4": 4}[kind] if fmt else count, "type": kind}
        if minmax:
            acc["min"], acc["max"] = minmax
        accessors.append(acc)
        return len(accessors) - 1

    meshes = []
    for (c, s) in (((0, 0.25, 0), (4, 0.5, 1)), ((0, 0.2, 0), (0.6, 0.4, 0.6))):
        pos, nrm, idx = box(*c, *s)
        flat = [x for p in pos for x in p]
        lo = [min(p[i] for p in pos) for i in range(3)]
        hi = [max(p[i] for p in pos) for i in range(3)]
        a_pos = add(flat, "f", len(flat), "VEC3", 5126, 34962, (lo, hi))
        a_nrm = add([x for n in nrm for x in n], "f", len(flat), "VEC3", 5126, 34962)
        a_idx = add(idx, "H", len(idx), "SCALAR", 5123, 34963)
        meshes.append({"primitives": [{"attributes": {"POSITION": a_pos, "NORMAL": a_nrm}, "indices": a_idx, "material": len(meshes)}]})

    def clip(name, seconds, walk):
        n = 9
        times = [seconds * i / (n - 1) for i in range(n)]
        a_t = add(times, "f", n, "SCALAR", 5126, None, ([0.0], [seconds]))
        channels, samplers = [], []
        if walk:
            tr = []
            for t in times:
                tr += [-1.0 + 2.0 * t / seconds, 0.1 * abs(math.sin(2 * math.pi * t / seconds)), 0.0]
            samplers.append({"input": a_t, "output": add(tr, "f", 3 * n, "VEC3", 5126), "interpolation": "LINEAR"})
            channels.append({"sampler": len(samplers) - 1, "target": {"node": 0, "path": "translation"}})
        rot = []
        for t in times:
            a = 0.4 * math.sin(2 * math.pi * t / seconds)
            rot += [0.0, math.sin(a / 2), 0.0, math.cos(a / 2)]
        samplers.append({"input": a_t, "output": add(rot, "f", 4 * n, "VEC4", 5126), "interpolation": "LINEAR"})
        channels.append({"sampler": len(samplers) - 1, "target": {"node": 1, "path": "rotation"}})
        return {"name": name, "channels": channels, "samplers": samplers}

    animations = [clip("Walk", 1.0, True), clip("Idle", 0.5, False)]
    doc = {
        "asset": {"version": "2.0", "generator": "vvgen tests/data/wide/make.py"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [
            {"name": "body", "mesh": 0, "children": [1]},
            {"name": "head", "mesh": 1, "translation": [2.2, 0.45, 0.0]},
        ],
        "meshes": meshes,
        "materials": [
            {"name": "body", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.45, 0.1, 1.0], "metallicFactor": 0.0}},
            {"name": "head", "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.5, 0.8, 1.0], "metallicFactor": 0.0}},
        ],
        "animations": animations,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"uri": "longbox.bin", "byteLength": len(blob)}],
    }
    with open(os.path.join(out, "longbox.bin"), "wb") as f:
        f.write(blob)
    with open(os.path.join(out, "longbox.gltf"), "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")


def plate():
    out = os.path.join(HERE, "plate")
    os.makedirs(out, exist_ok=True)
    pos, _, idx = box(10, 5, 0, 3, 2, 0.05)
    lines = ["ply", "format ascii 1.0", "comment a flat wide plate far off the origin (vvgen tests/data/wide/make.py)",
             f"element vertex {len(pos)}", "property float x", "property float y", "property float z",
             "property uchar red", "property uchar green", "property uchar blue",
             f"element face {len(idx) // 3}", "property list uchar int vertex_indices", "end_header"]
    for (x, y, z) in pos:
        lines.append(f"{x:g} {y:g} {z:g} {int(40 + 60 * (x - 8.5))} {int(60 + 80 * (y - 4))} 180")
    for i in range(0, len(idx), 3):
        lines.append(f"3 {idx[i]} {idx[i + 1]} {idx[i + 2]}")
    with open(os.path.join(out, "plate.ply"), "w") as f:
        f.write("\n".join(lines) + "\n")


def flap():
    out = os.path.join(HERE, "flap")
    os.makedirs(out, exist_ok=True)
    cols = 13
    for frame in range(3):
        bend = 0.15 * (frame + 1)
        lines = [f"# a wide thin strip bending, frame {frame} (vvgen tests/data/wide/make.py)"]
        for i in range(cols):
            x = -1.5 + 3.0 * i / (cols - 1)
            y = bend * x * x
            for z in (-0.3, 0.3):
                lines.append(f"v {x:.4f} {y:.4f} {z:.4f} {0.3 + 0.2 * frame:.2f} 0.6 {0.9 - 0.05 * i:.2f}")
        for i in range(cols - 1):
            a, b, c, d = 2 * i + 1, 2 * i + 2, 2 * i + 4, 2 * i + 3
            lines.append(f"f {a} {b} {c}")
            lines.append(f"f {a} {c} {d}")
        with open(os.path.join(out, f"flap_{frame:03}.obj"), "w") as f:
            f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    longbox()
    plate()
    flap()
