#!/usr/bin/env bash
# Runs a vvgen benchmark and the peers' timings of the same work back to back, so ratios come from one run.
#   benches/peers.sh points VENV BENCH_PEERS   # vs Open3D / trimesh (sampling, voxel downsampling)
#   benches/peers.sh render VENV BENCH_PEERS   # vs pyrender + OSMesa (100k triangles, 800k points)
#   benches/peers.sh scene VENV BENCH_PEERS    # vs plyfile / Open3D / trimesh (reading the same 1M-point PLY)
# VENV: a Python venv with numpy, open3d, trimesh, plyfile, pyrender, PyOpenGL (kept outside the repo);
# BENCH_PEERS: the folder holding bench_python.py (e.g. ../shared/bench-peers).
set -euo pipefail
what=$1 venv=$2 peers=$3
data=target/bench-data
mkdir -p "$data"
echo "== vvgen ($what) =="
cargo bench --quiet --bench "$what" -- "$data"
echo "== peers =="
case $what in
  points)
    "$venv/bin/python" "$peers/bench_python.py" sample --runs 5
    "$venv/bin/python" "$peers/bench_python.py" voxel --cloud "$data/points_1m.ply" --runs 5 ;;
  scene)
    "$venv/bin/python" "$peers/bench_python.py" ply_io --cloud "$data/pc_1m_bin.ply" --tmp "$data/peer-ply" --runs 7 ;;
  render)
    PYOPENGL_PLATFORM=osmesa "$venv/bin/python" "$peers/bench_python.py" pyrender \
      --pc100k "$data/pc_100k.ply" --pc800k "$data/pc_800k.ply" --runs 3 --views 20 ;;
esac
