#!/usr/bin/env bash
# The seed-scale set (issue 17) built cold by one or more `vvgen` binaries, then Blender's time for the same
# images, all in one run: this machine's speed drifts by 10-40 % between hours and days, so only figures from one
# run are compared. Each binary builds twice, alternating (A B A B), each time in a fresh folder (on this file
# system, creating files right after a large removal is slower; old folders are removed in the background).
#
#   benches/seed_peers.sh BENCH_PEERS VVGEN [VVGEN...]
#
# BENCH_PEERS: the folder holding Blender's render_nerf.py (e.g. ../shared/bench-peers); Blender 3.4 on PATH
# (skipped with a note when it is not). The manifest is benches/seed.rs's: CesiumMan, 60 frames × (80 train +
# 20 test) hemisphere views, 800², 4 samples, RGBA + 16-bit depth, D-NeRF layout, plus a 60-frame point-cloud
# sequence. A binary from before previews existed refuses `preview = false`; it gets the manifest without it
# (it made none). Blender renders 4 views × 3 frames of the same model at 800² (Workbench, and Cycles at 4
# samples); its median seconds per image × 6 000 is its time for the set.
set -euo pipefail
peers=$1
shift
here=$(cd "$(dirname "$0")/.." && pwd)
glb=$here/tests/data/gltf/CesiumMan/CesiumMan.glb
work=$(mktemp -d)
trap 'wait; rm -rf "$work"' EXIT

cat > "$work/seed.toml" <<EOF
[dataset]
name = "seed"
out = "out"
cache = "cache"
preview = false
[source.man]
gltf = "$glb"
frames = { count = 60, fps = 30 }
[transform]
up = "y"
fit = { height = 2.4 }
center = "bbox"
over = "all-frames"
[render]
resolution = [800, 800]
samples = 4
passes = ["rgba", "depth"]
[rig.hemi]
kind = "hemisphere"
[split.train]
rig = "hemi"
views = 80
time = "all"
[split.test]
rig = "hemi"
views = 20
time = "all"
[output.d]
writer = "dnerf"
[output.p]
writer = "ply-sequence"
points = 1000000
voxel = 0.005
EOF
grep -v '^preview' "$work/seed.toml" > "$work/seed-old.toml"

# One cold build by binary $1 in a fresh folder: prints wall, user and system seconds.
build() {
    local d
    d=$(mktemp -d "$work/run.XXXX")
    if "$1" check "$work/seed.toml" >/dev/null 2>&1; then cp "$work/seed.toml" "$d/seed.toml"; else cp "$work/seed-old.toml" "$d/seed.toml"; fi
    if ! (cd "$d" && /usr/bin/time -f "%e %U %S" -o "$d/time" "$1" build seed.toml >"$d/log" 2>&1); then
        echo "$1: the build failed:" >&2
        tail -20 "$d/log" >&2
        exit 1
    fi
    read -r wall user sys < "$d/time"
    printf '%-40s %7.1f s wall  %6.1f s user  %5.1f s system  %6.2f ms per image\n' \
        "$1" "$wall" "$user" "$sys" "$(echo "$wall" | awk '{print $1 * 1000 / 6000}')"
    rm -rf "$d" &
}

echo "== vvgen, the seed-scale set cold ($(date -u +%FT%TZ), $(nproc) cores) =="
for _ in 1 2; do
    for b in "$@"; do build "$b"; done
done
wait

echo "== Blender (render_nerf.py, 4 views x 3 frames, 800²) =="
if ! command -v blender >/dev/null; then
    echo "blender not on PATH: skipped (apt install blender)"
    exit 0
fi
for engine in "BLENDER_WORKBENCH 1" "CYCLES 4"; do
    set -- $engine
    out=$work/blender-$1
    blender -b -P "$peers/render_nerf.py" -- --gltf "$glb" --out "$out" --engine "$1" --samples "$2" \
        --views 4 --frames 3 --res 800 >"$work/blender-$1.log" 2>&1
    python3 - "$out/timings.json" "$1" "$2" <<'EOF'
import json, sys
t = json.load(open(sys.argv[1]))
m = t["median_s"]
print(f"{sys.argv[2]:<18} samples {sys.argv[3]}: {m * 1000:7.1f} ms per image (median of {len(t['per_image_s'])}), "
      f"{m * 6000 / 60:5.1f} min for the set's 6 000 images")
EOF
done
