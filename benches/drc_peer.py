"""DracoPy's decode (Google's C++ Draco decoder, to NumPy arrays) of .drc files: the peer of
`cargo bench --bench drc_decode`, same protocol (one untimed call, then the median of 11), in the same run.
Needs a Python with `pip install DracoPy` (outside the repository).

    python benches/drc_peer.py FILE.drc...
"""
import sys
import time

import DracoPy

for path in sys.argv[1:]:
    data = open(path, "rb").read()
    DracoPy.decode(data)
    times = []
    for _ in range(11):
        t = time.perf_counter()
        DracoPy.decode(data)
        times.append(time.perf_counter() - t)
    times.sort()
    print(f"DracoPy {path}: {times[5] * 1e3:.2f} ms")
