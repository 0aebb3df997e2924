#!/usr/bin/env bash
# RGB PSNR of the `dynerf` videos against the PNG frames they were encoded from, per image size, decoded as
# K-Planes decodes them (ffmpeg's swscale to rgb24, as PyAV's `format='rgb24'` does), beside the ceiling of
# 4:2:0 itself (the PNGs through yuv420p and back with no codec at all). Needs ffmpeg and numpy.
#
#   benches/video_psnr.sh [ASSET.glb ...]     (default: the shipped CesiumMan)
#
# Prints, per asset and size: the mean and worst per-camera PSNR over all frames, the worst single frame, and
# the 4:2:0 ceiling's mean. Whole images, background included (what a loader reads).
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
vvgen=${VVGEN:-$repo/target/release/vvgen}
[ -x "$vvgen" ] || (cd "$repo" && cargo build --release --quiet)
assets=("$@")
[ ${#assets[@]} -gt 0 ] || assets=("$repo/tests/data/gltf/CesiumMan/CesiumMan.glb")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

for asset in "${assets[@]}"; do
  for size in "64 64" "128 96" "256 256" "676 508"; do
    set -- $size
    dir="$work/$(basename "$asset" .glb)-$1x$2"
    mkdir -p "$dir"
    cat > "$dir/m.toml" <<TOML
[dataset]
name = "v"
out = "out"
[source.s]
gltf = "$(realpath "$asset")"
frames = { count = 24, fps = 24 }
[transform]
fit = "frame"
[render]
resolution = [$1, $2]
samples = 4
background = [0.9, 0.9, 0.9]
[rig.ff]
kind = "forward-facing"
[split.train]
rig = "ff"
views = 5
[split.test]
rig = "ff"
views = 1
[output.llff]
writer = "dynerf"
dir = "llff"
init_points = 0
TOML
    "$vvgen" build --quiet --no-preview "$dir/m.toml" >/dev/null 2>&1
    for mp4 in "$dir"/out/llff/cam*.mp4; do
      cam=$(basename "$mp4" .mp4)
      raw() { ffmpeg -loglevel error -i "$1" ${2:+-vf "$2"} -f rawvideo -pix_fmt rgb24 -y "$3"; }
      raw "$dir/out/llff/frames/$cam/%04d.png" "" "$dir/$cam.png.rgb"
      raw "$mp4" "" "$dir/$cam.mp4.rgb"
      raw "$dir/out/llff/frames/$cam/%04d.png" "format=yuv420p" "$dir/$cam.420.rgb"
    done
    /usr/bin/python3 - "$dir" "$(basename "$asset")" "$1" "$2" <<'PY'
import sys, glob
import numpy as np
d, name, w, h = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
def frames(path, width, height):
    return np.fromfile(path, np.uint8).reshape(-1, height, width, 3)[..., :h, :w, :].astype(np.float64)
def psnr(mse):
    return 10 * np.log10(255.0 ** 2 / np.maximum(mse, 1e-12))
# H.264 4:2:0 has even sizes only: the video's frames may be one pixel larger.
ew, eh = w + w % 2, h + h % 2
cams, worst_frame, ceiling = [], 99.0, []
for ref in sorted(glob.glob(f"{d}/cam*.png.rgb")):
    a = frames(ref, w, h)
    b = frames(ref.replace(".png.rgb", ".mp4.rgb"), ew, eh)
    c = frames(ref.replace(".png.rgb", ".420.rgb"), w, h)
    per = ((a - b) ** 2).mean(axis=(1, 2, 3))
    cams.append(psnr(per.mean()))
    worst_frame = min(worst_frame, psnr(per.max()))
    ceiling.append(psnr(((a - c) ** 2).mean()))
print(f"{name:16} {w:>4}x{h:<4} per camera {np.mean(cams):5.1f} dB mean, {min(cams):5.1f} worst; "
      f"worst frame {worst_frame:5.1f}; 4:2:0 alone {np.mean(ceiling):5.1f}")
PY
  done
done
