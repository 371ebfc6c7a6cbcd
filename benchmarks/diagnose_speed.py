"""Speed of the discrepancy workflow: prints figures, asserts nothing.

    python benchmarks/diagnose_speed.py

Target: a full diagnosis of 150 points against the whole effect library in ≤ 5 s on this
machine: baseline fit (8 starts), every candidate fitted at every step, pairs where needed, and
the held-out check (leave one amplitude out, both models refitted per fold).
"""

import statistics
import time

import numpy as np

from core import PAPER_B, TABLE_1
from core.data import MeasuredStiffness
from core.identify.diagnose import diagnose
from core.io.measured import combined
from core.synthetic import synthetic_stiffness

TARGET_S = 5.0
F = np.linspace(1, 100, 30)
A_B = [0.013e-3, 0.04e-3, 0.1e-3, 0.17e-3, 0.35e-3]
A_T = list(np.geomspace(1e-4, 1e-1, 5))

CASES = {
    "nothing missing": (PAPER_B, {}, ("elastic", "fractional", "friction"), F, A_B),
    "friction missing (teaching)": (PAPER_B, {}, ("elastic", "fractional"), F, A_B),
    "inertia hidden": (PAPER_B, {"inertia": {"mass": 0.5}}, ("elastic", "fractional", "friction"), F, A_B),
    "two hidden (inertia + rate)": (
        PAPER_B, {"inertia": {"mass": 0.5}, "rate_amplitude_coupling": {"rate_exponent": 0.05}},
        ("elastic", "fractional", "friction"), F, A_B),
    "non-uniform strain, torsion": (TABLE_1.replace(outer_radius=0.016), {"nonuniform_strain": {}},
                                    ("elastic", "fractional", "friction"), np.linspace(10, 100, 30), A_T),
    "wave effects, 10 Hz–1 kHz": (PAPER_B, {"wave_effects": {"density": 1150.0}},
                                  ("elastic", "fractional", "friction"), np.geomspace(10, 1000, 30), A_B),
}


def main():
    print(f"full diagnosis, 150 points, whole library (target ≤ {TARGET_S:.0f} s); median of 3 runs")
    worst = 0.0
    for name, (design, effects, baseline, freqs, amps) in CASES.items():
        data = synthetic_stiffness(design.replace(effects=effects), freqs, amps, noise=0.005, seed=7)
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            result = diagnose(design, data, baseline=baseline)
            times.append(time.perf_counter() - t0)
        seconds = statistics.median(times)
        worst = max(worst, seconds)
        added = ", ".join(result.added) or "nothing"
        print(f"  {name:<30} {seconds:6.2f} s  ({seconds / TARGET_S:4.0%} of target)  added: {added}; "
              f"gap {result.baseline.gap:.4f} -> {result.final.gap:.4f}")
    # data of two modes, 150 points each, one compound; the axial rig carries a fixture mass
    parts = []
    for mode, amps, effects in (("axial", A_B, {"inertia": {"mass": 0.5}}), ("torsion", A_T, {})):
        d = synthetic_stiffness(PAPER_B.in_mode(mode).replace(effects=effects), F, amps, noise=0.005, seed=7)
        parts.append(MeasuredStiffness(d.frequency_hz, d.amplitude, d.stiffness, None, np.full(len(d), mode, dtype=object)))
    data = combined(parts, "axial")
    times = []
    for _ in range(3):
        t0 = time.perf_counter()
        result = diagnose(PAPER_B, data)
        times.append(time.perf_counter() - t0)
    seconds = statistics.median(times)
    worst = max(worst, seconds)
    where = ", ".join(f"{s.effect} on {s.mode or 'every mode'}" for s in result.steps) or "nothing"
    print(f"  {'two modes, 2 × 150 points':<30} {seconds:6.2f} s  ({seconds / TARGET_S:4.0%} of target)  added: "
          f"{where}; modes disagree: {result.modes_disagree}")
    print(f"slowest: {worst:.2f} s, ratio to target {worst / TARGET_S:.2f}")


if __name__ == "__main__":
    main()
