"""Speed of the what-ifs: prints figures and ratios to the targets, asserts nothing.

    python benchmarks/whatif_speed.py

Targets (issue "Supplier what-ifs"): a tolerance band of 500 samples over the explorer's sweeps
≤ 300 ms; the sensitivities at the operating point ≤ 50 ms; a target-driven design ≤ 2 s.
Median of 5 runs each (3 for the designs), on the Paper B bushing at 10 Hz and 0.1 mm.
"""

import statistics
import time

import numpy as np

from app import curves
from core import PAPER_B
from core.bushing import stiffness_points
from core.io.targets import problem_from_dict
from core.whatif.sensitivity import elasticities
from core.whatif.target import solve
from core.whatif.tolerance import Tolerances, _sample_factors, band

TOL = Tolerances({"shear_modulus": 0.10, "friction_stress_max": 0.15, "fractional_order": 0.05},
                 {"length": 0.0005}, samples=500, seed=0)


def median_ms(fn, runs=5):
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return 1e3 * statistics.median(times)


def line(what, ms, target_ms):
    print(f"  {what:<62} {ms:8.1f} ms  (target ≤ {target_ms:g} ms, ratio {ms / target_ms:.2f})")


def main():
    f = np.linspace(1, 100, 120)
    x = curves.amplitude_grid(PAPER_B, 120)
    print("tolerance bands, 500 samples (µ ±10 %, σ_fmax ±15 %, α ±5 %, L ±0.5 mm)")
    def fresh(fn):  # nothing kept from the run before (the sampled geometries' factors, the bands)
        def run():
            _sample_factors.cache_clear()
            curves.operating_bands.cache_clear()
            curves.card_bands.cache_clear()
            return fn()
        return run

    line("the explorer's operating curves (120 f + 120 amplitudes + 1)",
         median_ms(fresh(lambda: curves.operating_bands(PAPER_B, 10.0, 0.1, (1.0, 100.0), TOL))), 300)
    amps = curves.sweep_amplitudes(PAPER_B) * 1e-3
    grid_f = np.concatenate([np.repeat(f[None, :], amps.size, 0).ravel(), np.repeat([1.0, 10.0, 100.0], x.size)])
    grid_x = np.concatenate([np.repeat(amps, f.size), np.tile(x * 1e-3, 3)])
    line(f"every sweep curve of the explorer ({grid_f.size} points)",
         median_ms(fresh(lambda: band(PAPER_B, grid_f, grid_x, TOL))), 300)
    line("the card: 4 directions × 60 amplitudes",
         median_ms(fresh(lambda: curves.card_bands(PAPER_B, 10.0, TOL))), 300)
    from app.main import App

    app = App()
    app.state.tolerance_pct = {"shear_modulus": 10.0, "friction_stress_max": 15.0, "fractional_order": 5.0}
    app.state.band_on = True
    plain = App()
    steps = iter(range(1, 1000))

    def change(explorer, what):  # a new value each time: nothing comes from a cache
        value = next(steps)
        if what == "design":
            explorer.state.shear_modulus_mpa = 2.4 + 0.001 * value
        else:
            explorer.state.amplitude = 0.1 + 0.0001 * value

    for what in ("design", "amplitude"):
        line(f"the explorer's update after {'a design' if what == 'design' else 'an amplitude'} change, bands on",
             median_ms(lambda what=what: change(app, what)), 300)
        line(f"the explorer's update after {'a design' if what == 'design' else 'an amplitude'} change, bands off",
             median_ms(lambda what=what: change(plain, what)), 300)
    b = band(PAPER_B, f, 1e-4, TOL)
    print(f"  check: at 10 Hz the Monte Carlo's 1σ of |K| is {100 * b.std_magnitude[9] / b.nominal_magnitude[9]:.2f} %, "
          f"first order {100 * b.first_order_magnitude[9] / b.nominal_magnitude[9]:.2f} %")

    print("sensitivities at the operating point (8 parameters, central differences)")
    line("elasticities of |K| and the loss factor", median_ms(lambda: elasticities(PAPER_B, 10.0, 1e-4)), 50)

    print("designs from targets (median of 3)")
    known = PAPER_B.replace(inner_radius=0.015, outer_radius=0.030, length=0.070)
    cases = {
        "|K| = 4 kN/mm, η ≥ 0.12, b ≤ 40 mm, L ≤ 100 mm": {
            "targets": [{"mode": "axial", "frequency_hz": 10, "amplitude": 1e-4, "magnitude": 4e6},
                        {"mode": "axial", "frequency_hz": 10, "amplitude": 1e-4, "loss_factor": {"min": 0.12}}],
            "limits": {"outer_radius": {"max": 0.040}, "length": {"max": 0.100}}},
        "a known design from its axial, torsion, radial |K|": {
            "targets": [{"mode": m, "frequency_hz": 10, "amplitude": a,
                         "magnitude": abs(complex(stiffness_points(known.in_mode(m), 10.0, a)))}
                        for m, a in (("axial", 1e-4), ("torsion", 1e-2), ("radial", 1e-4))], "tolerance": 1e-6},
        "contradicting targets (|K| ≥ 5 and ≤ 4 kN/mm)": {
            "targets": [{"mode": "axial", "frequency_hz": 10, "amplitude": 1e-4, "magnitude": {"min": 5e6}},
                        {"mode": "axial", "frequency_hz": 10, "amplitude": 1e-4, "magnitude": {"max": 4e6}}]},
    }
    worst = 0.0
    for name, spec in cases.items():
        problem = problem_from_dict({"design": PAPER_B.to_dict(), **spec})
        found = []
        ms = median_ms(lambda problem=problem, found=found: found.append(solve(problem)), runs=3)
        worst = max(worst, ms)
        line(f"{name} ({'met' if found[-1].feasible else 'cannot'})", ms, 2000)
    print(f"slowest design search: {worst:.0f} ms, ratio to target {worst / 2000:.2f}")


if __name__ == "__main__":
    main()
