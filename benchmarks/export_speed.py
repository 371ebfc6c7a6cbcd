"""Speed of the exports: prints figures, asserts nothing.

    python benchmarks/export_speed.py

Target (issue 16): an export of a 30 × 10 frequency × amplitude grid in every format ≤ 1 s.
"""

import time

import numpy as np

from core import PAPER_B
from core.io.export import export

FREQS = np.geomspace(1, 100, 30)
AMPS = np.geomspace(1e-6, 1e-3, 10)


def main():
    total = 0.0
    for fmt, as_json in (("table", False), ("table", True), ("nastran", False), ("adams", False)):
        times = []
        for _ in range(5):
            t0 = time.perf_counter()
            text = export(PAPER_B, fmt, FREQS, AMPS, as_json=as_json)
            times.append(time.perf_counter() - t0)
        best = min(times)
        total += best
        name = f"{fmt}{' (JSON)' if as_json else ''}"
        print(f"{name:<14} 30 × 10 grid, 4 directions: {best * 1e3:6.1f} ms, {len(text) / 1e3:7.1f} kB "
              f"(target ≤ 1000 ms, ratio {best:.3f})")
    print(f"every format together: {total * 1e3:.0f} ms (target ≤ 1000 ms, ratio {total:.2f})")


if __name__ == "__main__":
    main()
