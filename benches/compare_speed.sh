#!/usr/bin/env bash
# `vvgen compare` against MPEG's pc_error on one pair of 1M-point frames, in the same run, alternated: CesiumMan
# sampled by vvgen (1M surface points with normals and colours), and a copy with 30 % of the points moved by a
# cell and colours shifted (benches/pc_error_reference.py --degrade). Both compute D1, D2 and colour PSNR; the
# figures are printed side by side and must agree within 0.01 dB.
#
#   benches/compare_speed.sh [VVGEN] [PC_ERROR] [WORK_DIR]
#   (PC_ERROR: benches/pc_error_build.sh builds it; python3 with numpy makes the copy)
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
vvgen=${1:-$repo/target/release/vvgen}
pc_error=${2:-/tmp/pcerr/pc_error}
work=${3:-/tmp/vvgen-compare-speed}
rm -rf "$work" && mkdir -p "$work" && cd "$work"
cat > m.toml <<TOML
[dataset]
name = "big"
out = "out"
cache = "cache"
[source.man]
gltf = "$repo/tests/data/gltf/CesiumMan/CesiumMan.glb"
frames = { count = 1, fps = 24 }
[transform]
up = "y"
fit = { height = 2.4 }
center = "bbox"
[output.big]
writer = "ply-sequence"
points = 1000000
dir = "big"
TOML
"$vvgen" build m.toml -q
python3 "$repo/benches/pc_error_reference.py" --degrade out/big/big_0000.ply copies
for run in 1 2; do
    /usr/bin/time -f "pc_error (1 thread, its default): %e s, %M kB" "$pc_error" -a out/big/big_0000.ply \
        -b copies/noise.ply -c 1 > pc_error.txt
    /usr/bin/time -f "pc_error --nbThreads=2: %e s, %M kB" "$pc_error" -a out/big/big_0000.ply \
        -b copies/noise.ply -c 1 --nbThreads=2 > /dev/null
    /usr/bin/time -f "vvgen compare: %e s, %M kB" "$vvgen" compare out/big/big_0000.ply copies/noise.ply > vvgen.txt
done
grep -E "mseF,PSNR|c\[[012]\],PSNRF" pc_error.txt
cat vvgen.txt
