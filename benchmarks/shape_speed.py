"""Speed of the shape factors in every direction: prints figures, asserts nothing.

    python benchmarks/shape_speed.py

Targets (issue 15): a finite-length shape-factor lookup ≤ 1 ms; a 100 × 100 stiffness map
(frequency × amplitude) in any mode within 2× the axial map's time. The table's generation time
and accuracy are printed by tools/shape_table.py.
"""

import statistics
import time

import numpy as np

from core import PAPER_B
from core.bushing import stiffness_points
from core.shape import finite_shape_factor, table


def best_of(fn, repeat=7):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times), statistics.median(times)


def main():
    rng = np.random.default_rng(0)
    t = table()
    q = np.exp(rng.uniform(np.log(t.radius_ratio[0]), np.log(t.radius_ratio[-1]), 1000))
    lam = np.exp(rng.uniform(np.log(t.length_ratio[0]), np.log(t.length_ratio[-1]), 1000))
    finite_shape_factor(1.0, 2.0, 3.0, "radial")  # the splines are built once per process
    for mode in ("axial", "radial", "conical"):
        t0 = time.perf_counter()
        for qi, li in zip(q, lam):
            finite_shape_factor(1.0, qi, li * (qi - 1.0), mode)
        per = (time.perf_counter() - t0) / q.size
        print(f"finite-length S lookup, {mode:<8}: {per * 1e6:6.1f} µs per geometry (target ≤ 1000 µs, "
              f"ratio {per / 1e-3:.3f})")

    f = np.geomspace(1, 100, 100)
    base = None
    for mode, x in (("axial", np.geomspace(1e-6, 1e-3, 100)), ("torsion", np.geomspace(1e-5, 1e-1, 100)),
                    ("radial", np.geomspace(1e-6, 1e-3, 100)), ("conical", np.geomspace(1e-5, 1e-1, 100))):
        design = PAPER_B.replace(mode=mode)
        best, median = best_of(lambda d=design, xx=x: stiffness_points(d, f[None, :], xx[:, None]))
        base = base or median
        print(f"100 × 100 map, {mode:<8} ({design.shape_kind} S): median {median * 1e3:6.2f} ms, best "
              f"{best * 1e3:6.2f} ms; {median / base:4.2f}× the axial map (target ≤ 2×)")


if __name__ == "__main__":
    main()
