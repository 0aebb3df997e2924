#!/usr/bin/env bash
# vvgen's `.blend` import against Blender's own evaluation, vertex for vertex:
#   benches/blend_fidelity.sh FILE.blend…
# For each file: Blender writes its evaluated vertices at the first, middle and last frames
# (benches/blender_blend.py); vvgen imports the file as `blend = …` (no transform: Blender's world), writes
# each of those frames' posed geometry with `vvgen inspect --ply`, and the largest distance from either set to
# the other (symmetric Hausdorff: the glTF export splits vertices at seams, on Blender's) is printed as a
# fraction of the subject's height. Needs Blender and numpy.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
vvgen="${VVGEN:-$root/target/release/vvgen}"
for blend in "$@"; do
    work="$(mktemp -d)"
    # In its own folder: a .blend names its libraries and images relative to itself.
    name="$(cd "$(dirname "$blend")" && pwd)/$(basename "$blend")"
    if ! blender -b --factory-startup --disable-autoexec "$name" --python "$root/benches/blender_blend.py" \
        -- "$work/ref.json" >/dev/null 2>&1 || [ ! -f "$work/ref.json" ]; then
        echo "$(basename "$blend"): Blender itself cannot evaluate it (no reference)"
        rm -rf "$work"
        continue
    fi
    printf '[dataset]\nname = "f"\nout = "out"\n[source.s]\nblend = "%s"\n[render]\nresolution = [32, 32]\n[rig.h]\nkind = "hemisphere"\n[split.train]\nrig = "h"\nviews = 1\n[output.d]\nwriter = "nerfstudio"\n' "$name" > "$work/m.toml"
    /usr/bin/python3 - "$work" "$vvgen" "$(basename "$blend")" <<'PY'
import json, subprocess, sys
import numpy as np
work, vvgen, name = sys.argv[1:]
ref = json.load(open(f"{work}/ref.json"))
start = ref["range"][0]
worst = 0.0
for f, pts in ref["frames"].items():
    i = int(f) - start
    r = subprocess.run([vvgen, "inspect", f"{work}/m.toml", "--frame", str(i), "--ply", f"{work}/f.ply"],
                       capture_output=True, text=True)
    if r.returncode != 0 and "out of range" in r.stderr:
        # A file with no animation is one frame; Blender's other frames must equal it.
        r = subprocess.run([vvgen, "inspect", f"{work}/m.toml", "--frame", "0", "--ply", f"{work}/f.ply"],
                           capture_output=True, text=True)
    if r.returncode != 0:
        print(f"{name}: vvgen failed at frame {f}: {r.stderr.strip()}")
        sys.exit(0)
    data = open(f"{work}/f.ply", "rb").read()
    head, body = data.split(b"end_header\n", 1)
    lines = head.decode().splitlines()
    n = next(int(l.split()[2]) for l in lines if l.startswith("element vertex"))
    props = []
    for l in lines[lines.index(next(l for l in lines if l.startswith("element vertex"))) + 1:]:
        if not l.startswith("property"):
            break
        props.append(l.split()[1])
    types = {"float": "<f4", "double": "<f8", "uchar": "u1", "uint8": "u1", "int": "<i4", "uint": "<u4"}
    dt = np.dtype([(f"p{k}", types[t]) for k, t in enumerate(props)])
    v = np.frombuffer(body[: n * dt.itemsize], dtype=dt)
    got = np.stack([v["p0"], v["p1"], v["p2"]], axis=1).astype(np.float64)
    want = np.array(pts, dtype=np.float64)
    def one(a, b):
        m = 0.0
        for c in range(0, len(a), 512):
            d = ((a[c:c + 512, None, :] - b[None, :, :]) ** 2).sum(-1).min(1)
            m = max(m, float(d.max()))
        return m ** 0.5
    off = max(one(got, want), one(want, got)) if len(got) and len(want) else float("inf")
    worst = max(worst, off / max(ref["height"], 1e-9))
    print(f"{name}: frame {f}: {len(want)} Blender vertices, {len(got)} vvgen, off {off:.3g} ({off / max(ref['height'], 1e-9):.2g} of the height)")
print(f"{name}: worst {worst:.2g} of the height")
PY
    rm -rf "$work"
done
