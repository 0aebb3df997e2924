#!/usr/bin/env bash
# STL reading speed beside Blender 4.5's C++ importer (`wm.stl_import`) and trimesh, in the same run: assimp's
# spider (tests/data/stl) tiled into a 2 000 000-triangle binary file (100 MB) and a 400 000-triangle ASCII one
# (105 MB), alternating rounds. vvgen is timed for a whole `vvgen inspect` (process start, reading, posing, the
# geometry's hash and bounds); the peers for their import call alone, inside a Python already started.
#
#   benches/stl_speed.sh [WORK_DIR] [ROUNDS]
#
# Blender: $BPY, a Python with `bpy==4.5.*` (default /tmp/bpy45/bin/python); trimesh: $PY with `trimesh`.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
work=${1:-/tmp/vvgen-stl-speed}
rounds=${2:-3}
bpy=${BPY:-/tmp/bpy45/bin/python}
py=${PY:-python3}
mkdir -p "$work"
(cd "$repo" && cargo build --release --quiet)
vvgen=$repo/target/release/vvgen
"$py" - "$repo/tests/data/stl/Spider_binary.stl" "$work" <<'PY'
import struct, sys
src, work = sys.argv[1], sys.argv[2]
b = open(src, 'rb').read()
n = struct.unpack('<I', b[80:84])[0]
tris = [struct.unpack('<12f', b[84 + 50 * i:84 + 50 * i + 48]) for i in range(n)]
def tiled(count):
    k = 0
    while k < count:
        i, t = k % n, k // n
        dx, dy = 10.0 * (t % 40), 10.0 * (t // 40)
        v = tris[i]
        yield v[3:6], [(v[3 + 3 * j] + dx, v[4 + 3 * j] + dy, v[5 + 3 * j]) for j in range(3)]
        k += 1
with open(f'{work}/big_binary.stl', 'wb') as f:
    count = 2_000_000
    f.write(b'solid tiled spider'.ljust(80, b' ') + struct.pack('<I', count))
    for nrm, c in tiled(count):
        f.write(struct.pack('<12fH', *nrm, *c[0], *c[1], *c[2], 0))
with open(f'{work}/big_ascii.stl', 'w') as f:
    f.write('solid tiled\n')
    for nrm, c in tiled(400_000):
        f.write(' facet normal %e %e %e\n  outer loop\n' % nrm)
        for p in c:
            f.write('   vertex %e %e %e\n' % p)
        f.write('  endloop\n endfacet\n')
    f.write('endsolid tiled\n')
PY
for form in binary ascii; do
    cat > "$work/$form.toml" <<TOML
[dataset]
name = "s"
out = "out"
[source.s]
mesh = "big_$form.stl"
[rig.r]
kind = "hemisphere"
[split.train]
rig = "r"
views = 1
[output.d]
writer = "dnerf"
TOML
done
cat > "$work/peers.py" <<'PY'
import sys, time
tool, path = sys.argv[1], sys.argv[2]
if tool == 'blender':
    import bpy
    bpy.ops.wm.read_factory_settings(use_empty=True)
    t = time.perf_counter(); bpy.ops.wm.stl_import(filepath=path); dt = time.perf_counter() - t
    n = sum(len(o.data.polygons) for o in bpy.context.scene.objects if o.type == 'MESH')
else:
    import trimesh
    t = time.perf_counter(); m = trimesh.load(path); dt = time.perf_counter() - t
    n = len(m.faces)
print(f'{tool}: {dt:.2f} s ({n} triangles)')
PY
for r in $(seq "$rounds"); do
    for form in binary ascii; do
        t0=$(date +%s.%N)
        (cd "$work" && "$vvgen" inspect -q "$form.toml" > /dev/null)
        t1=$(date +%s.%N)
        echo "round $r $form vvgen: $(echo "$t1 - $t0" | bc | sed 's/^\./0./') s (whole inspect)"
        echo "round $r $form $("$bpy" "$work/peers.py" blender "$work/big_$form.stl" 2>/dev/null | grep '^blender')"
        echo "round $r $form $("$py" "$work/peers.py" trimesh "$work/big_$form.stl" 2>/dev/null | grep '^trimesh')"
    done
done
