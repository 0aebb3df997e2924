#!/usr/bin/env bash
# Lit rendering speed (issue 16): CesiumMan at 800², 4 samples, a sun with 3° soft shadows and the sunset map;
# 4 frames × 16 views, RGBA only, cold builds (fresh cache, environment prefiltering included). Three scenes,
# alternating: lit on a ground plane (`pbr`, the lit example's scene), lit alone (`alone`: the issue's scene,
# the man shadowing himself), unlit on the ground (`unlit`); then Blender's Eevee and Cycles (16 samples) on
# two of the same cameras with and without the ground, in the same run, per image.
#
#   benches/lit_speed.sh [WORK_DIR] [ROUNDS]
#
# Blender: $BPY, a Python with `bpy==4.5.*` (default /tmp/bpy45/bin/python), or BPY=blender for Debian's 3.4.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
work=${1:-/tmp/vvgen-lit-speed}
rounds=${2:-2}
mkdir -p "$work"
(cd "$repo" && cargo build --release --quiet)
vvgen=$repo/target/release/vvgen
bpy=${BPY:-/tmp/bpy45/bin/python}
run=("$bpy" "$repo/benches/blender_lit.py")
[ "$bpy" = blender ] && run=(blender -b -P "$repo/benches/blender_lit.py")
map=$repo/tests/data/hdri/sunset.exr
man=$repo/tests/data/gltf/CesiumMan/CesiumMan.glb
manifest() { # name: pbr | alone | unlit
    local lit="" shading=pbr ground="[source.ground]
plane = { size = [3.0, 3.0], color = [0.5, 0.5, 0.5], z = -1.2 }"
    [ "$1" = unlit ] && shading=unlit
    [ "$1" = alone ] && ground=""
    if [ "$shading" = pbr ]; then
        lit="[environment]
map = \"$map\"
strength = 0.6
[light.sun]
kind = \"sun\"
direction = [0.45, 0.35, -0.82]
intensity = 2.5
angle_deg = 3"
    fi
    cat <<TOML
[dataset]
name = "speed"
out = "out-$1"
cache = "cache-$1"
preview = false
[source.man]
gltf = "$man"
frames = { count = 4, fps = 24 }
$ground
[transform]
up = "y"
fit = { height = 2.4 }
center = "bbox"
[render]
resolution = [800, 800]
samples = 4
shading = "$shading"
$lit
[rig.hemi]
kind = "hemisphere"
[split.train]
rig = "hemi"
views = 16
[output.d]
writer = "dnerf"
TOML
}
for s in pbr alone unlit; do manifest $s > "$work/$s.toml"; done
for r in $(seq "$rounds"); do
    for s in pbr alone unlit; do
        rm -rf "$work/cache-$s" "$work/out-$s"
        t0=$(date +%s.%N)
        (cd "$work" && "$vvgen" build $s.toml > /dev/null 2>&1)
        t1=$(date +%s.%N)
        echo "vvgen $s: 64 images cold in $(echo "$t1 - $t0" | bc) s: $(echo "($t1 - $t0) * 1000 / 64" | bc) ms per image"
    done
done
for engine in eevee cycles; do
    for scene in pbr alone; do
        ground=()
        [ $scene = pbr ] && ground=(--plane 3,3,-1.2,0.5)
        "${run[@]}" -- --model "$man" --dataset "$work/out-$scene/speed_dnerf" \
            --out "$work/$engine-$scene" --sun 0.45,0.35,-0.82,2.5,3 --env "$map,0.6" "${ground[@]}" --samples 16 \
            --engine $engine --images train/0/0,train/1/0 2>&1 | grep -E "^rendered" | sed "s/^/$engine-16 $scene: /"
    done
done
