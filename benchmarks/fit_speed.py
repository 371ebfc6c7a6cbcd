"""Speed of parameter identification (issue 4): prints figures, asserts nothing.

    python benchmarks/fit_speed.py

Target: a global five-parameter fit of 150 points in ≤ 1 s on this machine (8 starting points,
the first a deliberately poor guess). The thesis' two-step procedure is timed beside it.
"""

import statistics
import time

import numpy as np

from core import PAPER_B, TABLE_1, stiffness_points
from core.bushing import loop_force
from core.data import MeasuredLoop, MeasuredStiffness
from core.fit import fit_global, fit_two_step


def synthetic(design, freqs, amps, seed):
    rng = np.random.default_rng(seed)
    ff, xx = np.meshgrid(freqs, amps)
    k = stiffness_points(design, ff.ravel(), xx.ravel())
    return MeasuredStiffness(ff.ravel(), xx.ravel(), k * (1 + 0.005 * (rng.standard_normal(k.size) + 1j * rng.standard_normal(k.size))))


def timed(fn, repeat=5):
    out = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        result = fn()
        out.append(time.perf_counter() - t0)
    return statistics.median(out), result


def main():
    cases = {
        "Paper B, axial": (PAPER_B, np.linspace(1, 100, 30), [0.013e-3, 0.04e-3, 0.1e-3, 0.17e-3, 0.35e-3]),
        "Table 1, torsion": (TABLE_1, np.linspace(10, 100, 30), [1.74e-5, 1.74e-4, 1.74e-3, 1.74e-2, 1.74e-1]),
    }
    for name, (design, freqs, amps) in cases.items():
        data = synthetic(design, freqs, amps, seed=1)
        start = design.replace(shear_modulus=design.material.shear_modulus * 0.6,
                               fractional_coefficient=design.material.fractional_coefficient * 1.7,
                               fractional_order=0.4 if design.material.fractional_order < 0.3 else 0.2,
                               friction_stress_max=design.material.friction_stress_max * 2,
                               friction_strain_half=design.material.friction_strain_half * 0.25)
        seconds, r = timed(lambda: fit_global(start, data))  # noqa: B023
        print(f"{name:<18} global fit, {len(data)} points, 8 starts: {seconds * 1e3:7.0f} ms  "
              f"(target ≤ 1000 ms)  gap {r.gap:.4f}")
    t = np.arange(400) / 200 / 0.1
    theta = 2 * np.pi * 0.1 * t
    rng = np.random.default_rng(2)
    force = sum(loop_force(PAPER_B, 0.1, 1e-3, theta))
    loop = MeasuredLoop(t, 1e-3 * np.sin(theta), force + 15 * rng.standard_normal(t.size))
    sweep = synthetic(PAPER_B, np.arange(1.0, 101.0), [0.1e-3], seed=3)
    start = PAPER_B.replace(shear_modulus=1.5e6, fractional_coefficient=1e6, fractional_order=0.4,
                            friction_stress_max=4e4, friction_strain_half=1e-3)
    seconds, r = timed(lambda: fit_two_step(start, loop, sweep))
    print(f"{'Paper B':<18} two-step (loop + 100-point sweep): {seconds * 1e3:7.0f} ms  gap {r.gap:.4f}")


if __name__ == "__main__":
    main()
