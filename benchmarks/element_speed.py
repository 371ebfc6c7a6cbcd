"""µs per step of the Python time-domain element (core.element), six channels of core.PAPER_B.

A harmonic drive at 10 Hz, ε̂ = 1e-3 in every channel, 1000 steps a period, after one period of
warm-up: CPU time (time.process_time, the least of 5 runs) per committed step, and the Newton iterations of the
series solve. The aim (issue 30) is ≤ 30 µs per step with 3 slices. The layers' law runs on
Python floats (NumPy's cost per call, about 1 µs, would dominate arrays of 6–30 layers): a
step is a handful of array operations (the exponentials' states, the inputs and outputs) and
O(layers) float arithmetic, so the cost grows with the layers of the sliced channels (axial
and torsion) and with the series solve's evaluations (about 2 a step).

    PYTHONPATH=$PWD python benchmarks/element_speed.py
"""

from __future__ import annotations

import time
import warnings

import numpy as np

from core import PAPER_B
from core.element import CHANNEL_MODES, CHANNELS, Element, coefficients

STEPS = 1000
REPEATS = 5
F_HZ = 10.0


def per_step(slices: int, steps: int = 3 * STEPS) -> tuple[float, float]:
    """(µs of CPU per committed step, mean Newton iterations) over ``steps`` steps."""
    el = Element(coefficients(PAPER_B, slices, (0.1, F_HZ * STEPS / 400.0)))
    amp = np.array([PAPER_B.in_mode(CHANNEL_MODES[c]).drive(1e-3) for c in CHANNELS])
    h = 1.0 / (F_HZ * STEPS)
    drive = amp * np.sin(2 * np.pi * np.arange(1, steps + STEPS + 1) / STEPS)[:, None]
    for x in drive[:STEPS]:
        el.commit(x, h)
    best, iterations = float("inf"), 0
    saved = el.state()
    for _ in range(REPEATS):  # the least CPU of a few runs: other processes share the machine
        el.restore(saved)
        iterations = 0
        start = time.process_time()
        for x in drive[STEPS:]:
            el.commit(x, h)
            iterations += el.iterations
        best = min(best, time.process_time() - start)
    return 1e6 * best / steps, iterations / steps


def main() -> None:
    warnings.simplefilter("error")
    print("Python element, six channels (CPU µs per committed step; the machine may be shared)")
    for slices in (1, 3, 10):
        us, its = per_step(slices)
        print(f"  {slices} slice{'s' if slices > 1 else ' '}: {us:7.1f} µs/step   "
              f"({its:.1f} Newton iterations per step; aim ≤ 30 µs)")


if __name__ == "__main__":
    main()
