"""plyfile reading the scene bench's 3D Gaussian splatting file (`target/bench-data/gaussians_1m.ply`) as vvgen does:
positions, base colours (3DGS's SH2RGB, clamped, floored to bytes) and the Gaussians whose opacity reaches 1/255.
Same protocol as the scene bench: one untimed call, then the median of the timed ones.

    python benches/splat_peer.py [target/bench-data/gaussians_1m.ply] [runs]
"""
import importlib.metadata
import statistics
import sys
import time

import numpy as np
import plyfile

SH_C0 = 0.28209479177387814


def read(path):
    v = plyfile.PlyData.read(path)["vertex"]
    keep = 1.0 / (1.0 + np.exp(-v["opacity"].astype(np.float64))) >= 1.0 / 255.0
    xyz = np.stack([v["x"], v["y"], v["z"]], axis=-1)[keep]
    dc = np.stack([v["f_dc_0"], v["f_dc_1"], v["f_dc_2"]], axis=-1)[keep].astype(np.float64)
    rgb = np.floor(np.clip(0.5 + SH_C0 * dc, 0.0, 1.0) * 255.0).astype(np.uint8)
    return xyz, rgb


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else "target/bench-data/gaussians_1m.ply"
    runs = int(sys.argv[2]) if len(sys.argv) > 2 else 5
    xyz, _ = read(path)
    times = []
    for _ in range(runs):
        t = time.perf_counter()
        read(path)
        times.append(time.perf_counter() - t)
    print(f"plyfile {importlib.metadata.version('plyfile')}: {len(xyz)} Gaussians kept, "
          f"read as points in {statistics.median(times) * 1e3:8.3f} ms (median of {runs})")


if __name__ == "__main__":
    main()
