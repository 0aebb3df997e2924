#!/usr/bin/env bash
# Lit rendering against Blender 3.4 Cycles (issue 16's fidelity bar): CesiumMan and FlightHelmet on a ground
# plane under a sun and Blender's "sunset" map, the same cameras in both, Standard view transform, Cycles at
# 256 samples without denoising as the reference (its pixel filter Blender's default, Blackman-Harris 1.5 px), and
# vvgen with the same filter (FILTER=box compares vvgen's default instead). Prints silhouette IoU, PSNR, SSIM and
# shadow IoU per image (benches/lit_metrics.py). Blender is a peer, never a test dependency.
#
#   benches/lit_fidelity.sh [WORK_DIR]      (default /tmp/vvgen-lit-fidelity)
#
# Needs: blender (apt, 3.4), a python with numpy and Pillow as $PYTHON (default python3), FlightHelmet from
# ../shared/assets (or $FLIGHT_HELMET). Takes about 10 minutes on 2 cores, most of it Cycles.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
work=${1:-/tmp/vvgen-lit-fidelity}
py=${PYTHON:-python3}
helmet=${FLIGHT_HELMET:-$repo/../shared/assets/gltf/FlightHelmet/FlightHelmet.gltf}
samples=${CYCLES_SAMPLES:-256}
filter=${FILTER:-blackman-harris}
mkdir -p "$work"
(cd "$repo" && cargo build --release --quiet)
vvgen=$repo/target/release/vvgen
map=$repo/tests/data/hdri/sunset.exr
sun_dir="0.45,0.35,-0.82"; sun_strength=2.5; sun_angle=3; env_strength=0.6
plane_z=-1.0; grey=0.5

manifest() { # name model with_sun
    local sun=""
    if [ "$3" = 1 ]; then
        sun="[light.sun]
kind = \"sun\"
direction = [${sun_dir//,/, }]
intensity = $sun_strength
angle_deg = $sun_angle"
    fi
    cat <<TOML
[dataset]
name = "$1"
out = "out"
cache = "cache"
preview = false
[source.model]
gltf = "$2"
frames = { count = 1, fps = 24 }
[source.ground]
plane = { size = [3.0, 3.0], color = [$grey, $grey, $grey], z = $plane_z }
[transform]
up = "y"
fit = { height = 2.0 }
center = "bbox"
[render]
resolution = [400, 400]
samples = 4
filter = "$filter"
shading = "pbr"
passes = ["rgba", "depth"]
[environment]
map = "$map"
strength = $env_strength
$sun
[rig.hemi]
kind = "hemisphere"
numpy_seed = 0
[split.train]
rig = "hemi"
views = 3
[output.d]
writer = "dnerf"
TOML
}

for model in cesium helmet; do
    case $model in
        cesium) file=$repo/tests/data/gltf/CesiumMan/CesiumMan.glb ;;
        helmet) file=$helmet ;;
    esac
    for light in sun env; do
        dir=$work/$model-$light
        mkdir -p "$dir"
        manifest "$model-$light" "$file" "$([ $light = sun ] && echo 1 || echo 0)" > "$dir/m.toml"
        (cd "$dir" && "$vvgen" build m.toml > /dev/null)
        flags=()
        [ $light = env ] && flags+=(--no-sun)
        blender -b -P "$repo/benches/blender_lit.py" -- --model "$file" --dataset "$dir/out/$model-${light}_dnerf" \
            --out "$dir/cycles" --sun "$sun_dir,$sun_strength,$sun_angle" --env "$map,$env_strength" \
            --plane "3,3,$plane_z,$grey" --samples "$samples" "${flags[@]}" 2>&1 | grep -E "^rendered|Error" || true
    done
    echo "$model (vvgen 4 samples, $filter filter, vs Cycles $samples samples)"
    "$py" "$repo/benches/lit_metrics.py" "$work/$model-sun/out/$model-sun_dnerf" "$work/$model-env/out/$model-env_dnerf" \
        "$work/$model-sun/cycles" "$work/$model-env/cycles" --plane-z "$plane_z" \
        --sun "$sun_dir,$sun_strength" --grey "$grey"
done
