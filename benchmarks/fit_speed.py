"""Speed of parameter identification: prints figures, asserts nothing.

    python benchmarks/fit_speed.py

Target: a global five-parameter fit of 150 points in ≤ 1 s on this machine (8 starting points,
the first a deliberately poor guess). The thesis' two-step procedure is timed beside it.
"""

import statistics
import time

import numpy as np

from core import PAPER_B, TABLE_1
from core.data import MeasuredStiffness
from core.identify.fit import fit_global, fit_two_step
from core.io.measured import combined
from core.synthetic import synthetic_loop, synthetic_stiffness


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
        data = synthetic_stiffness(design, freqs, amps, seed=1)
        start = design.replace(shear_modulus=design.material.shear_modulus * 0.6,
                               fractional_coefficient=design.material.fractional_coefficient * 1.7,
                               fractional_order=0.4 if design.material.fractional_order < 0.3 else 0.2,
                               friction_stress_max=design.material.friction_stress_max * 2,
                               friction_strain_half=design.material.friction_strain_half * 0.25)
        seconds, r = timed(lambda: fit_global(start, data))  # noqa: B023
        print(f"{name:<18} global fit, {len(data)} points, 8 starts: {seconds * 1e3:7.0f} ms  "
              f"(target ≤ 1000 ms)  gap {r.gap:.4f}")
    loop = synthetic_loop(PAPER_B, 0.1, 1e-3, seed=2)  # 2 periods of 200 samples
    sweep = synthetic_stiffness(PAPER_B, np.arange(1.0, 101.0), [0.1e-3], seed=3)
    start = PAPER_B.replace(shear_modulus=1.5e6, fractional_coefficient=1e6, fractional_order=0.4,
                            friction_stress_max=4e4, friction_strain_half=1e-3)
    seconds, r = timed(lambda: fit_two_step(start, loop, sweep))
    print(f"{'Paper B':<18} two-step (loop + 100-point sweep): {seconds * 1e3:7.0f} ms  gap {r.gap:.4f}")

    # issue 16: one material from four directions, 150 points each (target ≤ 2 s)
    amps = {"axial": [1.3e-5, 4e-5, 1e-4, 1.7e-4, 3.5e-4], "radial": [2e-6, 6e-6, 2e-5, 4e-5, 6e-5],
            "torsion": [1e-4, 3e-4, 1e-3, 3e-3, 1e-2], "conical": [2e-4, 6e-4, 2e-3, 6e-3, 2e-2]}
    parts = []
    for i, (mode, a) in enumerate(amps.items()):
        d = synthetic_stiffness(PAPER_B.in_mode(mode), np.linspace(5, 155, 30), a, seed=10 + i)
        parts.append(MeasuredStiffness(d.frequency_hz, d.amplitude, d.stiffness, None, np.full(len(d), mode, dtype=object)))
    joint = combined(parts, "axial")
    seconds, r = timed(lambda: fit_global(start, joint), repeat=3)
    print(f"{'Paper B':<18} joint fit, 4 modes × 150 points (with profiles): {seconds * 1e3:7.0f} ms "
          f"(target ≤ 2000 ms, ratio {seconds / 2:.2f})  gaps {', '.join(f'{k} {v:.4f}' for k, v in r.gap_by_mode.items())}")


if __name__ == "__main__":
    main()
