#!/usr/bin/env bash
# Lit rendering against Blender 4.5 LTS Cycles (issue 48's bar): CesiumMan and FlightHelmet on a 6 × 6 ground of
# albedo 0.8 under a sun along (−1, 1, −2) of 1 W/m² and 0.5° and Blender's "sunset" map at 0.4, three cameras at
# 400², the same in both; Standard view transform, Cycles at 512 samples without denoising, two seeds averaged in
# linear light (one seed's noise alone costs SSIM 0.05), its pixel filter Blender's default (Blackman-Harris
# 1.5 px), and vvgen with the same filter (FILTER=box compares vvgen's default instead). Prints silhouette IoU,
# PSNR, SSIM and shadow IoU per image, their mean and worst (benches/lit_metrics.py). Blender is a peer, never a
# test dependency.
#
#   benches/lit_fidelity.sh [WORK_DIR]      (default /tmp/vvgen-lit-fidelity)
#
# Needs: $BPY, a Python with `bpy==4.5.*` (default /tmp/bpy45/bin/python; BPY=blender runs Debian's Blender 3.4
# instead), a python with numpy and Pillow as $PYTHON (default python3), FlightHelmet from ../shared/assets (or
# $FLIGHT_HELMET). SEEDS (default "0 1"), CYCLES_SAMPLES (512), the scene's settings below. About 20 minutes on 2
# cores, nearly all of it Cycles; MODELS="obj" OBJ=path/to/model.obj measures an OBJ (its MTL materials through
# Blender's OBJ importer) instead, FIT='"frame"' frames a subject of any shape; REUSE_CYCLES=1 measures a new vvgen against an earlier run's renders; UNDER=1
# views the subjects from below instead (use another WORK_DIR).
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
work=${1:-/tmp/vvgen-lit-fidelity}
py=${PYTHON:-python3}
helmet=${FLIGHT_HELMET:-$repo/../shared/assets/gltf/FlightHelmet/FlightHelmet.gltf}
samples=${CYCLES_SAMPLES:-512}
seeds=${SEEDS:-0 1}
bpy=${BPY:-/tmp/bpy45/bin/python}
filter=${FILTER:-blackman-harris}
mkdir -p "$work"
(cd "$repo" && cargo build --release --quiet)
vvgen=$repo/target/release/vvgen
map=$repo/tests/data/hdri/sunset.exr
sun_dir=${SUN_DIR:--1,1,-2}; sun_strength=${SUN_STRENGTH:-1}; sun_angle=${SUN_ANGLE:-0.5}
env_strength=${ENV_STRENGTH:-0.4}; plane_z=-1.0; grey=${GREY:-0.8}; plane_size=${PLANE_SIZE:-6.0}

# The cameras: the hemisphere views of `numpy_seed = 0`, or with UNDER=1 two views from 10° below the subject's
# middle, one on its shadowed side (azimuth 45°, facing the sun's shadow) and one opposite.
if [ "${UNDER:-0}" = 1 ]; then
    rig='[rig.low]
kind = "orbit"
elevation_deg = -10
start_azimuth_deg = 45
[split.train]
rig = "low"
views = 2'
else
    rig='[rig.hemi]
kind = "hemisphere"
numpy_seed = 0
[split.train]
rig = "hemi"
views = 3'
fi

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
$( [[ "$2" == *.obj ]] && echo "mesh = \"$2\"" || printf 'gltf = "%s"\nframes = { count = 1, fps = 24 }' "$2")
[source.ground]
plane = { size = [$plane_size, $plane_size], color = [$grey, $grey, $grey], z = $plane_z }
[transform]
up = "y"
fit = ${FIT:-{ height = 2.0 \}}
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
$rig
[output.d]
writer = "dnerf"
TOML
}

for model in ${MODELS:-cesium helmet}; do
    case $model in
        cesium) file=$repo/tests/data/gltf/CesiumMan/CesiumMan.glb ;;
        helmet) file=$helmet ;;
        obj) file=$OBJ ;;
    esac
    for light in sun env; do
        dir=$work/$model-$light
        mkdir -p "$dir"
        manifest "$model-$light" "$file" "$([ $light = sun ] && echo 1 || echo 0)" > "$dir/m.toml"
        (cd "$dir" && "$vvgen" build m.toml > /dev/null)
        flags=()
        [ $light = env ] && flags+=(--no-sun)
        for seed in $seeds; do
            # REUSE_CYCLES=1 keeps renders of an earlier run (the reference does not change with vvgen).
            if [ "${REUSE_CYCLES:-0}" = 1 ] && [ -d "$dir/cycles-$seed" ]; then continue; fi
            run=("$bpy" "$repo/benches/blender_lit.py")
            [ "$bpy" = blender ] && run=(blender -b -P "$repo/benches/blender_lit.py")
            "${run[@]}" -- --model "$file" --dataset "$dir/out/$model-${light}_dnerf" \
                --out "$dir/cycles-$seed" --sun="$sun_dir,$sun_strength,$sun_angle" --env "$map,$env_strength" \
                --plane "$plane_size,$plane_size,$plane_z,$grey" --samples "$samples" --seed "$seed" "${flags[@]}" \
                2>&1 | grep -E "^rendered|Error" || true
        done
    done
    refs() { local out=""; for seed in $seeds; do out="$out${out:+,}$work/$model-$1/cycles-$seed"; done; echo "$out"; }
    version=$("$bpy" -c "import bpy; print(bpy.app.version_string)" 2>/dev/null | tail -1 || blender --version | head -1)
    echo "$model (vvgen 4 samples, $filter filter, vs Cycles $version, $samples samples, seeds $seeds averaged)"
    "$py" "$repo/benches/lit_metrics.py" "$work/$model-sun/out/$model-sun_dnerf" "$work/$model-env/out/$model-env_dnerf" \
        "$(refs sun)" "$(refs env)" --plane-z="$plane_z" --sun="$sun_dir,$sun_strength" --grey "$grey"
done
