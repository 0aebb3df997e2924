#!/usr/bin/env bash
# Whether two vvgen binaries render the same bytes: the check a speed change that should not move a pixel owes
# (the render bench keeps no images). Builds nine small manifests with each binary, cold, and compares the
# datasets file by file (`vvgen/dataset.json` aside: it records the manifest's digest, and the manifests differ
# in their output paths). The manifests cover the renderer's paths: unlit textured CesiumMan at 4 and 9 samples
# with normal and mask passes (deferred texturing, resolve per sample grid), Lambert shading with vertex colours
# (shaded per sample), a textured box at 1 sample, and lit (`pbr`) CesiumMan on a ground plane under a sun and
# an HDR map with the albedo pass; and a vox10 point-cloud sequence drawn as cubes (a voxel's edge, and larger at
# their true size), 1-px squares and disks.
#
#   benches/same_bytes.sh OLD_VVGEN NEW_VVGEN [WORK_DIR]
#
# Prints one line per manifest ("same" or "DIFFERS") and exits 1 when any differs.
set -euo pipefail
old=$1 new=$2
work=${3:-/tmp/vvgen-same-bytes}
repo=$(cd "$(dirname "$0")/.." && pwd)
gltf=$repo/tests/data/gltf
man="gltf = \"$gltf/CesiumMan/CesiumMan.glb\"
frames = { count = 2, fps = 24 }"
rm -rf "$work" && mkdir -p "$work"

manifest() { # name source render-settings
    cat <<EOF
[dataset]
name = "$1"
out = "out"
cache = "cache"
preview = false
[source.man]
$2
[transform]
up = "y"
fit = { height = 2.4 }
center = "bbox"
[render]
resolution = [400, 400]
$3
[rig.hemi]
kind = "hemisphere"
[split.train]
rig = "hemi"
views = 6
time = "all"
[output.d]
writer = "dnerf"
EOF
}

write_manifests() { # dir
    manifest unlit "$man" 'samples = 4
passes = ["rgba", "depth", "normal", "mask"]' > "$1/unlit.toml"
    manifest unlit9 "$man" 'samples = 9
passes = ["rgba", "depth"]' > "$1/unlit9.toml"
    manifest lambert "gltf = \"$gltf/VertexColorTest/VertexColorTest.gltf\"
frames = { count = 1, fps = 24 }" 'samples = 4
shading = "lambert"
passes = ["rgba", "depth", "normal"]' > "$1/lambert.toml"
    manifest boxtex "gltf = \"$gltf/BoxTextured/BoxTextured.glb\"
frames = { count = 1, fps = 24 }" 'samples = 1
passes = ["rgba", "depth"]' > "$1/boxtex.toml"
    manifest pbr "$man
[source.ground]
plane = { size = [3.0, 3.0], color = [0.5, 0.5, 0.5], z = -1.2 }" "samples = 4
shading = \"pbr\"
passes = [\"rgba\", \"depth\", \"normal\", \"albedo\"]
[environment]
map = \"$repo/tests/data/hdri/sunset.exr\"
strength = 0.6
[light.sun]
kind = \"sun\"
direction = [0.45, 0.35, -0.82]
intensity = 2.5
angle_deg = 3" > "$1/pbr.toml"
    local seq="ply_sequence = \"$repo/tests/data/seq/torus_vox10_{frame:04}.ply\"
frames = { start = 1000, end = 1001, fps = 30 }"
    manifest cubes "$seq" 'samples = 4
splat = { shape = "cube" }
passes = ["rgba", "depth", "normal"]' > "$1/cubes.toml"
    manifest solids "$seq" 'samples = 1
splat = { shape = "cube", size = 0.02, min_px = 0 }
passes = ["rgba", "depth", "normal"]' > "$1/solids.toml"
    manifest squares "$seq" 'samples = 4
splat = { shape = "square", size_px = 1 }
passes = ["rgba", "depth"]' > "$1/squares.toml"
    manifest disks "$seq" 'samples = 4
splat = { shape = "disk", size = 0.015 }
passes = ["rgba", "depth"]' > "$1/disks.toml"
}

status=0
for side in old new; do
    mkdir -p "$work/$side"
    write_manifests "$work/$side"
done
for m in unlit unlit9 lambert boxtex pbr cubes solids squares disks; do
    for side in old new; do
        bin=$old
        [ "$side" = new ] && bin=$new
        # Each manifest in its own folder: out and cache are relative to it.
        mkdir -p "$work/$side/$m"
        mv "$work/$side/$m.toml" "$work/$side/$m/"
        "$bin" build "$work/$side/$m/$m.toml" -q
    done
    if diff -r -q -x dataset.json "$work/old/$m/out" "$work/new/$m/out" > /dev/null; then
        echo "$m: same ($(find "$work/old/$m/out" -name '*.png' | wc -l) PNGs)"
    else
        echo "$m: DIFFERS"
        diff -r -q -x dataset.json "$work/old/$m/out" "$work/new/$m/out" | head -5 || true
        status=1
    fi
done
exit $status
